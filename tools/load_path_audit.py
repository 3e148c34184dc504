"""The handshake's load path, measured on one episode (issue 35's audit, rerunnable).

Runs one neutral-controller handshake (or the human protocol with ``--hand human``) and reports,
over the phases where the hands hold each other (grip, shake and hold):

- palm on palm: the share of the normal force between the hands that the sensored hand's palmar
  palm (the pieces Palm1 and Palm2 before the palm was one surface; now the palmar face, z < 0 in
  the palm's frame, of its one skin; not the thenar, not the back) exchanges with the partner's
  palm piece (not its thumb metacarpal), and the gap between them (median and largest over the
  shake);
- double count: where one partner geom touches two sensored skin geoms at contact points under
  ``SEAM_MM`` apart (a seam between two skin pieces), the smaller of the two forces is an
  indentation resisted twice: its share of the force between the hands;
- the sensored hand's wrist travel over the shake (0 for a hand fixed to the world);
- the bone-on-bone peak and the deepest skin-pair penetration.

- the hold: the relative fall of the force between the hands from 50 ms once the shake's last
  swing has died out (HOLD_SETTLE_S into the hold) to its last 50 ms.

Usage: ``python tools/load_path_audit.py [--seed 0] [--hand prosthetic|human]
[--representation soft-contact+relaxation] [--json OUT]``; ``--table`` runs seeds 0-4 and the
human hand and prints one row each; ``--report reports/load-path [--before CHECKOUT]`` writes
the report (both checkouts' tables and mj_step costs, the hold, the overload cases, the corners,
who loads each region). The report's "before" is 1c0ace0, the arms with the palm in four skins
(the commit before the palm became one surface), made with ``git worktree add /tmp/old 1c0ace0
&& ln -s ../calibration /tmp/old/softhand/calibration`` (the symlink makes
``softhand.calibration`` that checkout's own when it runs through PYTHONPATH beside an editable
install of this one).
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import mujoco
import numpy as np

#: the seam distance of softhand.envs.run.SEAM_M. The audit measures with its own loop, not with
#: softhand's ContactAreas (double_N, deepest), because it also runs on the checkout before the
#: arms (--before), which has neither; the two agree on this checkout (0.8 % at seed 0 both ways)
SEAM_MM = 2.0
#: softhand.envs.run.HOLD_SETTLE_S (one period of the 4 Hz shake), repeated so that the audit
#: reads the hold alike on a checkout that lacks it (--before)
HOLD_SETTLE_S = 0.25
HELD = ("grip", "shake", "hold")
#: set in the child processes that run another checkout (--before): its root
CHECKOUT_ENV = "SOFTHAND_AUDIT_CHECKOUT"


def _own_calibration() -> None:
    """In a child run of another checkout (``CHECKOUT_ENV``, through PYTHONPATH), import
    ``softhand.calibration`` from that checkout's calibration/: an editable install maps the
    package to its own checkout's folder, whose files an older checkout's code may not read
    (a contact class it does not know)."""
    import importlib.util

    root = os.environ.get(CHECKOUT_ENV)
    if not root:
        return
    import softhand

    folder = os.path.join(root, "calibration")
    spec = importlib.util.spec_from_file_location(
        "softhand.calibration", os.path.join(folder, "__init__.py"),
        submodule_search_locations=[folder])
    module = importlib.util.module_from_spec(spec)
    sys.modules["softhand.calibration"] = module
    spec.loader.exec_module(module)
    softhand.calibration = module


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
    whole_palm = name.index("pro_skin_Palm") if "pro_skin_Palm" in name else None
    palm_body = m.body("pro_palm").id
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
            if whole_palm is not None:  # the palm's one surface: its palmar face only (z < 0)
                R, p0 = d.xmat[palm_body].reshape(3, 3), d.xpos[palm_body]
                for i in np.flatnonzero(palm):
                    if whole_palm in g[i] and (R.T @ (pos[i] - p0))[2] > 0.0:
                        palm[i] = False
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
    if len(h) > 10:  # 50 ms once the shake's last swing has died out, and the hold's last 50 ms
        settled = h[0, 0] + HOLD_SETTLE_S
        first = h[(h[:, 0] >= settled) & (h[:, 0] < settled + 0.05), 1].mean()
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


def mid_shake(seed: int = 0, at_s: float = 1.9, options: dict | None = None):
    """(model, data) of the default scene (neutral controller) stepped to ``at_s`` (mid-shake),
    with MuJoCo ``options`` (fields of ``model.opt``) set first."""
    import gymnasium as gym

    import softhand.envs  # noqa: F401
    from softhand.envs.controllers import make_controller

    env = gym.make("softhand/Handshake-v0").unwrapped
    m, d = env.model, env.data
    for key, value in (options or {}).items():
        setattr(m.opt, key, value)
    policy = make_controller("neutral")
    obs, info = env.reset(seed=seed)
    while d.time < at_s:
        obs, *_, info = env.step(policy(obs, info))
    return m, d


def step_cost_us(seed: int = 0, at_s: float = 1.9, steps: int = 2000, repeats: int = 5,
                 options: dict | None = None) -> float:
    """Median over ``repeats`` of the mean wall time (us) of one mj_step of the default scene
    from its state at ``at_s`` (`mid_shake`, with ``options``), a copy of the data stepped
    ``steps`` times."""
    import time

    m, d = mid_shake(seed, at_s, options)
    times = []
    for _ in range(repeats):
        copy = mujoco.MjData(m)
        mujoco.mj_copyData(copy, m, d)
        t0 = time.perf_counter()
        for _ in range(steps):
            mujoco.mj_step(m, copy)
        times.append((time.perf_counter() - t0) / steps * 1e6)
    return float(np.median(times))


def hold_cases() -> list[dict]:
    """The hold of the default handshake (seed 0) on two skins, memoryless and on relaxation
    pads (HandshakeRun.hold_relaxation)."""
    from softhand.envs.run import run_handshake

    out = []
    for rep in ("soft-contact", "soft-contact+relaxation"):
        for design in ("pocket2-sil", "pocket2-pu"):
            run = run_handshake(design=design, representation=rep, seed=0)
            out.append({"design": design, "representation": rep, **run.hold_relaxation()})
    return out


def overload_cases() -> list[dict]:
    """Where the hard cases overload (HandshakeRun.overload): the motors slammed closed at
    full speed while the hands hold each other, and the partner squeezing 5x."""
    from softhand.envs import HandshakeEnv
    from softhand.envs.run import run_handshake, run_policy

    def slam(obs, info):
        return np.ones(6) if info.get("phase") in HELD else np.zeros(6)

    cases = [("motors slammed closed", run_policy(HandshakeEnv(), slam, seed=0)),
             ("partner squeezes 5x", run_handshake(squeeze=5.0, seed=0))]
    return [{"case": name, "max_region_N": float(run.region_force_N.max()), **run.overload()}
            for name, run in cases]


def who_loads(hand: str = "prosthetic", seed: int = 0) -> dict:
    """For each of the paper's regions: the partner geom that pressed its skin geom most (N s,
    over the whole episode, all of the skin geom's contacts, its sensor zone or not), its share
    of the region's skin force, and the phase and time of the region's peak (its reading). On
    the palm's one surface a contact belongs to the nearest zone (`ContactAreas.region_at`)."""
    import gymnasium as gym

    import softhand.envs  # noqa: F401
    from softhand.envs.controllers import make_controller
    from softhand.envs.run import ContactAreas

    env = gym.make("softhand/Handshake-v0", hand=hand).unwrapped
    m, d = env.model, env.data
    # each contact's region: its skin's, or on the palm's one surface the nearest zone's
    areas = ContactAreas(m, [m.geom(g).id for g in env.region_geoms], None,
                         [m.site(f"pro_touch_{r}").id for r in env.region_names])
    region_of = {int(g): r for g, r in zip((m.geom(g).id for g in env.region_geoms),
                                          env.region_names, strict=True)}
    by = {r: {} for r in env.region_names}
    peak = dict.fromkeys(env.region_names, (0.0, 0.0, ""))
    policy = make_controller("neutral")
    obs, info = env.reset(seed=seed)
    dt = env.frame_skip * float(m.opt.timestep)
    while True:
        obs, _, term, trunc, info = env.step(policy(obs, info))
        for i in range(d.ncon):
            c = d.contact[i]
            if c.efc_address < 0:
                continue
            g1, g2 = int(c.geom[0]), int(c.geom[1])
            skin, other = (g1, g2) if g1 in region_of else (g2, g1)
            if skin not in region_of or not m.geom(other).name.startswith("hum_"):
                continue
            name = m.geom(other).name.removeprefix("hum_tissue_")
            acc = by[env.region_names[areas.region_at(d, skin, c.pos)]]
            acc[name] = acc.get(name, 0.0) + float(d.efc_force[c.efc_address]) * dt
        for r, f in info["region_forces_N"].items():
            if f > peak[r][0]:
                peak[r] = (f, float(info["time_s"]), info["phase"])
        if term or trunc:
            break
    out = {}
    for r in env.region_names:
        total = sum(by[r].values())
        top = max(by[r].items(), key=lambda kv: kv[1]) if by[r] else ("-", 0.0)
        out[r] = {"peak_N": peak[r][0], "peak_time_s": peak[r][1], "peak_phase": peak[r][2],
                  "top_partner_geom": top[0],
                  "top_share_pct": 100.0 * top[1] / total if total > 0 else 0.0}
    return out


