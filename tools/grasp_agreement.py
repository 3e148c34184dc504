"""Does the grasp have one answer? The grasp solved by two solvers and other hop seeds.

For each partner of a population (``softhand.envs.population.sample_partners``) and the four
+-2.5 SD corners of the paper's subjects, the grasp's least-squares problem
(`softhand.hands.grasp`) is solved as the shipped solver solves it (its five starts, the cheapest,
then hops to any cheaper minimum nearby, `_solve_starts`), and again:

- with mujoco.minimize's finite differences (step ``grasp.FD_EPS``) instead of the analytic
  Jacobian: another solver of the same definition;
- with the analytic Jacobian and other hop seeds (2 and 3; the grasp's are 0 and 1): other
  starts of the same search;
- the cheapest start alone (the grasp before the hops).

Differences from the shipped grasp: the largest joint (deg, both hands), the partner's position
(mm) and orientation (deg). The issue's acceptance: within 2 deg and 2 mm for every pair of hands.

With ``--handshakes``, the four corners shake hands (neutral controller, seed 0): the bone-on-bone
peak (N) and the deepest pair (mm).

Usage: ``python tools/grasp_agreement.py [--n 30] [--seed 0] [--jobs 2] [--handshakes]
[--out reports/grasp-agreement]``; ``--handshakes-only`` reruns only the corners' handshakes
into an existing report (its grasps kept).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np


def _diff(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    joints = float(np.degrees(np.abs(a[6:] - b[6:]).max()))
    pos = float(1e3 * np.linalg.norm(a[:3] - b[:3]))
    # rotation vectors about the same starting orientation: their difference's angle
    turn = float(np.degrees(np.linalg.norm(a[3:6] - b[3:6])))
    return joints, pos, turn


def _far(d: list[float] | tuple[float, ...]) -> bool:
    return d[0] > 2.0 or d[1] > 2.0 or d[2] > 2.0


def agreement(length_mm: float, width_mm: float, palm_align_weight: float | None = None) -> dict:
    import dataclasses

    from softhand.hands import HandConfig, PartnerConfig, SceneConfig
    from softhand.hands.grasp import GRASP_SETTINGS, _Problem, _solve_starts, _start_runs

    settings = GRASP_SETTINGS  # or another palms-parallel weight (tools/palm_alignment.py)
    if palm_align_weight is not None:
        settings = dataclasses.replace(settings, palm_align_weight=palm_align_weight)

    config = SceneConfig(partner=PartnerConfig(hand=HandConfig(hand_length_m=length_mm / 1e3,
                                                               hand_width_m=width_mm / 1e3)))
    problem = _Problem(config, settings)
    t0 = time.perf_counter()
    shipped = _solve_starts(problem, settings)
    seconds = time.perf_counter() - t0
    fd = _solve_starts(problem, settings, finite_differences=True)
    other_seed = _solve_starts(problem, settings, seeds=(2, 3))
    runs = _start_runs(problem, settings)
    starts = min(runs, key=lambda r: r[0])
    return {"partner_mm": [length_mm, width_mm], "cost": shipped[0], "seconds": seconds,
            "fd": list(_diff(fd[1], shipped[1])),
            "fd_cost_pct": 100.0 * (fd[0] / shipped[0] - 1.0),
            "other_seeds": list(_diff(other_seed[1], shipped[1])),
            "other_seeds_cost_pct": 100.0 * (other_seed[0] / shipped[0] - 1.0),
            "starts_only": list(_diff(starts[1], shipped[1])),
            "starts_only_cost_pct": 100.0 * (starts[0] / shipped[0] - 1.0)}


def corner_handshake(length_mm: float, width_mm: float) -> dict:
    """The neutral handshake (seed 0) of a corner partner: bone on bone and the deepest pair."""
    import warnings

    from softhand.envs.run import run_handshake
    from softhand.envs.skins import CalibratedRangeWarning

    with warnings.catch_warnings():  # the range warning of a corner: not measured here
        warnings.simplefilter("ignore", CalibratedRangeWarning)
        run = run_handshake(seed=0, partner_size=(length_mm, width_mm))
    over = run.overload()
    return {"bone_on_bone_peak_N": over["bone_on_bone_peak_N"],
            "deepest_pair_mm": over["deepest_pair_mm"], "deepest_pair": over["deepest_pair"]}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=30)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default=None)
    p.add_argument("--jobs", type=int, default=1, help="partners solved at once (joblib)")
    p.add_argument("--handshakes", action="store_true",
                   help="shake hands at the four corners (bone on bone, deepest pair)")
    p.add_argument("--palm-align-weight", type=float, default=None,
                   help="solve with GraspSettings.palm_align_weight set to this, not the "
                        "shipped one (reports/palm-alignment.md)")
    p.add_argument("--handshakes-only", action="store_true",
                   help="rerun only the corners' handshakes into OUT.json (the grasps kept) and "
                        "rewrite OUT.md: what a change of the scene's physics moves there")
    a = p.parse_args(argv)
    w = a.palm_align_weight
    if w is not None and not (np.isfinite(w) and 0.0 < w <= 10.0):
        p.error(f"--palm-align-weight {w!r}: allowed (0, 10]")
    if a.handshakes_only and not a.out:
        p.error("--handshakes-only rewrites an existing report: give its --out (e.g. "
                "reports/grasp-agreement)")
    if a.handshakes_only:
        with open(a.out + ".json") as fh:
            rows = json.load(fh)
        for r in rows:
            if r["corner"]:
                r["handshake"] = corner_handshake(*r["partner_mm"])
        # the grasps' command as the report gave it (its --n, --seed, --jobs), and this rerun's
        with open(a.out + ".md") as fh:
            head = fh.read().split("Generated by `", 1)[1].split("`", 1)[0]
        _write(a.out, rows, a.n, a.seed, a.jobs, True,
               command=f"{head}`; the corners' handshakes rerun by `python "
                       f"tools/grasp_agreement.py --handshakes-only --out {a.out}")
        return 0
    from softhand.envs.partner import partner_size_range
    from softhand.envs.population import sample_partners

    sizes = [(q.hand_length_mm, q.hand_width_mm) for q in sample_partners(a.n, a.seed)]
    rng = partner_size_range()
    (l0, l1), (w0, w1) = rng["length"], rng["width"]
    corners = [(l0, w0), (l0, w1), (l1, w0), (l1, w1)]
    from joblib import Parallel, delayed

    every = sizes + corners
    rows = []
    results = Parallel(n_jobs=a.jobs, return_as="generator")(
        delayed(agreement)(length, width, a.palm_align_weight) for length, width in every)
    for i, r in enumerate(results):
        r["corner"] = i >= len(sizes)
        rows.append(r)
        print(f"{i + 1}/{len(every)}: {r['partner_mm'][0]:.0f} x {r['partner_mm'][1]:.0f} mm, "
              f"cost {r['cost']:.3e} ({r['seconds']:.1f} s); fd {np.round(r['fd'], 1)} "
              f"({r['fd_cost_pct']:+.3f} %); hop seeds 2-3 {np.round(r['other_seeds'], 1)}; starts only "
              f"{np.round(r['starts_only'], 1)}", file=sys.stderr, flush=True)
    if a.handshakes:
        for r in rows:
            if r["corner"]:
                r["handshake"] = corner_handshake(*r["partner_mm"])
                print(f"corner {r['partner_mm'][0]:.0f} x {r['partner_mm'][1]:.0f} mm: "
                      f"{r['handshake']}", file=sys.stderr, flush=True)
    if not a.out:
        return 0
    _write(a.out, rows, a.n, a.seed, a.jobs, a.handshakes, a.palm_align_weight)
    return 0


def _write(out: str, rows: list[dict], n: int, seed: int, jobs: int, handshakes: bool,
           palm_align_weight: float | None = None, command: str | None = None) -> None:
    """``out``.json (the rows) and ``out``.md (the report); ``command``: what the header says
    generated it (default: these arguments' command line)."""
    from softhand.hands.grasp import FD_EPS, GOOD_COST_M2

    with open(out + ".json", "w") as fh:
        json.dump(rows, fh, indent=1)
    fmt = lambda v: f"{v[0]:.1f}, {v[1]:.1f}, {v[2]:.1f}"  # noqa: E731
    lines = ["# Does the grasp have one answer?", "",
             "Generated by `" + (command or (
                 f"python tools/grasp_agreement.py --n {n} --seed {seed} --jobs {jobs}"
                 f"{' --handshakes' if handshakes else ''}"
                 + (f" --palm-align-weight {palm_align_weight:g}" if palm_align_weight else "")
                 + f" --out {out}")) + "`. The grasp "
             "(`softhand.hands.grasp.solve_grasp`) is the cheapest of the solver's five starts, then "
             "hops from it to any cheaper minimum nearby (two searches, hop seeds 0 and 1, the "
             "cheaper kept). Solved again with finite differences "
             f"(mujoco.minimize, step {FD_EPS:g}) instead of the analytic Jacobian, and with other "
             f"hop seeds (2 and 3), for {n} sampled partners and the four +-2.5 SD corners. Largest "
             "differences from the grasp (joint deg, partner position mm, partner orientation deg); "
             "the acceptance is 2 deg and 2 mm:", "",
             "| partners | finite differences | their cost against the grasp's % | hop seeds 2 and 3 | "
             "the cheapest start alone (before the hops) | grasp cost (m^2) | s a grasp (min, "
             "median, max) |",
             "|---|---|---|---|---|---|---|"]
    for label, sel in ((f"{n} sampled", lambda r: not r["corner"]),
                       ("4 corners", lambda r: r["corner"])):
        sub = [r for r in rows if sel(r)]

        def worst(key: str, sub: list = sub) -> list[float]:
            return [max(r[key][k] for r in sub) for k in range(3)]

        fdc = [r["fd_cost_pct"] for r in sub]
        cost = [r["cost"] for r in sub]
        sec = [r["seconds"] for r in sub]
        lines.append(
            f"| {label} | {fmt(worst('fd'))} | {min(fdc):+.3f} to {max(fdc):+.3f} | "
            f"{fmt(worst('other_seeds'))} | {fmt(worst('starts_only'))} | {min(cost):.2e} to "
            f"{max(cost):.2e} | {min(sec):.1f}, {float(np.median(sec)):.1f}, {max(sec):.1f} |")
    over_fd = [r for r in rows if _far(r["fd"])]
    over_seed = [r for r in rows if _far(r["other_seeds"])]
    moved = [r for r in rows if _far(r["starts_only"])]
    accepted = [r for r in rows if r["cost"] < GOOD_COST_M2]

    def which(sub: list, key: str) -> str:
        return "" if not sub else " (" + "; ".join(
            f"{r['partner_mm'][0]:.0f} x {r['partner_mm'][1]:.0f} mm: {fmt(r[key])}"
            for r in sub) + ")"

    lines += ["", f"Pairs of hands over 2 deg or 2 mm from the grasp: finite differences "
              f"{len(over_fd)} of {len(rows)}{which(over_fd, 'fd')}; hop seeds 2 and 3 {len(over_seed)} "
              f"of {len(rows)}{which(over_seed, 'other_seeds')}. Grasps that the hops moved over 2 deg "
              f"or 2 mm from the cheapest start: {len(moved)} of {len(rows)}. Grasps whose cost "
              f"meets the acceptance (under {GOOD_COST_M2:g} m^2): {len(accepted)} of "
              f"{len(rows)}.", ""]
    shaken = [r for r in rows if "handshake" in r]
    if shaken:
        lines += ["The corners' neutral handshakes (seed 0):", "",
                  "| partner mm | bone on bone peak N | deepest pair mm (pair) |", "|---|---|---|"]
        for r in shaken:
            h = r["handshake"]
            lines.append(f"| {r['partner_mm'][0]:.0f} x {r['partner_mm'][1]:.0f} | "
                         f"{h['bone_on_bone_peak_N']:.2f} | {h['deepest_pair_mm']:.2f} "
                         f"({h['deepest_pair']}) |")
        lines.append("")
    with open(out + ".md", "w") as fh:
        fh.write("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
