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

__all__ = ["ContactAreas", "HandshakeRun", "mean_curvature_radius", "run_handshake"]

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
    region_area_mm2: np.ndarray | None = None
    rigid_force_N: np.ndarray | None = None

    def table(self) -> dict[str, dict[str, float]]:
        """Per region: peak and mean force (N) and contact area (mm^2) over the handshake."""
        f = self.region_force_N
        a = self.region_area_mm2 if self.region_area_mm2 is not None else np.zeros_like(f)
        return {r: {"peak_N": float(f[:, i].max()), "mean_N": float(f[:, i].mean()),
                    "peak_area_mm2": float(a[:, i].max()), "mean_area_mm2": float(a[:, i].mean())}
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
        rigid = self.rigid_force_N if self.rigid_force_N is not None else np.zeros(1)
        return {"regions": self.table(), "over_2N": self.over_2n,
                "paper_over_2N": self.paper_comparison(), "skins": self.skins,
                "rigid_contact_peak_N": float(rigid.max()),
                "steps_per_s": self.steps / self.wall_s, "realtime_factor": sim / self.wall_s}


def mean_curvature_radius(model: mujoco.MjModel, geom: int) -> float:
    """1 / mean curvature (m) of a geom's flattest point: the harmonic mean of its principal radii
    (sphere r; capsule 2r; ellipsoid with semi-axes a1 >= a2 >= a3 at the a3 pole:
    2 / (a3/a1^2 + a3/a2^2)); other types: their largest size."""
    size, kind = model.geom_size[geom], model.geom_type[geom]
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return float(size[0])
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return 2.0 * float(size[0])
    if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        a1, a2, a3 = sorted(size, reverse=True)
        return float(2.0 / (a3 / a1**2 + a3 / a2**2))
    return float(max(size))


def sphere_overlap_area(r1: float, r2: float, depth: float) -> float:
    """Area (m^2) of the circle where two sphere surfaces of radii r1, r2 cross when pressed
    ``depth`` into each other (centres r1 + r2 - depth apart); 0 without overlap, the smaller
    cross-section once one sphere lies inside the other."""
    if depth <= 0:
        return 0.0
    d = r1 + r2 - depth
    if d <= abs(r1 - r2):
        return float(np.pi * min(r1, r2) ** 2)
    a2 = (4 * d * d * r1 * r1 - (d * d - r2 * r2 + r1 * r1) ** 2) / (4 * d * d)
    return float(np.pi * max(a2, 0.0))


class ContactAreas:
    """Per-region contact area and the force carried by bone on bone, from MuJoCo's contacts.

    Area estimate: each contact of a region's skin geom adds the area of the circle where the two
    undeformed surfaces, taken as spheres of each geom's mean curvature radius, intersect at the
    contact's penetration depth delta (exact for two spheres: 2 pi R delta, R = R1 R2 / (R1 + R2),
    to first order in delta, never more than the smaller sphere's cross-section). Softer skins
    sink deeper at the same force, so their areas grow (the paper's argument for compliant
    skins); the deformed patch of a real skin is larger still (an estimate, not an FE result).
    """

    def __init__(self, model: mujoco.MjModel, region_geoms: list[int]) -> None:
        self.region_of = -np.ones(model.ngeom, dtype=int)
        self.region_of[np.asarray(region_geoms)] = np.arange(len(region_geoms))
        self.radius = np.array([mean_curvature_radius(model, g) for g in range(model.ngeom)])
        self.bone = np.array(["bone_" in (model.geom(g).name or "") for g in range(model.ngeom)])
        self.model = model
        self.n_regions = len(region_geoms)
        self._force = np.zeros(6)

    def __call__(self, data: mujoco.MjData) -> tuple[np.ndarray, float, np.ndarray]:
        """Area per region (mm^2), bone-on-bone force (N), and per active contact a row of
        position xyz (m), normal xyz and normal force (N), as the recording takes them."""
        area = np.zeros(self.n_regions)
        rigid = 0.0
        rows = []
        for i in range(data.ncon):
            c = data.contact[i]
            if c.efc_address < 0:
                continue
            mujoco.mj_contactForce(self.model, data, i, self._force)
            rows.append([*c.pos, *c.frame[:3], self._force[0]])
            g1, g2 = c.geom1, c.geom2
            if self.bone[g1] and self.bone[g2]:
                rigid += self._force[0]
                continue
            depth = -c.dist
            for g in (g1, g2):
                r = self.region_of[g]
                if r >= 0 and depth > 0:
                    area[r] += sphere_overlap_area(self.radius[g1], self.radius[g2], depth) * 1e6
        return area, rigid, np.asarray(rows, dtype=float).reshape(-1, 7)


def run_handshake(*, design: str | None = None, skins: Mapping[str, str] | None = None,
                  controller: str = "neutral", seed: int = 0, record_every: int | None = None,
                  env: HandshakeEnv | None = None, **env_kwargs) -> HandshakeRun:
    """Run one episode; keep every ``record_every``-th physics step for the recording (default:
    the last step of every action, 100 Hz).

    ``env`` is an environment built already (then ``design``, ``skins`` and ``env_kwargs`` are
    not used): the CLI builds it first, so that every input is checked before the episode.
    """
    if env is None:
        env = HandshakeEnv(design=design, skins=skins, **env_kwargs)
    ctrl = make_controller(controller)
    record_every = record_every or env.frame_skip
    obs, info = env.reset(seed=seed)
    m, d = env.model, env.data
    areas = ContactAreas(m, [m.geom(g).id for g in env.region_geoms])
    frames: dict[str, list] = {k: [] for k in ("t", "q", "mp", "mq", "f", "c", "ph", "a", "r")}
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
            frames["ph"].append(info["phase"])
            area, rigid, rows = areas(d)
            frames["c"].append(rows)
            frames["a"].append(area)
            frames["r"].append(rigid)
        if term or trunc:
            break
    if term:
        raise FloatingPointError(f"the handshake became unstable at t = {d.time:.3f} s")
    return HandshakeRun(env.region_names, dict(env.skins), np.array(frames["t"]),
                        np.array(frames["q"]), np.array(frames["mp"]), np.array(frames["mq"]),
                        np.array(frames["f"]), frames["c"], frames["ph"], wall, steps, m,
                        np.array(frames["a"]), np.array(frames["r"]))
