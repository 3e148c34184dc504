"""Does the grasp have one answer? Every start of the solver, to the end, with both Jacobians.

For each partner of a population (``softhand.envs.population.sample_partners``) and the four
+-2.5 SD corners of the paper's subjects, the grasp's least-squares problem
(`softhand.hands.grasp`) is solved from each of its starts (the relaxed prior, the partner
turned -+0.2 rad about the palm normal, shifted -+10 mm along its axis), both stages, to the end,
once with the analytic Jacobian (the shipped solver) and once with mujoco.minimize's finite
differences. The grasp is the cheapest start of the analytic solver (`_solve_starts`). Against it:

- the finite-difference solver's cheapest start (another solver, the same definition);
- every start whose cost is within ``--tie`` (relative) of the cheapest (the starts that found
  the answer); and the cheapest start that lands elsewhere (over 2 deg or 2 mm away): how much
  dearer it is, i.e. how clearly the answer is the answer;
- the first start that met the acceptance (cost < GOOD_COST_M2), the grasp before it was the
  cheapest.

Differences: the largest joint (deg, both hands), the partner's position (mm) and orientation
(deg).

With ``--handshakes``, each pair of hands whose two solvers disagree (over 2 deg or 2 mm) also
shakes hands twice (neutral controller, seed 0), once on each solver's grasp: what the second
answer changes where it counts, the region peaks and which regions pass 2 N.

Usage: ``python tools/grasp_agreement.py [--n 30] [--seed 0] [--tie 0.005] [--handshakes]
[--out reports/grasp-agreement]``.
"""

from __future__ import annotations

import argparse
import functools
import json
import sys

import numpy as np


