"""Run one handshake with a controller and collect what a user looks at: forces, motion, contacts."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field

import mujoco
import numpy as np

from softhand.envs.controllers import make_controller
from softhand.envs.handshake import HandshakeEnv
from softhand.paper import paper

__all__ = ["HandshakeRun", "run_handshake"]

OVER_N = 2.0  # the paper's Fig. 4 threshold


@dataclass
class HandshakeRun:
    """One handshake: per physics step (frame) the state, region forces and contacts."""

    region_names: tuple[str, ...]
    skins: dict[str, str]
    time_s: np.ndarray
    qpos: np.ndarray
    mocap_pos: np.ndarray
    mocap_quat: np.ndarray
    region_force_N: np.ndarray
    contacts: list[np.ndarray]
    phase: list[str]
    wall_s: float
    steps: int
    model: mujoco.MjModel = field(repr=False)

    def table(self) -> dict[str, dict[str, float]]:
        f = self.region_force_N
        return {r: {"peak_N": float(f[:, i].max()), "mean_N": float(f[:, i].mean())}
                for i, r in enumerate(self.region_names)}

    @property
    def over_2n(self) -> list[str]:
        return [r for r, v in self.table().items() if v["peak_N"] > OVER_N]

    def paper_comparison(self) -> dict[str, list[str]]:
        ref = set(paper()["handshake"]["over_2N"])
        got = set(self.over_2n)
        return {"both": sorted(ref & got), "only_paper": sorted(ref - got),
                "only_softhand": sorted(got - ref)}

    def summary(self) -> dict:
        sim = float(self.time_s[-1])
        return {"regions": self.table(), "over_2N": self.over_2n,
                "paper_over_2N": self.paper_comparison(), "skins": self.skins,
                "steps_per_s": self.steps / self.wall_s, "realtime_factor": sim / self.wall_s}


def _contacts(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    rows = []
    force = np.zeros(6)
    for i in range(data.ncon):
        c = data.contact[i]
        if c.efc_address < 0:
            continue
        mujoco.mj_contactForce(model, data, i, force)
        rows.append([*c.pos, *c.frame[:3], force[0]])
    return np.asarray(rows, dtype=float).reshape(-1, 7)


def run_handshake(*, design: str | None = None, skins: Mapping[str, str] | None = None,
                  controller: str = "open-loop", seed: int = 0, record_every: int = 10,
                  **env_kwargs) -> HandshakeRun:
    """Run one episode; keep every ``record_every``-th physics step for the recording."""
    env = HandshakeEnv(design=design, skins=skins, **env_kwargs)
    ctrl = make_controller(controller)
    obs, info = env.reset(seed=seed)
    m, d = env.model, env.data
    frames: dict[str, list] = {k: [] for k in ("t", "q", "mp", "mq", "f", "c", "ph")}
    steps, wall = 0, 0.0
    while True:
        t0 = time.perf_counter()
        obs, _, term, trunc, info = env.step(ctrl(obs, info))
        wall += time.perf_counter() - t0
        steps += env.frame_skip
        if steps % record_every == 0 or term or trunc:
            frames["t"].append(d.time)
            frames["q"].append(d.qpos.copy())
            frames["mp"].append(d.mocap_pos.copy())
            frames["mq"].append(d.mocap_quat.copy())
            frames["f"].append([info["region_forces_N"][r] for r in env.region_names])
            frames["c"].append(_contacts(m, d))
            frames["ph"].append(info["phase"])
        if term or trunc:
            break
    if term:
        raise FloatingPointError(f"the handshake became unstable at t = {d.time:.3f} s")
    return HandshakeRun(env.region_names, dict(env.skins), np.array(frames["t"]),
                        np.array(frames["q"]), np.array(frames["mp"]), np.array(frames["mq"]),
                        np.array(frames["f"]), frames["c"], frames["ph"], wall, steps, m)
