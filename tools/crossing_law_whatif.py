"""What if a border pair's law followed its finger's crossing through the episode? A what-if.

    python tools/crossing_law_whatif.py [--seeds 0 1 2] [--out reports/crossing-law-whatif]

The scene chooses each border pair's law once, from its finger's crossing at the grasp
(`softhand.envs.skins.border_pairs`), and the finger then turns on the border through the shake
(reports/contact-geometry.md). This runs the default handshake (neutral, pocket2-sil) as shipped
("at the grasp") and with every border pair's ``solref``/``solimp`` set before each env step to
the border law of the crossing its contact has then (`border_class`, the same values the scene
writes: `softhand.skin.rig.pair_law_values`), switching only once the crossing is ``--hysteresis``
deg past the midpoint between two laws' angles ("following"). For each: the number of switches,
the share of the border pairs' force (read before each env step) within
`CROSSING_TOLERANCE_DEG` of the law the pair then carries, the force between the hands and the
four palm regions' peaks (a run that diverges raises, as every handshake does). Not a feature of
the scene: the MJCF would no longer describe the simulated model alone, and the batched env's
worlds share one model; what it would buy is what this measures. Writes ``OUT.md`` and ``OUT.json``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import mujoco
import numpy as np

from softhand.bench.common import machine_info, machine_line
from softhand.envs import run as run_module
from softhand.envs.handshake import HandshakeEnv
from softhand.envs.skins import _skin_first, skin_of_pair
from softhand.io import atomic_write_json, atomic_write_text
from softhand.skin.contact_classes import BORDER_CROSSINGS_DEG, border_class, class_crossing
from softhand.skin.files import load_calibration
from softhand.skin.local_geometry import (
    CROSSING_TOLERANCE_DEG,
    LocalGeometry,
    crossing_deg,
    surface_point,
)
from softhand.skin.rig import pair_law_values

REGIONS = ("Palm1", "Palm2", "Back1", "Back2")


def episode(seed: int, follow: bool, hysteresis: float) -> dict:
    env = HandshakeEnv()
    m = env.model
    d0 = mujoco.MjData(m)
    mujoco.mj_forward(m, d0)
    border = {}  # pid -> [skin geom, other geom, {class: (solref, solimp)}, current class]
    for pid in range(m.npair):
        name = m.pair(pid).name
        c = env.pair_laws[name]
        if c.law.startswith("border/finger"):
            cal = load_calibration(skin_of_pair(name, env.skins)[1])
            g1, g2 = _skin_first(m, pid)
            vals = {border_class(a): pair_law_values(m, pid, cal.pair_laws[border_class(a)]
                                                     .pair.params, issues=[], data=d0)
                    for a in BORDER_CROSSINGS_DEG}
            border[(min(g1, g2), max(g1, g2))] = [pid, g1, g2, vals, c.law]
    local, force = LocalGeometry(m), np.zeros(6)
    fits, total, switches = 0.0, 0.0, 0
    step = env.step

    def stepped(action):
        nonlocal fits, total, switches
        d = env.data
        for i in range(d.ncon):
            con = d.contact[i]
            row = border.get((min(con.geom1, con.geom2), max(con.geom1, con.geom2)))
            if row is None:
                continue
            pid, g1, g2, vals, law = row
            shape = local.shape(d, g1, surface_point(con, g1))
            x = (crossing_deg(shape, local.shape(d, g2, surface_point(con, g2)))
                 if shape.kind == "border" else None)
            mujoco.mj_contactForce(m, d, i, force)
            total += force[0]
            fits += force[0] * (x is not None
                                and abs(x - class_crossing(law)) <= CROSSING_TOLERANCE_DEG)
            if not follow or x is None:
                continue
            want = border_class(x)
            mid = 0.5 * (class_crossing(law) + class_crossing(want))
            if want != law and abs(x - mid) >= hysteresis:
                m.pair_solref[pid], m.pair_solimp[pid] = vals[want]
                row[4] = want
                switches += 1
        return step(action)

    env.step = stepped
    r = run_module.run_handshake(env=env, seed=seed)
    table = r.table()
    return {"seed": seed, "follow": follow, "switches": switches,
            "within_law_pct": 100.0 * fits / max(total, 1e-12),
            "total_Ns": r.force_accounting()["total_Ns"],
            "peak_N": {k: table[k]["peak_N"] for k in REGIONS}}


def markdown(d: dict) -> str:
    lines = ["# A border law that follows the crossing: what it would buy", "",
             f"`python tools/crossing_law_whatif.py --seeds {' '.join(map(str, d['seeds']))} "
             f"--hysteresis {d['hysteresis']:g}`: the default handshake (neutral, pocket2-sil) "
             "with each border pair's law chosen once at the grasp (as shipped) and following "
             "the crossing of its contact before each env step (a what-if; the tool's "
             "docstring). Within its law: the share of the border pairs' force within "
             f"{d['tolerance']:g} deg of the angle of the law the pair then carries.", "",
             machine_line(d["machine"]), "",
             "| seed | border law | switches | border force within its law % | force between "
             "the hands N s | " + " | ".join(f"{r} peak N" for r in REGIONS) + " |",
             "|---|---|---|---|---|" + "---|" * len(REGIONS)]
    for r in d["runs"]:
        lines.append(f"| {r['seed']} | {'following the crossing' if r['follow'] else 'at the grasp'}"
                     f" | {r['switches']} | {r['within_law_pct']:.1f} | {r['total_Ns']:.1f} | "
                     + " | ".join(f"{r['peak_N'][k]:.2f}" for k in REGIONS) + " |")
    return "\n".join(lines) + "\n\n" + summary(d) + "\n"


def summary(d: dict) -> str:
    """What the table shows, over its seeds: the border force within its law at the grasp and
    following the crossing, the switches, and how far the force between the hands and each
    region's peak move."""
    grasp = {r["seed"]: r for r in d["runs"] if not r["follow"]}
    follow = {r["seed"]: r for r in d["runs"] if r["follow"]}
    seeds = [s for s in grasp if s in follow]

    def span(values, fmt=".0f") -> str:
        lo, hi = min(values), max(values)
        return f"{lo:{fmt}}" if f"{lo:{fmt}}" == f"{hi:{fmt}}" else f"{lo:{fmt}}-{hi:{fmt}}"

    total = [100.0 * abs(follow[s]["total_Ns"] / grasp[s]["total_Ns"] - 1.0) for s in seeds]
    moves = [(100.0 * (follow[s]["peak_N"][k] / grasp[s]["peak_N"][k] - 1.0), k, s)
             for s in seeds for k in REGIONS if grasp[s]["peak_N"][k] > 0.0]
    worst = max(moves, key=lambda m: abs(m[0]))
    return (f"Over seeds {', '.join(map(str, seeds))}: the border pairs' force within its law "
            f"{span([grasp[s]['within_law_pct'] for s in seeds])} % at the grasp, "
            f"{span([follow[s]['within_law_pct'] for s in seeds])} % following the crossing "
            f"({span([follow[s]['switches'] for s in seeds])} switches an episode); the force "
            f"between the hands moves by {span(total, '.1f')} %, the regions' peaks by up to "
            f"{worst[0]:+.0f} % ({worst[1]} at seed {worst[2]}).")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--hysteresis", type=float, default=3.0)
    ap.add_argument("--out", default="reports/crossing-law-whatif")
    a = ap.parse_args()
    if any(s < 0 for s in a.seeds):
        raise SystemExit(f"--seeds {' '.join(map(str, a.seeds))}: each must be 0 or more")
    if not 0.0 <= a.hysteresis <= 15.0:
        raise SystemExit(f"--hysteresis {a.hysteresis}: allowed 0-15 deg")
    out = Path(a.out)
    if not out.parent.is_dir():
        raise SystemExit(f"--out {a.out}: folder {out.parent} does not exist")
    data = {"machine": machine_info(), "seeds": a.seeds, "hysteresis": a.hysteresis,
            "tolerance": CROSSING_TOLERANCE_DEG,
            "runs": [episode(s, f, a.hysteresis) for s in a.seeds for f in (False, True)]}
    atomic_write_json(out.with_suffix(".json"), json.loads(json.dumps(data, default=float)))
    atomic_write_text(out.with_suffix(".md"), markdown(data))
    print(markdown(data))


if __name__ == "__main__":
    main()