def _diff(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    joints = float(np.degrees(np.abs(a[6:] - b[6:]).max()))
    pos = float(1e3 * np.linalg.norm(a[:3] - b[:3]))
    # rotation vectors about the same starting orientation: their difference's angle
    turn = float(np.degrees(np.linalg.norm(a[3:6] - b[3:6])))
    return joints, pos, turn


def _far(d: tuple[float, float, float]) -> bool:
    return d[0] > 2.0 or d[1] > 2.0 or d[2] > 2.0


def agreement(length_mm: float, width_mm: float, tie: float = 0.005) -> dict:
    from softhand.hands import HandConfig, PartnerConfig, SceneConfig
    from softhand.hands.grasp import GOOD_COST_M2, GRASP_SETTINGS, _Problem, _start_runs

    config = SceneConfig(partner=PartnerConfig(hand=HandConfig(hand_length_m=length_mm / 1e3,
                                                               hand_width_m=width_mm / 1e3)))
    problem = _Problem(config, GRASP_SETTINGS)
    runs = {fd: [(cost, x) for cost, x, _ in _start_runs(problem, GRASP_SETTINGS,
                                                          finite_differences=fd)]
            for fd in (False, True)}
    shipped = min(runs[False], key=lambda r: r[0])
    fd_best = min(runs[True], key=lambda r: r[0])
    both = runs[False] + runs[True]
    ties = [_diff(x, shipped[1]) for c, x in both if c <= shipped[0] * (1 + tie)]
    elsewhere = sorted((c, _diff(x, shipped[1])) for c, x in both
                       if _far(_diff(x, shipped[1])))
    first = next((r for r in runs[False] if r[0] < GOOD_COST_M2), shipped)
    return {"partner_mm": [length_mm, width_mm],
            "costs": [r[0] for r in runs[False]], "costs_fd": [r[0] for r in runs[True]],
            "cost": shipped[0], "ties": len(ties),
            "tie_spread": [max(t[k] for t in ties) for k in range(3)],
            "fd_vs_shipped": list(_diff(fd_best[1], shipped[1])),
            "fd_cost_pct": 100.0 * (fd_best[0] / shipped[0] - 1.0),
            "next_minimum_pct": (100.0 * (elsewhere[0][0] / shipped[0] - 1.0)
                                 if elsewhere else None),
            "first_vs_shipped": list(_diff(first[1], shipped[1]))}


def handshake_on_both_grasps(length_mm: float, width_mm: float) -> dict:
    """The default handshake (neutral, seed 0) of this partner on the shipped grasp and on the
    finite-difference solver's: per region the change of the peak (N, the second minus the
    shipped), the largest, and the regions whose over-2 N class changes."""
    import os
    import warnings

    import softhand.hands.grasp as grasp
    from softhand.envs.run import run_handshake
    from softhand.envs.skins import CalibratedRangeWarning

    shipped = grasp._solve_starts
    runs = []
    cache = os.environ.get("SOFTHAND_CACHE_DIR")
    os.environ["SOFTHAND_CACHE_DIR"] = "off"  # neither grasp may come from the other's cache
    try:
        for fd in (False, True):
            grasp.solve_grasp.cache_clear()
            grasp._solve_starts = functools.partial(shipped, finite_differences=fd)
            try:
                with warnings.catch_warnings():  # every partner's range warning: not measured here
                    warnings.simplefilter("ignore", CalibratedRangeWarning)
                    runs.append(run_handshake(seed=0, partner_size=(length_mm, width_mm)))
            finally:
                grasp._solve_starts = shipped
    finally:
        grasp.solve_grasp.cache_clear()
        if cache is None:
            os.environ.pop("SOFTHAND_CACHE_DIR", None)
        else:
            os.environ["SOFTHAND_CACHE_DIR"] = cache
    (a, b), (sa, sb) = (r.table() for r in runs), (set(r.over_2n) for r in runs)
    change = {k: b[k]["peak_N"] - v["peak_N"] for k, v in a.items()}
    largest = max(change, key=lambda k: abs(change[k]))
    return {"peak_change_N": change, "largest": [largest, change[largest], a[largest]["peak_N"]],
            "over_2N_changed": sorted(sa ^ sb)}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=30)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--tie", type=float, default=0.005)
    p.add_argument("--out", default=None)
    p.add_argument("--handshakes", action="store_true",
                   help="shake hands on both solvers' grasps where they disagree")
    a = p.parse_args(argv)
    from softhand.envs.partner import partner_size_range
    from softhand.envs.population import sample_partners

    sizes = [(q.hand_length_mm, q.hand_width_mm) for q in sample_partners(a.n, a.seed)]
    rng = partner_size_range()
    (l0, l1), (w0, w1) = rng["length"], rng["width"]
    corners = [(l0, w0), (l0, w1), (l1, w0), (l1, w1)]
    rows = []
    for i, (length, width) in enumerate(sizes + corners):
        r = agreement(length, width, a.tie)
        r["corner"] = i >= len(sizes)
        rows.append(r)
        print(f"{i + 1}/{len(sizes) + 4}: {length:.0f} x {width:.0f} mm, cost {r['cost']:.3e}, "
              f"{r['ties']} tied, spread {r['tie_spread'][0]:.1f} deg "
              f"{r['tie_spread'][1]:.1f} mm; fd {r['fd_vs_shipped'][0]:.1f} deg "
              f"{r['fd_vs_shipped'][1]:.1f} mm ({r['fd_cost_pct']:+.2f} %); next minimum "
              f"{r['next_minimum_pct']}", file=sys.stderr, flush=True)
    if a.handshakes:
        for r in rows:
            if _far(r["fd_vs_shipped"]):
                r["handshake"] = handshake_on_both_grasps(*r["partner_mm"])
                k, dv, base = r["handshake"]["largest"]
                print(f"handshake {r['partner_mm'][0]:.0f} x {r['partner_mm'][1]:.0f} mm: {k} "
                      f"{dv:+.2f} N (of {base:.2f}); over 2 N changed: "
                      f"{r['handshake']['over_2N_changed'] or 'none'}", file=sys.stderr,
                      flush=True)
    if a.out:
        with open(a.out + ".json", "w") as fh:
            json.dump(rows, fh, indent=1)
        lines = ["# Does the grasp have one answer?", "",
                 f"Generated by `python tools/grasp_agreement.py --n {a.n} --seed {a.seed} "
                 f"--tie {a.tie}{' --handshakes' if a.handshakes else ''} --out "
                 "reports/grasp-agreement`: each of the grasp solver's 5 "
                 f"starts solved to the end, with the analytic Jacobian (shipped) and with finite "
                 f"differences, for {a.n} sampled partners and the four +-2.5 SD corners. The "
                 "grasp is the analytic solver's cheapest start. Largest differences from it "
                 "(joint deg, partner position mm, partner orientation deg):", "",
                 "| partners | the other solver's cheapest | its cost against the grasp's % | "
                 f"starts within {100 * a.tie:g} % of the grasp's cost | the next minimum's "
                 "extra cost % (min, median) | the first accepted start (the grasp before) |",
                 "|---|---|---|---|---|---|"]
        fmt = lambda v: f"{v[0]:.1f}, {v[1]:.1f}, {v[2]:.1f}"  # noqa: E731
        for label, sel in ((f"{a.n} sampled", lambda r: not r["corner"]),
                           ("4 corners", lambda r: r["corner"])):
            sub = [r for r in rows if sel(r)]
            def worst(key: str, sub: list = sub) -> list[float]:
                return [max(r[key][k] for r in sub) for k in range(3)]

            nxt = [r["next_minimum_pct"] for r in sub if r["next_minimum_pct"] is not None]
            fdc = [r["fd_cost_pct"] for r in sub]
            lines.append(
                f"| {label} | {fmt(worst('fd_vs_shipped'))} | {min(fdc):+.2f} to "
                f"{max(fdc):+.2f} | {fmt(worst('tie_spread'))} | "
                + (f"{min(nxt):.2f}, {float(np.median(nxt)):.2f}" if nxt else "none")
                + f" | {fmt(worst('first_vs_shipped'))} |")
        over_fd = [r for r in rows if _far(r["fd_vs_shipped"])]
        over_tie = [r for r in rows if _far(r["tie_spread"])]
        moved = [r for r in rows if _far(r["first_vs_shipped"])]
        lines += ["", f"Pairs of hands where the other solver's cheapest start lands over 2 deg or "
                  f"2 mm from the grasp: {len(over_fd)} of {len(rows)}"
                  + (" (" + "; ".join(f"{r['partner_mm'][0]:.0f} x {r['partner_mm'][1]:.0f} mm: "
                                      f"{fmt(r['fd_vs_shipped'])}, cost {r['fd_cost_pct']:+.2f} %"
                                      for r in over_fd) + ")" if over_fd else "")
                  + f". Starts within {100 * a.tie:g} % of the grasp's cost that land over 2 deg "
                  f"or 2 mm away: {len(over_tie)} of {len(rows)}. Grasps that the cheapest start "
                  f"moved from the first accepted one: {len(moved)} of {len(rows)}.", ""]
        shaken = [r for r in rows if "handshake" in r]
        if shaken:
            lines += ["What the other solver's grasp changes in the handshake (neutral controller, "
                      "seed 0; each pair of hands above shaken on both grasps): the region whose "
                      "peak changes most, and the regions whose over-2 N class changes.", "",
                      "| partner mm | largest peak change N (region, its peak on the grasp) | "
                      "over 2 N changed |", "|---|---|---|"]
            for r in shaken:
                k, dv, base = r["handshake"]["largest"]
                lines.append(f"| {r['partner_mm'][0]:.0f} x {r['partner_mm'][1]:.0f} | "
                             f"{dv:+.2f} ({k}, {base:.2f}) | "
                             f"{', '.join(r['handshake']['over_2N_changed']) or 'none'} |")
            lines.append("")
        with open(a.out + ".md", "w") as fh:
            fh.write("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
