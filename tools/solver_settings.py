"""Are the scene's cone and solver settings the cheapest that keep the forces? (issue 35, item 7)

Runs the default handshake (pocket2-sil, 2 ms) with MuJoCo's option changed one setting at a
time (the friction cone, the solver, its iterations and tolerances, the Jacobian's storage) for
the neutral, force and open-loop controllers at seeds 0 and 1, and reports for each:

- the cost of one ``mj_step`` at mid-shake (t = 1.9 s, neutral, seed 0): the median of 5 runs of
  2000 steps from a copy of the state, in one process (`step_cost_us`);
- the largest change of a region's peak and mean force against the shipped settings, over the
  regions whose peak passes 1 N (relative, %), and where it is.

The shipped settings stay unless a setting is cheaper with every change within 2 %.

Usage: ``python tools/solver_settings.py [--out reports/solver-settings]`` (about a minute).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import mujoco
import numpy as np

CONTROLLERS = ("neutral", "force", "open-loop")
SEEDS = (0, 1)
TOLERANCE_PCT = 2.0


def variants() -> dict[str, dict]:
    cone, solver, jac = mujoco.mjtCone, mujoco.mjtSolver, mujoco.mjtJacobian
    return {
        "shipped": {},
        "pyramidal cone": {"cone": cone.mjCONE_PYRAMIDAL},
        "CG solver": {"solver": solver.mjSOL_CG},
        "PGS solver": {"solver": solver.mjSOL_PGS},
        "iterations 10": {"iterations": 10},
        "tolerance 1e-5": {"tolerance": 1e-5},
        "line search iterations 10": {"ls_iterations": 10},
        "dense Jacobian": {"jacobian": jac.mjJAC_DENSE},
        "sparse Jacobian": {"jacobian": jac.mjJAC_SPARSE},
    }


def _env(setting: dict):
    from softhand.envs.handshake import HandshakeEnv

    env = HandshakeEnv()
    for key, value in setting.items():
        setattr(env.model.opt, key, value)
    return env


def _table(setting: dict, controller: str, seed: int) -> dict:
    from softhand.envs.run import run_handshake

    return run_handshake(controller=controller, seed=seed, env=_env(setting)).table()


def step_cost_us(setting: dict, at_s: float = 1.9, steps: int = 2000,
                 repeats: int = 5) -> float:
    from softhand.envs.controllers import make_controller

    env = _env(setting)
    m, d = env.model, env.data
    policy = make_controller("neutral")
    obs, info = env.reset(seed=0)
    while d.time < at_s:
        obs, *_, info = env.step(policy(obs, info))
    times = []
    for _ in range(repeats):
        copy = mujoco.MjData(m)
        mujoco.mj_copyData(copy, m, d)
        t0 = time.perf_counter()
        for _ in range(steps):
            mujoco.mj_step(m, copy)
        times.append((time.perf_counter() - t0) / steps * 1e6)
    return float(np.median(times))


#: MuJoCo's timers reported per step (the parts of an mj_step)
PARTS = {"collision": "mjTIMER_POS_COLLISION", "of it narrowphase": "mjTIMER_COL_NARROW",
         "constraint (assembly and solver)": "mjTIMER_CONSTRAINT", "step": "mjTIMER_STEP"}


def step_parts_us(steps: int = 2000, at_s: float = 1.9) -> dict[str, float]:
    """The shipped scene's mj_step at mid-shake split by MuJoCo's own timers (us per step)."""
    from softhand.envs.controllers import make_controller

    env = _env({})
    m, d = env.model, env.data
    policy = make_controller("neutral")
    obs, info = env.reset(seed=0)
    while d.time < at_s:
        obs, *_, info = env.step(policy(obs, info))
    copy = mujoco.MjData(m)
    mujoco.mj_copyData(copy, m, d)
    before = {k: copy.timer[getattr(mujoco.mjtTimer, t)].duration for k, t in PARTS.items()}
    for _ in range(steps):
        mujoco.mj_step(m, copy)
    return {k: 1e6 * (copy.timer[getattr(mujoco.mjtTimer, t)].duration - before[k]) / steps
            for k, t in PARTS.items()}


def measure() -> dict:
    import warnings

    warnings.simplefilter("ignore")  # the default run's range warning, once per run
    cases = [(c, s) for c in CONTROLLERS for s in SEEDS]
    base = {case: _table({}, *case) for case in cases}
    out = {}
    for name, setting in variants().items():
        print(f"{name} ...", file=sys.stderr, flush=True)
        worst = {"peak_pct": 0.0, "mean_pct": 0.0, "where": None}
        for case in cases:
            table = base[case] if not setting else _table(setting, *case)
            for region, ref in base[case].items():
                if ref["peak_N"] <= 1.0:
                    continue
                for key, what in (("peak_pct", "peak_N"), ("mean_pct", "mean_N")):
                    change = 100.0 * abs(table[region][what] / ref[what] - 1.0)
                    if change > worst[key]:
                        worst[key] = change
                        if change >= max(worst["peak_pct"], worst["mean_pct"]):
                            worst["where"] = f"{case[0]}, seed {case[1]}, {region}"
        out[name] = {"setting": {k: int(v) if not isinstance(v, float) else v
                                 for k, v in setting.items()},
                     "step_us": step_cost_us(setting), **worst}
    out["shipped"]["parts_us"] = step_parts_us()
    m = _env({}).model
    mesh = sum(mujoco.mjtGeom.mjGEOM_MESH in (m.geom_type[m.pair_geom1[p]],
                                              m.geom_type[m.pair_geom2[p]]) for p in range(m.npair))
    out["shipped"]["pairs"] = {"capsule": int(m.npair - mesh), "mesh": int(mesh)}
    return out


def write(out: str, data: dict) -> None:
    from softhand.bench.common import machine_info, machine_line

    shipped = data["shipped"]["step_us"]
    lines = ["# The scene's cone and solver settings", "",
             "Generated by `python tools/solver_settings.py --out reports/solver-settings`: the "
             "default handshake (pocket2-sil, 2 ms) with one MuJoCo option changed at a time; the "
             "cost of an mj_step at mid-shake (neutral, seed 0; median of 5 x 2000 steps, one "
             "process) and the largest change of a region's peak and mean force against the "
             f"shipped settings (elliptic cone, Newton, 100 iterations, tolerance 1e-8), over the "
             f"regions whose peak passes 1 N, controllers {', '.join(CONTROLLERS)}, seeds "
             f"{', '.join(map(str, SEEDS))}.", "", machine_line(machine_info()), "",
             "| setting | mj_step us | against shipped | largest peak change % | largest mean "
             "change % | where |", "|---|---|---|---|---|---|"]
    for name, r in data.items():
        lines.append(f"| {name} | {r['step_us']:.1f} | {r['step_us'] / shipped:.2f}x | "
                     f"{r['peak_pct']:.2f} | {r['mean_pct']:.2f} | {r['where'] or '-'} |")
    keep = [n for n, r in data.items() if n != "shipped" and r["step_us"] < 0.95 * shipped
            and max(r["peak_pct"], r["mean_pct"]) <= TOLERANCE_PCT]
    lines += ["", ("Cheaper by 5 % or more with every change within 2 %: " + ", ".join(keep))
              if keep else "No setting is 5 % cheaper with every change within 2 %: the shipped "
              "settings stay."]
    parts = data["shipped"]["parts_us"]
    lines += ["", "Where the shipped step's time goes (MuJoCo's timers, 2000 steps from mid-shake; "
              "the timers' own overhead included): " + "; ".join(
                  f"{k} {v:.1f} us ({100 * v / parts['step']:.0f} %)" for k, v in parts.items()
                  if k != "step") + f", of {parts['step']:.1f} us a step. The solver converges "
              "within its first iterations, so its settings cannot halve a step: a cheaper step "
              "needs fewer or cheaper collision pairs (of the scene's explicit pairs, "
              f"{data['shipped']['pairs']['capsule']} are capsule on capsule, "
              f"{data['shipped']['pairs']['mesh']} have a mesh, whose narrowphase is the "
              "convex-hull routine)."]
    with open(f"{out}.md", "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(f"{out}.json", "w") as f:
        json.dump(data, f, indent=1)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=None, help="write OUT.md and OUT.json")
    args = p.parse_args(argv)
    data = measure()
    for name, r in data.items():
        print(f"{name:28s} {r['step_us']:6.1f} us  peak {r['peak_pct']:5.2f} %  "
              f"mean {r['mean_pct']:5.2f} %  {r['where'] or '-'}")
    if args.out:
        write(args.out, data)
    return 0


if __name__ == "__main__":
    sys.exit(main())
