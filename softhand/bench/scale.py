"""Benchmark of handshakes at scale: one env, the vector env, the physics ceiling, where a step's
time goes.

Measures, in one process on this machine (``softhand bench handshake --scale``, written to
``bench-handshake-scale.json`` and ``.md``), the default handshake (pocket2-sil, neutral
controller, 2 ms physics step, an env step every 10 ms) over whole episodes:

* **one env**: env steps per second of ``env.step`` alone (the controller's own time is not the
  env's), best of ``repeats`` episodes;
* **physics ceiling**: the same episode's ``mj_step`` calls alone, timed inside the episode: the
  env steps per second that the physics allows, with no Python around it;
* **Python per stage**: an instrumented episode (each stage of ``HandshakeEnv.step`` timed by a
  wrapper, about a microsecond each): the time per env step of the physics and of every piece of
  Python around it, and that episode's Python share (its timers count as Python);
* **Python share**: 1 - physics / env step, both timed within one episode where only ``mj_step``
  is wrapped (a timer pair per call, about 2 us an env step, counted as Python: an upper bound);
  the median of ``repeats`` such episodes. Physics and Python come from the same seconds, so
  the machine's drift, which reached 1.5x within minutes on the 2-core host, cancels (a plain
  and an instrumented episode measured apart gave shares from 2 to 42 % in one run);
* **vector env**: `HandshakeVectorEnv` with N worlds of the same
  scene (seeds 0..N-1), stepped with the controller's array entry for as many env steps as one
  episode, on the threads this process may use: env steps per second summed over the worlds and
  the aggregate real-time factor (simulated seconds of all worlds per wall second).

Every figure is wall-clock time of this machine, reported and never asserted by tests; the load
average at the start and the end is printed with the table (other work on the machine slows it).
"""

from __future__ import annotations

import contextlib
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import mujoco

from softhand.bench.common import machine_info, machine_line
from softhand.envs.controllers import make_controller
from softhand.envs.handshake import HandshakeEnv
from softhand.envs.vector import HandshakeVectorEnv
from softhand.io import atomic_write_json, atomic_write_text
from softhand.paths import REPORTS_DIR

__all__ = ["STAGES", "VECTOR_WORLDS", "physics_share", "run_scale_benchmark", "step_stages"]

#: Worlds of the vector env measured by default.
VECTOR_WORLDS = (2, 8, 32, 128)
#: The stages of an env step, in the report's order: (label, what it covers).
STAGES = (
    ("physics", "mj_step, the frame's 5 physics steps"),
    ("physics loop", "the mount path and the divergence checks around mj_step"),
    ("region forces", "the regions' contact sensors summed, skin and bone; the same call "
     "counts the saturated sensors and reads the partner's feel"),
    ("embedded sensors", "the transfer laws and the electronics of the 18 patch sensors"),
    ("saturated sensors", "contact sensors that matched more contacts than their slots (read "
     "with the region forces)"),
    ("range check", "the contacts beyond their law's calibrated range"),
    ("partner script", "the partner's grip regulator, from its feel"),
    ("phase and reward", "the handshake's phase and the reward's terms"),
    ("info", "the info dict"),
    ("observation", "the observation vector"),
    ("step body", "the action's checks and the rest of step()"),
)


@contextlib.contextmanager
def _timed(totals: dict[str, float]) -> Iterator[Callable[[Any, str, str], None]]:
    """``wrap(obj, attribute, stage)`` replaces a callable by one that adds its wall time to
    ``totals[stage]``; every wrapper is removed on exit."""
    undo: list[tuple[Any, str, Any, bool]] = []

    def wrap(obj: Any, name: str, stage: str) -> None:
        inner = getattr(obj, name)

        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return inner(*args, **kwargs)
            finally:
                totals[stage] += time.perf_counter() - t0

        undo.append((obj, name, inner, name in vars(obj)))
        setattr(obj, name, timed)

    try:
        yield wrap
    finally:
        for obj, name, inner, own in reversed(undo):
            if own:
                setattr(obj, name, inner)
            else:
                delattr(obj, name)


