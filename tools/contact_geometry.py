"""The laws against the shapes the contacts meet (issue 36, items 1 and 5): a report.

    python tools/contact_geometry.py [--out reports/contact-geometry]

Each contact between the hands is classified by the shapes of its two geoms at the contact
point (`softhand.skin.local_geometry`: round with its radius and axis, a mesh's flat face or
rounded border, the crossing angle) and set against the law its pair carries. Writes
``OUT.md`` and ``OUT.json``:

1. the share of the force between the hands whose skin law, tissue law and both were made for
   the contact's geometry: neutral seeds 0-4, force and open-loop at seed 0, and the human
   protocol at seeds 0 and 7 (the laws are those each run's pairs carry);
2. the class table of the default run (neutral, seed 0): what presses the skin and where, its
   share, the law, whether it was made for it; the crossing angles summed over their bins;
3. the radii of the rounded palm borders the fingers press (force-weighted percentiles), the
   shape issue 36's border law needs; per pair that carries a border law, the crossing at the
   grasp its law was chosen from against the crossings it meets over the run;
4. over the paper's population (30 sampled partners, seed 0; `softhand.envs.population`), the
   prosthetic hand and the human protocol: the share whose skin law fits and the share on a
   rounded palm border, median and 10th-90th percentiles over the partners;
5. how the answer moves with the classification's two settings (the window, the flat face's
   largest normal spread), default run;
6. the classification's cost: one episode with and without it (wall, this machine).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from softhand.bench.common import machine_info, machine_line
from softhand.envs import run as run_module
from softhand.envs.run import run_handshake
from softhand.io import atomic_write_json, atomic_write_text
from softhand.skin import local_geometry as lg

RUNS = ([("neutral", "prosthetic", s) for s in range(5)]
        + [("force", "prosthetic", 0), ("open-loop", "prosthetic", 0)]
        + [("neutral", "human", 0), ("neutral", "human", 7)])


def _geometry(controller: str, hand: str, seed: int) -> dict:
    acc = run_handshake(controller=controller, hand=hand, seed=seed).force_accounting()
    return acc["by_geometry"]


def _border_radii() -> dict:
    """Force-weighted percentiles of the rounded palm borders' radii that skin contacts meet
    (the skin's palm border, pressed by the partner), default run."""
    seen: list[tuple[float, float]] = []
    original = run_module.ContactAreas._classify

    def classify(self, data, c, law, f):
        original(self, data, c, law, f)
        skin = c.geom1 if self.hand[c.geom1] == 0 else c.geom2
        s = self._local.shape(data, skin, lg.surface_point(c, skin))  # as _classify reads it
        if s.kind == "border":
            seen.append((s.radius_mm, f))

    run_module.ContactAreas._classify = classify
    try:
        run_handshake(seed=0)
    finally:
        run_module.ContactAreas._classify = original
    r, w = np.array(seen).T
    return _weighted_percentiles(r, w)


def _weighted_percentiles(values: np.ndarray, weights: np.ndarray) -> dict[str, float]:
    """The 10th, 50th and 90th percentiles of ``values`` weighted by ``weights`` (keys "10",
    "50", "90")."""
    order = np.argsort(values)
    cdf = np.cumsum(weights[order]) / weights.sum()
    return {str(q): float(values[order][min(np.searchsorted(cdf, q / 100), values.size - 1)])
            for q in (10, 50, 90)}


def _crossing_drift() -> list[dict]:
    """Default run: per pair that carries a border law, the crossing its class was chosen from
    (at the grasp, `softhand.envs.skins.border_pairs`) against the crossings its contacts meet
    over the episode (force-weighted median and 10th-90th percentiles), and the share of its
    force within `CROSSING_TOLERANCE_DEG` of its law's angle."""
    import mujoco

    from softhand.envs.handshake import HandshakeEnv
    from softhand.envs.skins import _skin_first
    from softhand.hands.grasp import set_grasp_state, solve_grasp
    from softhand.skin.contact_classes import class_crossing

    env = HandshakeEnv()
    m = env.model
    seen: dict[tuple[int, int], list[tuple[float, float]]] = {}
    original = run_module.ContactAreas._classify

    def classify(self, data, c, law, f):
        original(self, data, c, law, f)
        skin, other = (c.geom1, c.geom2) if self.hand[c.geom1] == 0 else (c.geom2, c.geom1)
        a = self._local.shape(data, skin, lg.surface_point(c, skin))
        x = lg.crossing_deg(a, self._local.shape(data, other, lg.surface_point(c, other)))
        if a.kind == "border" and x is not None:
            seen.setdefault((skin, other), []).append((x, f))

    run_module.ContactAreas._classify = classify
    try:
        run_handshake(env=env, seed=0)
    finally:
        run_module.ContactAreas._classify = original
    d = mujoco.MjData(m)
    set_grasp_state(m, d, solve_grasp(env.config))
    local = lg.LocalGeometry(m)
    at_grasp = {}  # the crossings the pairs' laws were chosen from
    for pid in range(m.npair):
        on = lg.border_contact(m, d, *_skin_first(m, pid), local=local)
        if on is not None:
            at_grasp[m.pair(pid).name] = lg.crossing_deg(*on)
    rows = []
    for pid in range(m.npair):
        name = m.pair(pid).name
        law = env.pair_laws[name].law
        g1, g2 = _skin_first(m, pid)
        if not law.startswith("border/finger") or (g1, g2) not in seen:
            continue
        x, f = np.array(seen[(g1, g2)]).T
        near = np.abs(x - class_crossing(law)) <= lg.CROSSING_TOLERANCE_DEG
        rows.append({"pair": name, "law": law, "grasp_crossing_deg": at_grasp.get(name),
                     "run_crossing_deg": _weighted_percentiles(x, f),
                     "force_Ns": float(f.sum() * m.opt.timestep * env.frame_skip),
                     "fits_pct": float(100 * f[near].sum() / f.sum())})
    return sorted(rows, key=lambda r: -r["force_Ns"])


def _sensitivity() -> list[dict]:
    rows = []
    for window, face in ((4.0, 15.0), (6.0, 15.0), (8.0, 15.0), (6.0, 10.0), (6.0, 20.0)):
        old = lg.WINDOW_MM, lg.FACE_DEG
        lg.WINDOW_MM, lg.FACE_DEG = window, face
        try:
            g = _geometry("neutral", "prosthetic", 0)
        finally:
            lg.WINDOW_MM, lg.FACE_DEG = old
        border = lg.palm_border_share_pct(g)
        rows.append({"window_mm": window, "face_deg": face,
                     "skin_own_class_share_pct": g["skin_own_class_share_pct"],
                     "palm_border_share_pct": border})
    return rows


def _population(hand: str) -> dict:
    from softhand.envs.population import run_population, sample_partners

    results, errors = run_population(sample_partners(30, seed=0), {"hand": hand})
    skin = [r["force_accounting"]["by_geometry"]["skin_own_class_share_pct"] for r in results]
    border = [lg.palm_border_share_pct(r["force_accounting"]["by_geometry"]) for r in results]

    def spread(v):
        return {"median": float(np.median(v)), "p10": float(np.percentile(v, 10)),
                "p90": float(np.percentile(v, 90))}
    return {"hand": hand, "partners": len(results), "failed": len(errors),
            "skin_own_class_share_pct": spread(skin), "palm_border_share_pct": spread(border)}


def _cost() -> dict:
    """Time inside the classification over one default episode (perf_counter around each
    contact's), with the hulls' cells read afresh and kept from an earlier episode."""
    spent = [0.0]
    original = run_module.ContactAreas._classify

    def timed(self, *args):
        t = time.perf_counter()
        original(self, *args)
        spent[0] += time.perf_counter() - t

    run_module.ContactAreas._classify = timed
    out = {}
    try:
        for label in ("cold", "warm"):
            if label == "cold":
                lg._HULLS.clear()
            spent[0] = 0.0
            t = time.perf_counter()
            run_handshake(seed=0)
            out[label] = {"episode_s": time.perf_counter() - t, "classify_s": spent[0]}
    finally:
        run_module.ContactAreas._classify = original
    return out


def _merged(classes: list[dict]) -> list[dict]:
    """The class table with the crossing bins summed (contact without its angle, law)."""
    out: dict[tuple, dict] = {}
    for c in classes:
        what = c["contact"].rsplit(" ", 2)[0] if c["contact"].endswith(" deg") else c["contact"]
        row = out.setdefault((what, c["law"]), {"contact": what, "law": c["law"],
                                                "share_pct": 0.0, "fits_pct": 0.0})
        row["share_pct"] += c["share_pct"]
        row["fits_pct"] += c["share_pct"] if c["skin_fits"] else 0.0
    return sorted(out.values(), key=lambda r: -r["share_pct"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="reports/contact-geometry")
    args = ap.parse_args()
    data: dict = {"machine": machine_info(), "window_mm": lg.WINDOW_MM, "face_deg": lg.FACE_DEG,
                  "crossing_tolerance_deg": lg.CROSSING_TOLERANCE_DEG, "runs": []}
    for controller, hand, seed in RUNS:
        print(f"{controller} {hand} seed {seed}", flush=True)
        g = _geometry(controller, hand, seed)
        data["runs"].append({"controller": controller, "hand": hand, "seed": seed, **g})
    data["border_radius_mm"] = _border_radii()
    data["crossing_drift"] = _crossing_drift()
    print("populations", flush=True)
    data["populations"] = [_population(h) for h in ("prosthetic", "human")]
    data["sensitivity"] = _sensitivity()
    data["cost"] = _cost()
    out = Path(args.out)
    atomic_write_json(out.with_suffix(".json"), json.loads(json.dumps(data, default=float)))
    atomic_write_text(out.with_suffix(".md"), markdown(data))
    print(markdown(data))


def markdown(d: dict) -> str:
    lines = ["# The laws against the shapes the contacts meet", "",
             "`python tools/contact_geometry.py --out reports/contact-geometry`: each contact "
             "between the hands classified by the shapes of its two geoms at the contact point "
             "(`softhand.skin.local_geometry`: round with its radius and axis; on a mesh, a flat "
             f"face where the hull's normals within {d['window_mm']:g} mm agree within "
             f"{d['face_deg']:g} deg, a rounded border otherwise) and set against the law its "
             "pair carries. A finger law (the FE's cylinder at its class's crossing angle: 90 "
             "deg across a phalanx; 90, 60 or 30 deg across a rounded palm border) counts "
             f"within {d['crossing_tolerance_deg']:g} deg of its angle.",
             "", machine_line(d["machine"]), "",
             "Share of the force between the hands (all recorded frames) whose law was made for "
             "the contact's geometry:", "",
             "| run | skin law | tissue law | both | force between the hands, N s |",
             "|---|---|---|---|---|"]
    for r in d["runs"]:
        lines.append(f"| {r['controller']}, {r['hand']} hand, seed {r['seed']} | "
                     f"{r['skin_own_class_share_pct']:.1f} % | "
                     f"{r['tissue_own_class_share_pct']:.1f} % | {r['own_class_share_pct']:.1f} % "
                     f"| {r['total_Ns']:.1f} |")
    default = d["runs"][0]
    lines += ["", "The default run (neutral, prosthetic hand, seed 0), crossing angles summed:", "",
              "| what presses the skin, where | share | law it carries | of which its law fits |",
              "|---|---|---|---|"]
    for r in _merged(default["classes"])[:10]:
        lines.append(f"| {r['contact']} | {r['share_pct']:.1f} % | {r['law']} | "
                     f"{r['fits_pct']:.1f} % |")
    rad = d["border_radius_mm"]
    lines += ["", "The rounded palm borders the partner presses in the default run, their radius "
              f"(force-weighted): 10th percentile {rad['10']:.1f} mm, median {rad['50']:.1f} mm, "
              f"90th {rad['90']:.1f} mm (from the normals' spread over the window).", ""]
    if d.get("crossing_drift"):
        lines += ["A pair's border law is chosen once, from its finger's crossing at the grasp "
                  "(`softhand.envs.skins.border_pairs`: the nearest angle of "
                  "`BORDER_CROSSINGS_DEG`); the crossings its contacts then meet over the "
                  "default run (force-weighted) and the share of its force within "
                  f"{d['crossing_tolerance_deg']:g} deg of its law's angle:", "",
                  "| pair | law | crossing at the grasp, deg | over the run: median (p10-p90) "
                  "| force N s | within its law's angle |", "|---|---|---|---|---|---|"]
        for r in d["crossing_drift"]:
            x, at = r["run_crossing_deg"], r["grasp_crossing_deg"]
            lines.append(f"| {r['pair']} | {r['law']} | "
                         f"{'-' if at is None else format(at, '.0f')} | {x['50']:.0f} "
                         f"({x['10']:.0f}-{x['90']:.0f}) | {r['force_Ns']:.2f} | "
                         f"{r['fits_pct']:.0f} % |")
        lines.append("")
    if d.get("populations"):
        lines += ["Over the paper's population (30 sampled partners, seed 0), median and "
                  "10th-90th percentiles over the partners:", "",
                  "| sensored hand | partners | skin law made for the geometry | a finger or "
                  "border on a rounded palm border |", "|---|---|---|---|"]
        for p in d["populations"]:
            a, b = p["skin_own_class_share_pct"], p["palm_border_share_pct"]
            lines.append(f"| {p['hand']} | {p['partners']} | {a['median']:.1f} % "
                         f"({a['p10']:.1f}-{a['p90']:.1f}) | {b['median']:.1f} % "
                         f"({b['p10']:.1f}-{b['p90']:.1f}) |")
        lines.append("")
    lines += ["The classification's settings, default run:", "",
              "| window mm | flat face: normals within, deg | skin law fits | fingers on a palm "
              "border |", "|---|---|---|---|"]
    for r in d["sensitivity"]:
        lines.append(f"| {r['window_mm']:g} | {r['face_deg']:g} | "
                     f"{r['skin_own_class_share_pct']:.1f} % | {r['palm_border_share_pct']:.1f} % |")
    c = d["cost"]
    lines += ["", f"Cost: the classification took {c['cold']['classify_s']:.2f} s of a default "
              f"episode's {c['cold']['episode_s']:.2f} s with its hulls' cells read afresh, and "
              f"{c['warm']['classify_s']:.2f} s of {c['warm']['episode_s']:.2f} s once an "
              "earlier episode has read them (each mesh shape is read once per 1 mm cell of the "
              "geom's frame and kept per hull for the process)."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
