"""The handshake's load path, measured on one episode (issue 35's audit, rerunnable).

Runs one neutral-controller handshake (or the human protocol with ``--hand human``) and reports,
over the phases where the hands hold each other (grip, shake and hold):

- palm on palm: the share of the normal force between the hands that the sensored hand's palmar
  palm pieces (Palm1, Palm2; not the thenar, not the back) exchange with the partner's palm piece
  (not its thumb metacarpal), and the gap between those pieces (median and largest over the shake);
- double count: where one partner geom touches two sensored skin geoms at contact points under
  ``SEAM_MM`` apart (a seam between two skin pieces), the smaller of the two forces is an
  indentation resisted twice: its share of the force between the hands;
- the sensored hand's wrist travel over the shake (0 for a hand fixed to the world);
- the bone-on-bone peak and the deepest skin-pair penetration.

- the hold: the relative fall of the force between the hands from its first to its last 50 ms.

Usage: ``python tools/load_path_audit.py [--seed 0] [--hand prosthetic|human]
[--representation soft-contact+relaxation] [--json OUT]``; ``--table`` runs seeds 0-4 and the
human hand and prints one row each.
"""

from __future__ import annotations

import argparse
import json
import sys

import mujoco
import numpy as np

SEAM_MM = 2.0
HELD = ("grip", "shake", "hold")