def corner_cases() -> list[dict]:
    """Bone on bone and the deepest pair at the four +-2.5 SD corners of the paper's subjects,
    both sensored hands (neutral, seed 0)."""
    from softhand.envs.partner import partner_size_range
    from softhand.envs.run import run_handshake

    r = partner_size_range()
    (l0, l1), (w0, w1) = r["length"], r["width"]
    out = []
    for hand in ("prosthetic", "human"):
        for size in ((l0, w0), (l0, w1), (l1, w0), (l1, w1)):
            run = run_handshake(partner_size=size, hand=hand, seed=0)
            out.append({"hand": hand, "partner_mm": list(size), **run.overload()})
    return out


def write_report(out: str, before: str | None) -> None:
    """``out``.md and ``out``.json: the table for this checkout and (``before``: the path of
    another checkout, run through PYTHONPATH) for that one, the hold, the overload cases and
    the cost of an mj_step of both."""
    import subprocess
    import tempfile

    from softhand.bench.common import machine_info

    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    checkouts = {"after": here, **({"before": before} if before else {})}

    def cost(path: str) -> float:  # one process per measurement, so that neither warms the other
        env = {**os.environ, "PYTHONPATH": path, CHECKOUT_ENV: path}
        done = subprocess.run([sys.executable, __file__, "--step-cost"], env=env, check=True,
                              capture_output=True, text=True)
        return float(done.stdout)

    # the checkouts' mj_step costs interleaved, 3 rounds, the least of each (the host drifts)
    costs = {k: [] for k in checkouts}
    for _ in range(3):
        for key, path in checkouts.items():
            costs[key].append(cost(path))
    data = {"machine": machine_info(),
            "after": {"rows": [audit(s) for s in range(5)] + [audit(0, "human")],
                      "step_us": min(costs["after"]), "step_us_runs": costs["after"]}}
    if before:
        env = {**os.environ, "PYTHONPATH": before, CHECKOUT_ENV: before}
        with tempfile.TemporaryDirectory() as tmp:
            rows = os.path.join(tmp, "rows.json")
            subprocess.run([sys.executable, __file__, "--table", "--json", rows], env=env,
                           check=True, capture_output=True)
            with open(rows) as fh:
                data["before"] = {"rows": json.load(fh), "step_us": min(costs["before"]),
                                  "step_us_runs": costs["before"], "checkout": before}
    data["hold"] = hold_cases()
    data["overload"] = overload_cases()
    data["corners"] = corner_cases()
    data["who_loads"] = {hand: who_loads(hand) for hand in ("prosthetic", "human")}
    _write(out, data)


