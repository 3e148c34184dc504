"""The physics of the handshake env, behind one seam: what a batched backend would implement.

`TwoHandTouchEnv` and its scenario keep the
partner's script, the controllers' interface, the reward and the observation; everything that
touches MuJoCo's state during an episode goes through `MujocoPhysics`:

- ``reset(mount_pos, quat, ...)``: MuJoCo's reset, the partner's mount placed, motors pre-shaped
- ``advance(ctrl, mount_path)``: one action period: ``frame_skip`` steps, the mount following its
  prescribed path (one row per step), sensors read on the last step; returns None, or the
  `Divergence` that ended it
- ``region_forces()``: force (N) of each region: its skin's contact sensor and its bones bottoming
  out under it; and the bones' part
- ``saturated_sensors()``: region sensors that matched more contacts than they have slots
- ``partner_feel()``: net force (N) on each of the partner's phalanx tissues
- ``contacts_above(limits)``: the contacts whose normal force exceeds their pair's calibrated range:
  geom pairs and forces
- ``qpos``, ``qvel``, ``time``: the state

`softhand.envs.batch.BatchPhysics` implements the same methods over arrays with a leading
world axis (``mujoco.batch``: W worlds on threads), for the vector env (softhand.envs.vector); the
partner's script, the controllers and the reward run over those arrays
(`HandshakeWorlds`), the single env being one world.
Both backends read the sensors (`SensorLayout`), diagnose a divergence (`diagnose`)
and check the contacts' ranges (`contacts_above`) with the same functions. Timings of the
handshake are of this class's ``advance``.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass

import mujoco
import numpy as np
from numba import njit

from softhand.compiled import pairwise_sum
from softhand.hands.skeleton import SENSOR_SLOTS

__all__ = ["Divergence", "DivergenceError", "MujocoPhysics", "SensorLayout", "contacts_above",
           "diagnose", "mujoco_warnings_kept", "settled_rows"]

_NO_SENSORS = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
_W = mujoco.mjtWarning
#: what each MuJoCo warning means, and whether its index is a qpos address (else a dof, an
#: actuator or a count); MuJoCo resets the data after the three "bad" state warnings
_WARNINGS = {int(_W.mjWARN_BADQACC): ("a bad acceleration", "dof"),
             int(_W.mjWARN_BADQVEL): ("a bad velocity", "dof"),
             int(_W.mjWARN_BADQPOS): ("a bad position", "qpos"),
             int(_W.mjWARN_BADCTRL): ("a bad control", "actuator"),
             int(_W.mjWARN_CONTACTFULL): ("a full contact buffer", "count"),
             int(_W.mjWARN_CNSTRFULL): ("a full constraint buffer", "count"),
             int(_W.mjWARN_INERTIA): ("an invalid inertia matrix", "dof")}
_NAMES = {int(v): k for k, v in _W.__members__.items()}
_RESETS = (int(_W.mjWARN_BADQACC), int(_W.mjWARN_BADQVEL), int(_W.mjWARN_BADQPOS))


@dataclass(frozen=True)
class Divergence:
    """Why a physics step diverged: ``time_s``, the simulated time of the last good state (s),
    and ``cause``, one line naming what MuJoCo found (its warning, the dof and joint), e.g.
    ``MuJoCo reset the simulation after a bad acceleration (mjWARN_BADQACC) in dof 37 (joint
    pro_skin_Little1_pad)``."""

    time_s: float
    cause: str

    def __str__(self) -> str:
        return f"{self.cause} at t = {self.time_s:.3f} s"


class DivergenceError(RuntimeError):
    """A run's simulation diverged (`Divergence`): raised by the runs (e.g.
    `softhand.envs.run.run_handshake`) instead of continuing from MuJoCo's reset state.

    Attributes: ``divergence``, ``skins`` and ``representations`` (region -> name), and
    ``timestep_s``; `summary` says all but the advice, which ``str()`` adds.
    """

    def __init__(self, divergence: Divergence, *, skins: Mapping[str, str],
                 representations: Mapping[str, str], timestep_s: float,
                 what: str = "the handshake") -> None:
        self.divergence = divergence
        self.skins, self.representations = dict(skins), dict(representations)
        self.timestep_s = float(timestep_s)
        #: a smaller timestep to try (s): 1 ms from the default, else half, at least 0.1 ms
        self.suggested_timestep_s = max(1e-4, min(1e-3, self.timestep_s / 2))
        self.summary = (f"{what} diverged at t = {divergence.time_s:.3f} s ({divergence.cause}); "
                        f"{_listed('skin', self.skins)}, "
                        f"{_listed('representation', self.representations)}, timestep "
                        f"{self.timestep_s * 1e3:g} ms")
        super().__init__(f"{self.summary}; try a smaller timestep (e.g. "
                         f"{self.suggested_timestep_s:g} s)")


def _listed(what: str, by_region: Mapping[str, str]) -> str:
    names = sorted(set(by_region.values()))
    return f"{what} {names[0]}" if len(names) == 1 else f"{what}s {', '.join(names)}"


class MujocoPhysics:
    """One MuJoCo model and its data, stepped ``frame_skip`` steps per action.

    Args:
        model: the compiled handshake scene.
        frame_skip: physics steps per action (>= 1).
        region_sensors: the region contact sensors' names, in the env's region order.
        feel_sensors: the partner's net-force contact sensors the grip regulator reads.
        mocap_body: the partner's mount (a mocap body).
        bone_sensors: per region, the contact sensors of its bones inside its zone (bone
            bottoming out under its skin); their force is part of the region's force.
    """

    def __init__(self, model: mujoco.MjModel, frame_skip: int, region_sensors: list[str],
                 feel_sensors: list[str], mocap_body: str,
                 bone_sensors: list[tuple[str, ...]] | None = None) -> None:
        self.model = model
        self.data = mujoco.MjData(model)
        self.frame_skip = int(frame_skip)
        m = model
        #: where the region, bone and feel sensors sit in sensordata
        self.sensors = SensorLayout(m, region_sensors, feel_sensors, bone_sensors)
        self._mocap = m.body(mocap_body).mocapid[0]
        # views into MjData (its buffers never move): written or read every step
        self._row = self.data.mocap_pos[self._mocap]
        self.ctrl, self._sensordata = self.data.ctrl, self.data.sensordata
        self.qpos, self.qvel = self.data.qpos, self.data.qvel
        self._warnings = self.data.warning.number  # MuJoCo's warning counters (a view)
        #: why the last `advance` diverged (None: it did not, or no step since reset)
        self.divergence: Divergence | None = None
        self._reads: tuple | None = None  # the sensors' reads of the state (`_read`)
        self._opt = model.opt  # a view of the model's options, made once (each access makes one)

    @property
    def time(self) -> float:
        return float(self.data.time)

    def reset(self, mount_pos: np.ndarray, mount_quat: np.ndarray,
              preset: tuple[tuple[int, int, float], ...] = ()) -> None:
        """MuJoCo's reset, the mount placed, and each ``(qpos address, act address, value)`` of
        ``preset`` set: a joint and its integrated-velocity servo's setpoint (a motor pre-shaped
        before the episode)."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)  # also zeroes MuJoCo's warning counters
        self.divergence, self._reads = None, None
        d.mocap_pos[self._mocap] = mount_pos
        d.mocap_quat[self._mocap] = mount_quat
        for qadr, aadr, value in preset:
            d.qpos[qadr] = value
            if aadr >= 0:  # a servo with a state (integrated velocity); a position servo has none
                d.act[aadr] = value
        mujoco.mj_forward(m, d)

    def advance(self, mount_path: np.ndarray) -> Divergence | None:
        """``frame_skip`` steps with the controls already in `ctrl`, the mount at
        ``mount_path[i]`` on step i (shape (frame_skip, 3)). Sensors are computed on the last
        step only: they do not act on the dynamics (35 contact sensors, read once per action).

        Returns None, or the `Divergence` that stopped it: MuJoCo reset the data after a
        bad position, velocity or acceleration (its time went back; checked every step, and the
        action period stops there), MuJoCo raised another warning (full contact or constraint
        buffer, bad control, bad inertia), or the state is not finite. The state is then not a
        continuation of the episode. The checks read a time per step and a few counters and
        sums per action."""
        m, d, row, opt = self.model, self.data, self._row, self._opt
        h = opt.timestep
        self.divergence, self._reads = None, None
        flags = opt.disableflags
        opt.disableflags = flags | _NO_SENSORS
        try:
            for pos in mount_path[:-1]:
                row[:] = pos
                t = d.time
                mujoco.mj_step(m, d)
                if d.time < t + 0.5 * h:  # MuJoCo reset the data (mj_checkPos/Vel/Acc)
                    self.divergence = self._divergence(t)
                    return self.divergence
            opt.disableflags = flags
            row[:] = mount_path[-1]
            t = d.time
            mujoco.mj_step(m, d)
        finally:
            opt.disableflags = flags
        if d.time < t + 0.5 * h:
            self.divergence = self._divergence(t)
        # MuJoCo checks the state (and every step's qacc) at the start of its next step, so the
        # state the last step made is checked here
        elif not _settled(self._warnings, self.qpos, self.qvel):
            self.divergence = self._divergence(d.time)
        return self.divergence

    def _divergence(self, t: float) -> Divergence:
        return diagnose(self.model, self.data, t)

    def _read(self) -> tuple[np.ndarray, np.ndarray, int, np.ndarray]:
        """The sensors' reads of this state (`SensorLayout.read`), made once per state."""
        if self._reads is None:
            self._reads = self.sensors.read(self._sensordata)
        return self._reads

    def region_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """Per region: the force on its sensed skin and bone together (N), and the bone's part."""
        total, bone, _, _ = self._read()
        return total, bone

    def saturated_sensors(self) -> int:
        return self._read()[2]

    def partner_feel(self) -> np.ndarray:
        return self._read()[3]

    def contacts_above(self, limits: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(geom pairs (k, 2), normal forces (k,), limits (k,)) of the contacts whose normal force
        exceeds ``limits[geom1, geom2]`` (a geom x geom table; inf where there is no limit)."""
        return contacts_above(self.data, limits)


def contacts_above(d: mujoco.MjData, limits: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(geom pairs (k, 2), normal forces (k,), limits (k,)) of the contacts of ``d`` whose normal
    force exceeds ``limits[geom1, geom2]`` (a geom x geom table; inf where there is no limit)."""
    con = d.contact
    # contiguous copies, also of no contacts: the kernel sees one array type and compiles once,
    # on the first step (a view of one contact is C-contiguous, of more only strided)
    return _above(np.ascontiguousarray(con.geom), np.ascontiguousarray(con.efc_address),
                  d.efc_force, limits)


@njit(cache=True)
def _above(geom, efc_address, efc_force, limits):
    """`contacts_above` on the contact arrays, compiled (elliptic cones: a contact's first
    constraint row is its normal force)."""
    keep = np.zeros(geom.shape[0], np.bool_)
    for c in range(geom.shape[0]):
        adr = efc_address[c]
        keep[c] = adr >= 0 and efc_force[adr] > limits[geom[c, 0], geom[c, 1]]
    geoms = geom[keep].astype(np.int64)
    force = np.empty(geoms.shape[0])
    top = np.empty(geoms.shape[0])
    for k in range(geoms.shape[0]):
        top[k] = limits[geoms[k, 0], geoms[k, 1]]
    k = 0
    for c in range(geom.shape[0]):
        if keep[c]:
            force[k] = efc_force[efc_address[c]]
            k += 1
    return geoms, force, top


class SensorLayout:
    """Where the regions' contact sensors, their bones' and the partner's feel sensors sit in
    ``sensordata``; reads one world's sensordata (1-D) or many worlds' at once (rows).

    Args: as `MujocoPhysics`.
    """

    def __init__(self, m: mujoco.MjModel, region_sensors: list[str], feel_sensors: list[str],
                 bone_sensors: list[tuple[str, ...]] | None = None) -> None:
        # a contact sensor's SENSOR_SLOTS slots of (found, force xyz in the contact frame) start
        # at its address; slot 0's found counts every match
        self._found_idx = np.array([m.sensor_adr[m.sensor(s).id] for s in region_sensors], int)
        bones = [(i, m.sensor_adr[m.sensor(s).id]) for i, names in enumerate(bone_sensors or [])
                 for s in names]
        self._n_regions = len(region_sensors)
        self._bone_region = np.array([i for i, _ in bones], int)
        self._bone_adr = np.array([a for _, a in bones], int)
        # a region's bone sensors are consecutive: each region's sum is one segment
        self._bone_starts = np.unique(self._bone_region, return_index=True)[1].astype(int)
        self._feel_adr = np.array([m.sensor_adr[m.sensor(s).id] for s in feel_sensors], int)

    def region_forces(self, sensordata: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per region (last axis): the force on its sensed skin and bone together (N), and the
        bone's part."""
        rows = np.atleast_2d(sensordata)
        total, bone = _region_forces(rows, self._found_idx, self._bone_adr, self._bone_region,
                                     self._bone_starts, self._n_regions)
        return (total, bone) if sensordata.ndim > 1 else (total[0], bone[0])

    def read(self, sensordata: np.ndarray) -> tuple[np.ndarray, np.ndarray, int, np.ndarray]:
        """One world's (1-D sensordata) `region_forces`, `saturated` and `feel` in one compiled
        call: (force per region, its bone's part, saturated sensors, feel per phalanx)."""
        total, bone, saturated, feel = _read(sensordata[None], self._found_idx, self._bone_adr,
                                             self._bone_region, self._bone_starts,
                                             self._n_regions, self._feel_adr)
        return total[0], bone[0], int(saturated[0]), feel[0]

    def saturated(self, sensordata: np.ndarray) -> np.ndarray:
        """How many region sensors matched more contacts than they have slots."""
        out = _saturated(np.atleast_2d(sensordata), self._found_idx)
        return out if sensordata.ndim > 1 else out[0]

    def feel(self, sensordata: np.ndarray) -> np.ndarray:
        """Net force (N) on each of the partner's phalanx tissues (last axis)."""
        rows = np.atleast_2d(sensordata)
        out = _feel(rows, self._feel_adr)
        return out if sensordata.ndim > 1 else out[0]


@njit(cache=True, inline="always")
def _slots_force(row: np.ndarray, adr: int, scratch: np.ndarray) -> float:
    """A contact sensor's summed normal force: its SENSOR_SLOTS slots' second entries, summed in
    numpy's order (contact_sensor_force bit for bit), gathered into ``scratch`` (SENSOR_SLOTS)."""
    for s in range(SENSOR_SLOTS):
        scratch[s] = row[adr + 1 + 4 * s]
    return pairwise_sum(scratch)


@njit(cache=True)
def _region_forces(rows, region_adr, bone_adr, bone_region, bone_starts, n_regions):
    """SensorLayout.region_forces of W worlds' sensordata rows, compiled: (skin + bone, bone);
    a region's bones are summed as np.add.reduceat does (the first, plus the rest pairwise)."""
    worlds = rows.shape[0]
    total = np.empty((worlds, n_regions))
    bone = np.zeros((worlds, n_regions))
    per_bone = np.empty(bone_adr.size)
    scratch = np.empty(SENSOR_SLOTS)
    for w in range(worlds):
        row = rows[w]
        for k in range(bone_adr.size):
            per_bone[k] = _slots_force(row, bone_adr[k], scratch)
        for j in range(bone_starts.size):
            start = bone_starts[j]
            end = bone_starts[j + 1] if j + 1 < bone_starts.size else bone_adr.size
            bone[w, bone_region[start]] = per_bone[start] + pairwise_sum(per_bone[start + 1:end])
        for i in range(n_regions):
            total[w, i] = _slots_force(row, region_adr[i], scratch) + bone[w, i]
    return total, bone


@njit(cache=True)
def _read(rows, region_adr, bone_adr, bone_region, bone_starts, n_regions, feel_adr):
    total, bone = _region_forces(rows, region_adr, bone_adr, bone_region, bone_starts, n_regions)
    return total, bone, _saturated(rows, region_adr), _feel(rows, feel_adr)


@njit(cache=True)
def _settled(warnings, qpos, qvel) -> bool:
    """No MuJoCo warning was counted and the state is finite."""
    for n in warnings:
        if n:
            return False
    for x in qpos:
        if not math.isfinite(x):
            return False
    for x in qvel:  # noqa: SIM110 (numba compiles the loop, not a generator in all())
        if not math.isfinite(x):
            return False
    return True


@njit(cache=True)
def settled_rows(warnings, qpos, qvel, rows):
    """`_settled` of each of the worlds ``rows``: ``warnings`` (W, mjNWARNING) counts, ``qpos``
    (W, nq), ``qvel`` (W, nv)."""
    out = np.empty(rows.size, np.bool_)
    for k in range(rows.size):
        w = rows[k]
        out[k] = _settled(warnings[w], qpos[w], qvel[w])
    return out


@njit(cache=True)
def _saturated(rows, found_adr):
    out = np.zeros(rows.shape[0], np.int64)
    for w in range(rows.shape[0]):
        for adr in found_adr:
            out[w] += rows[w, adr] > SENSOR_SLOTS
    return out


@njit(cache=True)
def _feel(rows, feel_adr):
    """SensorLayout.feel of W worlds' sensordata rows: the norm of each net force, as
    np.linalg.norm sums its squares."""
    out = np.empty((rows.shape[0], feel_adr.size))
    for w in range(rows.shape[0]):
        for k in range(feel_adr.size):
            x, y, z = rows[w, feel_adr[k] + 1], rows[w, feel_adr[k] + 2], rows[w, feel_adr[k] + 3]
            out[w, k] = math.sqrt((x * x + y * y) + z * z)
    return out


def diagnose(m: mujoco.MjModel, d: mujoco.MjData, t: float) -> Divergence:
    """Why a world diverged at ``t`` (s, its last good time), from its data after the step:
    MuJoCo's warning (the first that fired), a reset (its time went back), or the first
    non-finite entry of the state."""
    fired = np.flatnonzero(d.warning.number)
    if fired.size:
        w = int(fired[0])
        what, kind = _WARNINGS.get(w, (f"warning {w}", "count"))
        i = int(d.warning.lastinfo[w])
        where = ""
        if kind == "dof" and 0 <= i < m.nv:
            where = f" in dof {i} (joint {_name(m, mujoco.mjtObj.mjOBJ_JOINT, m.dof_jntid[i])})"
        elif kind == "qpos" and 0 <= i < m.nq:
            j = int(np.searchsorted(m.jnt_qposadr, i, side="right") - 1)
            where = f" in qpos {i} (joint {_name(m, mujoco.mjtObj.mjOBJ_JOINT, j)})"
        elif kind == "actuator" and 0 <= i < m.nu:
            where = f" of actuator {_name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, i)}"
        elif kind == "count":
            where = f" ({i})"
        head = "MuJoCo reset the simulation after" if w in _RESETS else "MuJoCo warned of"
        return Divergence(t, f"{head} {what} ({_NAMES.get(w, w)}){where}")
    if d.time < t:
        return Divergence(t, "MuJoCo reset the simulation (its time went back to "
                             f"{d.time:.3f} s)")
    for name, values, size in (("qpos", d.qpos, m.nq), ("qvel", d.qvel, m.nv),
                               ("qacc", d.qacc, m.nv)):
        bad = np.flatnonzero(~np.isfinite(values[:size]))
        if bad.size:
            i = int(bad[0])
            j = (int(np.searchsorted(m.jnt_qposadr, i, side="right") - 1) if name == "qpos"
                 else int(m.dof_jntid[i]))
            return Divergence(t, f"non-finite state: {name}[{i}] = {values[i]} (joint "
                                 f"{_name(m, mujoco.mjtObj.mjOBJ_JOINT, j)})")
    return Divergence(t, "non-finite state")


def _name(model: mujoco.MjModel, kind: mujoco.mjtObj, i: int) -> str:
    return mujoco.mj_id2name(model, kind, int(i)) or f"#{int(i)}"


@contextmanager
def mujoco_warnings_kept() -> Iterator[list[str]]:
    """MuJoCo's warnings kept in a list (yielded) instead of printed and appended to
    ``MUJOCO_LOG.TXT`` in the working folder, MuJoCo's default: a run reports a divergence
    itself (`DivergenceError`, from MuJoCo's warning counters). Process-wide while open."""
    kept: list[str] = []
    old = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(kept.append)
    try:
        yield kept
    finally:
        mujoco.set_mju_user_warning(old)