def audit(seed: int = 0, hand: str = "prosthetic", timestep_s: float = 0.002,
          representation: str | None = None) -> dict:
    import gymnasium as gym

    import softhand.envs  # noqa: F401
    from softhand.envs.controllers import make_controller

    kw = {"representation": representation} if representation else {}
    env = gym.make("softhand/Handshake-v0", hand=hand, timestep_s=timestep_s, **kw).unwrapped
    m, d = env.model, env.data
    name = [m.geom(g).name for g in range(m.ngeom)]
    pro_palm = np.array([n in ("pro_skin_Palm1", "pro_skin_Palm2", "pro_skin_Palm") for n in name])
    hum_palm = np.array([n == "hum_tissue_palm" for n in name])
    pro_skin = np.array([n.startswith("pro_skin_") for n in name])
    hum = np.array([n.startswith("hum_") for n in name])
    bone = np.array(["bone" in n for n in name])
    pro_palm_ids = np.flatnonzero(pro_palm)
    wrist = m.body("pro_wrist").id
    policy = make_controller("neutral")
    obs, info = env.reset(seed=seed)
    sums = {"total": 0.0, "palm": 0.0, "double": 0.0, "bone": 0.0}
    gaps, wrist_pos, bone_peak, deepest = [], [], 0.0, 0.0
    dist_from = np.zeros(6)
    hold = []  # (t, force between the hands) in the hold
    while True:
        obs, _, term, trunc, info = env.step(policy(obs, info))
        phase = info["phase"]
        con = d.contact[:d.ncon]
        live = con.efc_address >= 0
        g = con.geom[live]
        f = d.efc_force[con.efc_address[live]] if live.any() else np.zeros(0)
        pos, dist = con.pos[live], con.dist[live]
        between = (pro_skin[g[:, 0]] | pro_skin[g[:, 1]] | bone[g[:, 0]]) & (hum[g[:, 0]]
                                                                             | hum[g[:, 1]])
        both_bone = bone[g[:, 0]] & bone[g[:, 1]] & between
        bone_peak = max(bone_peak, float(f[both_bone].sum()) if both_bone.any() else 0.0)
        skin_pair = between & ~both_bone
        if skin_pair.any():
            deepest = max(deepest, float(-dist[skin_pair].min()))
        if phase == "hold":
            hold.append((float(d.time), float(f[between].sum())))
        if phase in HELD:
            sums["total"] += float(f[between].sum())
            palm = (pro_palm[g[:, 0]] & hum_palm[g[:, 1]]) | (pro_palm[g[:, 1]] & hum_palm[g[:, 0]])
            sums["palm"] += float(f[palm].sum())
            sums["bone"] += float(f[both_bone].sum())
            idx = np.flatnonzero(skin_pair)
            for a in range(len(idx)):
                for b in range(a + 1, len(idx)):
                    i, j = idx[a], idx[b]
                    pi = g[i][pro_skin[g[i]]]
                    pj = g[j][pro_skin[g[j]]]
                    hi, hj = g[i][hum[g[i]]], g[j][hum[g[j]]]
                    if (len(pi) and len(pj) and len(hi) and len(hj) and pi[0] != pj[0]
                            and hi[0] == hj[0]
                            and np.linalg.norm(pos[i] - pos[j]) < SEAM_MM * 1e-3):
                        sums["double"] += float(min(f[i], f[j]))
            if phase == "shake":
                hid = m.geom("hum_tissue_palm").id
                gaps.append(min(mujoco.mj_geomDistance(m, d, int(p), hid, 0.05, dist_from)
                                for p in pro_palm_ids))
                wrist_pos.append(d.xpos[wrist].copy())
        if term or trunc:
            break
    total = max(sums["total"], 1e-12)
    h = np.array(hold) if hold else np.zeros((0, 2))
    decay = None
    if len(h) > 10:  # first and last 50 ms of the hold
        first = h[h[:, 0] < h[0, 0] + 0.05, 1].mean()
        last = h[h[:, 0] > h[-1, 0] - 0.05, 1].mean()
        decay = float(1.0 - last / first) if first > 0 else None
    travel = np.ptp(np.array(wrist_pos), axis=0) if wrist_pos else np.zeros(3)
    return {
        "hand": hand, "seed": seed, "timestep_s": timestep_s,
        "palm_on_palm_share": sums["palm"] / total,
        "double_count_share": sums["double"] / total,
        "bone_share": sums["bone"] / total,
        "palm_gap_mm": {"median": 1e3 * float(np.median(gaps)) if gaps else None,
                        "max": 1e3 * float(np.max(gaps)) if gaps else None,
                        "min": 1e3 * float(np.min(gaps)) if gaps else None},
        "wrist_travel_mm": (1e3 * travel).round(2).tolist(),
        "bone_on_bone_peak_N": bone_peak,
        "deepest_pair_mm": 1e3 * deepest,
        "force_N_s": sums["total"] * env.frame_skip * float(m.opt.timestep),
        "hold_s": float(h[-1, 0] - h[0, 0]) if len(h) else 0.0,
        "hold_force_decay": decay,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--hand", choices=("prosthetic", "human"), default="prosthetic")
    p.add_argument("--representation", default=None)
    p.add_argument("--json", default=None)
    p.add_argument("--table", action="store_true")
    a = p.parse_args(argv)
    if a.table:
        rows = [audit(s) for s in range(5)] + [audit(0, "human")]
        print("| hand | seed | palm on palm % | palm gap mm (median, max) | counted twice % | "
              "wrist travel mm (x, y, z) | bone on bone N | deepest pair mm | hold decay % |")
        print("|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            g = r["palm_gap_mm"]
            decay = "-" if r["hold_force_decay"] is None else f"{100 * r['hold_force_decay']:.1f}"
            print(f"| {r['hand']} | {r['seed']} | {100 * r['palm_on_palm_share']:.1f} | "
                  f"{g['median']:.1f}, {g['max']:.1f} | {100 * r['double_count_share']:.1f} | "
                  f"{', '.join(f'{v:.1f}' for v in r['wrist_travel_mm'])} | "
                  f"{r['bone_on_bone_peak_N']:.2f} | {r['deepest_pair_mm']:.1f} | {decay} |")
        if a.json:
            with open(a.json, "w") as fh:
                json.dump(rows, fh, indent=1)
        return 0
    out = audit(a.seed, a.hand, representation=a.representation)
    print(json.dumps(out, indent=1))
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