def update_corners(out: str) -> None:
    """Run the corners again into an existing ``out``.json and rewrite ``out``.md: what a change
    of the grasp of other hand sizes changes, when the default hands' grasp (every other table)
    is bit-identical. The report says when its corners were updated."""
    with open(out + ".json") as fh:
        data = json.load(fh)
    data["corners"] = corner_cases()
    data["corners_updated"] = _git_head()
    _write(out, data)


def _git_head() -> str:
    import subprocess

    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    done = subprocess.run(["git", "-C", here, "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True)
    return done.stdout.strip() or "unknown"


def _write(out: str, data: dict) -> None:
    """``out``.json and ``out``.md from the audit's data."""
    from softhand.bench.common import machine_line

    before = "before" in data
    with open(out + ".json", "w") as fh:
        json.dump(data, fh, indent=1)
    lines = ["# The handshake's load path", "",
             "Generated by `python tools/load_path_audit.py --report reports/load-path"
             + (" --before CHECKOUT" if before else "") + "` (neutral controller, pocket2-sil, "
             "2 ms; palm on palm: the sensored hand's palmar palm (its palmar face) against the partner's "
             "palm piece, thenars and thumbs left out; counted twice: the smaller of two "
             "contacts of one partner geom on two skin geoms under 2 mm apart; over grip, shake "
             "and hold; the gap and the wrist's travel over the shake).", "",
             machine_line(data["machine"]), ""]
    for key, title in (("before", "Before (both hands on arms, the palm in four skins)"),
                       ("after", "Now (each palm one surface, its regions zones)")):
        if key not in data:
            continue
        runs = ", ".join(f"{v:.0f}" for v in data[key]["step_us_runs"])
        lines += [f"## {title}", "", f"mj_step at mid-shake: {data[key]['step_us']:.0f} us, the "
                  f"least of 3 processes interleaved with the other checkout's ({runs} us; each "
                  "the median of 5 x 2000 steps).", "", _TABLE_HEAD, _TABLE_RULE]
        lines += [_row(r) for r in data[key]["rows"]]
        lines.append("")
    lines += ["## The hold", "", "The force between the hands over 50 ms once the shake's last "
              f"swing has died out ({HOLD_SETTLE_S:g} s into the 0.52 s hold, "
              "softhand.envs.run.HOLD_SETTLE_S) and over the hold's last 50 ms; on relaxation "
              "pads, the fall the QLV laws give for the pads' compression histories "
              "(force-weighted) and the share of the hold's force that went through a pad.", "",
              "| skin | representation | start N | end N | fall % | QLV of the pads, fall % "
              "| through pads % |", "|---|---|---|---|---|---|---|"]
    for h in data["hold"]:
        q = "-" if h["qlv_decay_pct"] is None else f"{h['qlv_decay_pct']:.2f}"
        lines.append(f"| {h['design']} | {h['representation']} | {h['force_start_N']:.2f} | "
                     f"{h['force_end_N']:.2f} | {h['decay_pct']:.2f} | {q} | "
                     f"{h['pad_share_pct']:.0f} |")
    lines += ["", "## Overload", "", "| case | largest region N | deepest pair mm (pair, t) | "
              "bone on bone peak N (t) | first overload |", "|---|---|---|---|---|"]
    for o in data["overload"]:
        first = ("-" if not o["first_overload"] else f"t = {o['first_overload_time_s']:.2f} s: "
                 + ", ".join(f"{k} {v:.1f} N" for k, v in o["first_overload"].items()))
        lines.append(f"| {o['case']} | {o['max_region_N']:.1f} | {o['deepest_pair_mm']:.1f} "
                     f"({o['deepest_pair']}, {o['deepest_pair_time_s']:.2f} s) | "
                     f"{o['bone_on_bone_peak_N']:.1f} ({o['bone_on_bone_peak_time_s']:.2f} s) | "
                     f"{first} |")
    updated = (f" (rerun at {data['corners_updated']} by `python tools/load_path_audit.py "
               "--update-corners reports/load-path`: the grasp of other hand sizes changed, the "
               "default hands' did not)") if data.get("corners_updated") else ""
    lines += ["", "## The corners", "", "The four +-2.5 SD corners of the paper's subjects "
              f"(partner length x width), neutral, seed 0{updated}:", "",
              "| sensored hand | partner mm | bone on bone peak N | deepest pair mm |",
              "|---|---|---|---|"]
    for c in data["corners"]:
        lines.append(f"| {c['hand']} | {c['partner_mm'][0]:.0f} x {c['partner_mm'][1]:.0f} | "
                     f"{c['bone_on_bone_peak_N']:.2f} | {c['deepest_pair_mm']:.1f} |")
    from softhand.paper import paper

    fig4 = set(paper()["handshake"]["over_2N"])
    lines += ["", "## Who loads each region", "", "Seed 0, neutral: for each region, its peak "
              "reading (N, when, in which phase) and the partner geom that pressed its skin "
              "most over the episode, with its share of that skin's force (all of the skin "
              "geom's contacts). Regions in the paper's Fig. 4 set marked.", "",
              "| region | Fig. 4 > 2 N | prosthetic: peak N (t s, phase) | by | human hand: peak N "
              "(t s, phase) | by |", "|---|---|---|---|---|---|"]
    pro, hum = data["who_loads"]["prosthetic"], data["who_loads"]["human"]
    for r in pro:
        cells = []
        for w in (pro[r], hum[r]):
            if w["peak_N"] > 0.05:
                cells += [f"{w['peak_N']:.2f} ({w['peak_time_s']:.2f}, {w['peak_phase']})",
                          f"{w['top_partner_geom']} ({w['top_share_pct']:.0f} %)"]
            else:
                cells += ["-", "-"]
        lines.append(f"| {r} | {'yes' if r in fig4 else ''} | " + " | ".join(cells) + " |")
    with open(out + ".md", "w") as fh:
        fh.write("\n".join(lines) + "\n")


_TABLE_HEAD = ("| hand | seed | palm on palm % | palm gap mm (median, max) | counted twice % | "
               "wrist travel mm (x, y, z) | bone on bone N | deepest pair mm | hold fall % |")
_TABLE_RULE = "|---|---|---|---|---|---|---|---|---|"


def _row(r: dict) -> str:
    g = r["palm_gap_mm"]
    decay = r.get("hold_force_decay")
    decay = "-" if decay is None else f"{100 * decay:.1f}"
    return (f"| {r['hand']} | {r['seed']} | {100 * r['palm_on_palm_share']:.1f} | "
            f"{g['median']:.1f}, {g['max']:.1f} | {100 * r['double_count_share']:.1f} | "
            f"{', '.join(f'{v:.1f}' for v in r['wrist_travel_mm'])} | "
            f"{r['bone_on_bone_peak_N']:.2f} | {r['deepest_pair_mm']:.1f} | {decay} |")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--hand", choices=("prosthetic", "human"), default="prosthetic")
    p.add_argument("--representation", default=None)
    p.add_argument("--json", default=None)
    p.add_argument("--table", action="store_true")
    p.add_argument("--step-cost", action="store_true")
    p.add_argument("--report", default=None, help="write REPORT.md and REPORT.json")
    p.add_argument("--before", default=None, help="another checkout, for the report")
    p.add_argument("--update-corners", default=None, metavar="REPORT",
                   help="rerun only the corners into REPORT.json and rewrite REPORT.md")
    a = p.parse_args(argv)
    _own_calibration()
    if a.update_corners:
        update_corners(a.update_corners)
        return 0
    if a.step_cost:
        print(step_cost_us())
        return 0
    if a.report:
        write_report(a.report, a.before)
        return 0
    if a.table:
        rows = [audit(s) for s in range(5)] + [audit(0, "human")]
        print(_TABLE_HEAD)
        print(_TABLE_RULE)
        for r in rows:
            print(_row(r))
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