def _episode(env: HandshakeEnv, seed: int, step: Callable | None = None) -> tuple[int, float]:
    """One episode with the neutral controller: (env steps, wall seconds inside env.step)."""
    ctrl = make_controller("neutral")
    step = step or env.step
    obs, info = env.reset(seed=seed)
    steps, wall = 0, 0.0
    while True:
        action = ctrl(obs, info)
        t0 = time.perf_counter()
        obs, _, terminated, truncated, info = step(action)
        wall += time.perf_counter() - t0
        steps += 1
        if terminated or truncated:
            return steps, wall


def step_stages(env: HandshakeEnv, seed: int = 0) -> dict[str, Any]:
    """One instrumented episode of ``env``: per `STAGES` label its time per env step (us),
    the env step's time (us, wrappers included) and the Python share (1 - physics / env step)."""
    totals: dict[str, float] = defaultdict(float)
    physics, scenario = env.physics, env.scenario
    with _timed(totals) as wrap:
        wrap(mujoco, "mj_step", "physics")
        wrap(physics, "advance", "advance")
        wrap(physics, "region_forces", "region forces")
        wrap(env.sensors, "step", "embedded sensors")
        wrap(physics, "saturated_sensors", "saturated sensors")
        wrap(physics, "contacts_above", "range check")
        wrap(env, "_check_range", "range check")
        wrap(physics, "partner_feel", "partner script")
        wrap(scenario, "partner_targets", "partner script")
        wrap(scenario, "phase", "phase and reward")
        wrap(scenario, "reward_terms", "phase and reward")
        wrap(env, "_info", "info")
        wrap(env, "_obs", "observation")
        steps, wall = _episode(env, seed)
    totals["physics loop"] = totals.pop("advance") - totals["physics"]
    totals["step body"] = wall - sum(totals.values())
    per_step = {label: 1e6 * totals[label] / steps for label, _ in STAGES}
    env_step = 1e6 * wall / steps
    return {"steps": steps, "env_step_us": env_step, "stages_us": per_step,
            "python_share": 1.0 - per_step["physics"] / env_step}


def physics_share(env: HandshakeEnv, seed: int = 0) -> tuple[float, float]:
    """One episode of ``env`` with only ``mj_step`` timed: (its Python share, 1 - physics time /
    env step time; its env step in us, the timers included)."""
    totals: dict[str, float] = defaultdict(float)
    with _timed(totals) as wrap:
        wrap(mujoco, "mj_step", "physics")
        steps, wall = _episode(env, seed)
    return 1.0 - totals["physics"] / wall, 1e6 * wall / steps


def _vector(worlds: int, steps: int, nthread: int | None) -> dict[str, Any]:
    vec = HandshakeVectorEnv(num_envs=worlds, nthread=nthread)
    try:
        ctrl = make_controller("neutral")
        obs, info = vec.reset(seed=0)
        wall = 0.0
        for _ in range(steps):
            actions = ctrl.actions(obs, info, vec.region_names)
            t0 = time.perf_counter()
            obs, _, _, _, info = vec.step(actions)
            wall += time.perf_counter() - t0
        dt = vec.frame_skip * float(vec.envs[0].model.opt.timestep)
    finally:
        vec.close()
    return {"worlds": worlds, "steps": steps, "wall_s": wall,
            "env_steps_per_s": worlds * steps / wall,
            "realtime_factor": worlds * steps * dt / wall}


def run_scale_benchmark(out_dir: str | Path = REPORTS_DIR, *,
                        worlds: tuple[int, ...] | None = None, repeats: int = 5,
                        nthread: int | None = None,
                        progress: Callable[[str], None] | None = None) -> str:
    """Run the benchmark (module docstring), write ``bench-handshake-scale.json`` and ``.md`` to
    ``out_dir``, return the Markdown. ``worlds``: the vector env's (default VECTOR_WORLDS);
    ``nthread``: its threads (default: the CPUs this process may use); ``progress`` gets a line
    before each part."""
    say = progress or (lambda line: None)
    out = Path(out_dir)
    data: dict[str, Any] = {"machine": machine_info()}
    say("one env, its physics ceiling and its stages")
    env = HandshakeEnv()
    dt = env.frame_skip * float(env.model.opt.timestep)
    # per repeat: a plain episode (the speed), one with mj_step alone timed (the Python share:
    # physics and env step from the same seconds) and an instrumented one (the stages)
    runs, instrumented, shares = [], [], []
    for _ in range(repeats):
        runs.append(_episode(env, seed=0))
        shares.append(physics_share(env)[0])
        instrumented.append(step_stages(env))
    steps, wall = min(runs, key=lambda r: r[1])
    stages = min(instrumented, key=lambda s: s["env_step_us"])
    shares.sort()
    physics_us = min(s["stages_us"]["physics"] for s in instrumented)
    env.close()
    data["single"] = {"steps": steps, "wall_s": wall, "env_steps_per_s": steps / wall,
                      "realtime_factor": steps * dt / wall,
                      "python_share": shares[len(shares) // 2], "python_shares": shares}
    data["ceiling"] = {"env_steps_per_s": 1e6 / physics_us,
                       "physics_steps_per_s": 1e6 * env.frame_skip / physics_us}
    data["stages"] = stages
    data["vector"] = []
    for n in VECTOR_WORLDS if worlds is None else worlds:
        say(f"vector env, {n} worlds")
        data["vector"].append(_vector(n, steps, nthread))
    data["nthread"] = nthread or data["machine"]["available_cpus"]
    data["repeats"] = repeats
    data["load_1min_end"] = machine_info()["load_1min"]
    atomic_write_json(out / "bench-handshake-scale.json", data)
    md = markdown(data)
    atomic_write_text(out / "bench-handshake-scale.md", md)
    return md


def markdown(d: dict[str, Any]) -> str:
    """The report of `run_scale_benchmark`'s data."""
    single, ceiling, stages = d["single"], d["ceiling"], d["stages"]
    dt_s = single["realtime_factor"] / single["env_steps_per_s"]
    lines = [
        "# Handshakes at scale (`softhand bench handshake --scale`)", "",
        f"{machine_line(d['machine'])} Load average at the end {d['load_1min_end']}.", "",
        f"The default handshake (pocket2-sil, neutral controller, a 2 ms physics step, an env step "
        f"every {1e3 * dt_s:.0f} ms), {single['steps']} env steps an episode. Env steps per "
        "second of `step()` alone (the controller's time is not the env's); the vector env's "
        f"worlds share one scene and step on {d['nthread']} thread(s) with `mujoco.batch`:", "",
        "| what | env steps/s | real-time factor |", "|---|---|---|",
        f"| one env (best of its episodes) | {single['env_steps_per_s']:.0f} | "
        f"{single['realtime_factor']:.1f}x |",
    ]
    for v in d["vector"]:
        lines.append(f"| vector env, {v['worlds']} worlds | {v['env_steps_per_s']:.0f} | "
                     f"{v['realtime_factor']:.1f}x |")
    lines += [f"| physics ceiling (the episode's `mj_step` alone) | "
              f"{ceiling['env_steps_per_s']:.0f} | "
              f"{ceiling['env_steps_per_s'] * dt_s:.1f}x |", "",
              f"The Python share of one env step (1 - its physics time / the env step's, both "
              f"timed within one episode where only `mj_step` is timed, its timers counted as "
              f"Python; the median of {d.get('repeats', 3)} episodes: "
              f"{', '.join(f'{100 * x:.0f}' for x in single['python_shares'])} "
              f"%) is **{100 * single['python_share']:.0f} %**. Where the "
              f"step's time goes (an instrumented episode of the same calls: "
              f"{stages['env_step_us']:.0f} us a step, its timers included, about a microsecond "
              f"a stage; Python share {100 * stages['python_share']:.0f} %):", "",
              "| stage | us per env step | share | what |", "|---|---|---|---|"]
    for label, what in STAGES:
        us = stages["stages_us"][label]
        lines.append(f"| {label} | {us:.0f} | {100 * us / stages['env_step_us']:.0f} % | "
                     f"{what} |")
    return "\n".join(lines) + "\n"
