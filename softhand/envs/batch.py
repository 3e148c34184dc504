"""The batched physics backend: W handshake scenes stepped together by ``mujoco.batch``.

`BatchPhysics` implements the seam of `MujocoPhysics` over
arrays with a leading world axis, for the vector env (`softhand.envs.vector`):

- ``reset(worlds, pos, quat, …)``: MuJoCo's reset of the given worlds, their mounts placed, motors
  pre-shaped (as MujocoPhysics.reset, per world)
- ``ctrl``: (W, nu) the worlds' controls, written before ``advance``
- ``advance(live, mount_paths)``: one action period of the ``live`` worlds: ``frame_skip`` steps,
  each world's mount on its path (W, frame_skip, 3); returns a `Divergence` or None per world
- ``region_forces()``: (W, regions) force (N) of each region, and the bones' part
- ``saturated_sensors()``: (W,) region sensors that matched more contacts than slots
- ``partner_feel()``: (W, phalanges) net force on each of the partner's phalanx tissues
- ``contacts_above(w, limits)``: world w's contacts beyond their pair's calibrated range
- ``qpos(index)``, ``qvel``: (W, k) the entries ``index`` (W, k) of each world's state
- ``time``: (W,) each world's time (s)

Worlds whose compiled models give MuJoCo's data the same layout share one
``mujoco.batch.Batch`` (``set_models``: each world its own model, e.g. other skins, whose pair
solref/solimp differ); worlds whose models differ in structure get a Batch each. Partners of other
hand sizes are such worlds: the partner's palm tissue is a convex mesh whose vertex count changes
with its size (415 or 416 vertices, and the collision BVH with them), and MuJoCo refuses to run
models of another data layout in one batch (``mjb_setModels``). Each Batch is persistent (one
MjData per world), so that a world's contacts can be read after a step (``data``); its threads
release the GIL and its results are bit-identical to one MjData per world stepped alone (MuJoCo's
documentation), which the tests check against the single env.

Divergence is per world and checked as the single env checks it: after every step a world whose
time went back (MuJoCo reset it after a bad position, velocity or acceleration) stops there, and
after the last step a world with a raised warning counter or a non-finite state diverged; a world
in which MuJoCo raised an error (``mujoco.batch.SimulationError``) diverged with that error. A
diverged world is never stepped again until it is reset.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import mujoco
import numpy as np
from mujoco import batch as mjbatch

from softhand.envs.physics import (
    Divergence,
    SensorLayout,
    contacts_above,
    diagnose,
    settled_rows,
)

__all__ = ["BatchPhysics", "layout_key"]

_NO_SENSORS = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)


def layout_key(m: mujoco.MjModel) -> tuple[int, ...]:
    """The model's sizes: models with equal keys give MjData one layout and share a Batch."""
    return tuple(int(v) for v in m._sizes)


class _Group:
    """The worlds of one Batch: their indices in the vector, and the Batch's bound arrays."""

    def __init__(self, worlds: list[int], models: list[mujoco.MjModel], nthread: int,
                 layout: SensorLayout) -> None:
        self.worlds = np.asarray(worlds)
        self.models = models
        self.batch = mjbatch.Batch(models[0], nsim=len(worlds),
                                   nthread=max(1, min(nthread, len(worlds))), persistent=True)
        self.distinct = list({id(m): m for m in models}.values())
        self.batch.set_models(models)
        self.layout = layout
        b = self.batch
        self.time, self.qpos, self.qvel = b.bind("time"), b.bind("qpos"), b.bind("qvel")
        self.ctrl, self.act = b.bind("ctrl"), b.bind("act")
        self.mocap_pos, self.mocap_quat = b.bind("mocap_pos"), b.bind("mocap_quat")
        self.sensordata = b.bind("sensordata")
        self.ncon = b.bind("ncon")  # contacts per world, without copying its data
        self.warning = np.asarray(b.warning)  # (nsim, mjNWARNING, 2): last info, count (a view)
        self.scratch = mujoco.MjData(models[0])  # get_data's target (a new MjData costs ~1 ms)
        self.every = np.arange(len(worlds))
        self.sensors_on = True  # the models as compiled

    def sensors(self, on: bool) -> None:
        """Sensors computed (on) or skipped by the next steps; they do not act on the dynamics.
        Only a change touches the models (mjb_setModels copies the batch's model pointers)."""
        if on == self.sensors_on:
            return
        self.sensors_on = on
        for m in self.distinct:
            flags = m.opt.disableflags
            m.opt.disableflags = flags & ~_NO_SENSORS if on else flags | _NO_SENSORS
        self.batch.set_models(self.models)  # a model edited: set again (mjb_setModels)


class BatchPhysics:
    """W scenes' physics, stepped ``frame_skip`` steps per action by ``mujoco.batch``.

    Args:
        models: one compiled scene per world (the same object may serve several worlds).
        frame_skip: physics steps per action (>= 1).
        region_sensors, feel_sensors, mocap_body, bone_sensors: as
            `MujocoPhysics` (the same names in every world).
        nthread: threads per Batch (default: the CPUs this process may run on).
    """

    def __init__(self, models: Sequence[mujoco.MjModel], frame_skip: int,
                 region_sensors: list[str], feel_sensors: list[str], mocap_body: str,
                 bone_sensors: list[tuple[str, ...]] | None = None,
                 nthread: int | None = None) -> None:
        if not models:
            raise ValueError("models: expected at least one world's model, got none")
        self.models = list(models)
        self.num_worlds = len(self.models)
        self.frame_skip = int(frame_skip)
        nthread = nthread or len(os.sched_getaffinity(0))
        by_key: dict[tuple[int, ...], list[int]] = {}
        for w, m in enumerate(self.models):
            by_key.setdefault(layout_key(m), []).append(w)
        self.groups: list[_Group] = []
        self._group_of = np.zeros(self.num_worlds, int)
        self._local = np.zeros(self.num_worlds, int)
        for worlds in by_key.values():
            ms = [self.models[w] for w in worlds]
            self._group_of[worlds] = len(self.groups)
            self._local[worlds] = np.arange(len(worlds))
            self.groups.append(_Group(worlds, ms, nthread, SensorLayout(
                ms[0], region_sensors, feel_sensors, bone_sensors)))
        self._mocap = np.array([m.body(mocap_body).mocapid[0] for m in self.models])
        self._timestep = np.array([m.opt.timestep for m in self.models])
        for g in self.groups:  # per Batch, by its local ids
            g.mocap, g.timestep = self._mocap[g.worlds], self._timestep[g.worlds]
        self._index_cache: dict[int, tuple[np.ndarray, list]] = {}
        #: why each world's last `advance` diverged (None: it did not)
        self.divergence: list[Divergence | None] = [None] * self.num_worlds

    # --- state ---------------------------------------------------------------------------------
    @property
    def time(self) -> np.ndarray:
        out = np.empty(self.num_worlds)
        for g in self.groups:
            out[g.worlds] = g.time
        return out

    def _columns(self, index: np.ndarray) -> list[np.ndarray | slice]:
        """Per Batch, the columns of ``index`` (W, k) for its worlds: one row (a slice when
        consecutive) where every world of the Batch has the same entries (one scene), else
        the rows. Kept per index array (the vector env passes the same ones every step)."""
        known = self._index_cache.get(id(index))
        if known is not None and known[0] is index:
            return known[1]
        cols = []
        for g in self.groups:
            rows = index[g.worlds]
            if (rows == rows[0]).all():
                first = rows[0]
                consecutive = first.size and (np.diff(first) == 1).all()
                cols.append(slice(int(first[0]), int(first[-1]) + 1) if consecutive else first)
            else:
                cols.append(rows)
        self._index_cache[id(index)] = (index, cols)
        return cols

    def _gather(self, field: str, index: np.ndarray) -> np.ndarray:
        out = np.empty(index.shape)
        for g, cols in zip(self.groups, self._columns(index), strict=True):
            rows = getattr(g, field)
            out[g.worlds] = (np.take_along_axis(rows, cols, axis=1)
                             if isinstance(cols, np.ndarray) and cols.ndim == 2 else rows[:, cols])
        return out

    def qpos(self, index: np.ndarray) -> np.ndarray:
        """Entries ``index[w]`` of world w's qpos, shape (W, k)."""
        return self._gather("qpos", np.asarray(index))

    def qvel(self, index: np.ndarray) -> np.ndarray:
        """Entries ``index[w]`` of world w's qvel, shape (W, k)."""
        return self._gather("qvel", np.asarray(index))

    def set_ctrl(self, index: np.ndarray, values: np.ndarray) -> None:
        """Controls ``index[w]`` (actuator ids, (W, k)) of world w to ``values[w]``."""
        index = np.asarray(index)
        for g, cols in zip(self.groups, self._columns(index), strict=True):
            if isinstance(cols, np.ndarray) and cols.ndim == 2:
                np.put_along_axis(g.ctrl, cols, values[g.worlds], axis=1)
            else:
                g.ctrl[:, cols] = values[g.worlds]

    def data(self, world: int) -> mujoco.MjData:
        """World ``world``'s MjData after its last call: a copy (contacts, forces, sensors) into
        its Batch's scratch MjData, which the next call of ``data`` on that Batch overwrites."""
        g = self.groups[self._group_of[world]]
        return g.batch.get_data(int(self._local[world]), g.scratch)

    # --- episode -------------------------------------------------------------------------------
    def reset(self, worlds: Sequence[int], mount_pos: np.ndarray, mount_quat: np.ndarray,
              presets: Sequence[tuple[tuple[int, int, float], ...]]) -> None:
        """MuJoCo's reset of ``worlds``, world k's mount at ``mount_pos[k]``, ``mount_quat[k]``
        and its ``presets[k]`` set (as MujocoPhysics.reset), then mj_forward."""
        for k, w in enumerate(worlds):
            g, j = self.groups[self._group_of[w]], int(self._local[w])
            g.batch.reset([j], stage=mujoco.mjtStage.mjSTAGE_NONE)  # zeroes its warnings
            g.mocap_pos[j, self._mocap[w]] = mount_pos[k]
            g.mocap_quat[j, self._mocap[w]] = mount_quat[k]
            for qadr, aadr, value in presets[k]:
                g.qpos[j, qadr] = value
                if aadr >= 0:  # a servo with a state (integrated velocity)
                    g.act[j, aadr] = value
            g.batch.forward([j])
            self.divergence[w] = None

    def advance(self, live: np.ndarray, mount_paths: np.ndarray) -> list[Divergence | None]:
        """``frame_skip`` steps of the worlds where ``live`` (W,) is True, with the controls
        already in `set_ctrl`, world w's mount at ``mount_paths[w, i]`` on step i (shape
        (W, frame_skip, 3)); sensors computed on the last step only. Returns, per world, None or
        the `Divergence` that stopped it (None for worlds not stepped)."""
        live = np.asarray(live, bool).copy()
        self.divergence = [None] * self.num_worlds
        last_good = self.time
        try:
            for i in range(self.frame_skip):
                last = i == self.frame_skip - 1
                for g in self.groups:
                    mine = live[g.worlds]
                    if mine.all():  # every world of the Batch: no ids for it to check
                        ids, step_ids = g.every, None
                    else:
                        ids = step_ids = np.flatnonzero(mine)
                        if not ids.size:
                            continue
                    worlds = g.worlds[ids]
                    g.mocap_pos[ids, g.mocap[ids]] = mount_paths[worlds, i]
                    t = g.time[ids]  # a copy (an index array)
                    last_good[worlds] = t
                    g.sensors(on=last)  # off for the frame's first steps, on for its last
                    try:
                        g.batch.step(step_ids)
                    except mjbatch.SimulationError as exc:  # MuJoCo raised an error in these worlds
                        for j in exc.ids:
                            w = int(g.worlds[j])
                            self.divergence[w] = Divergence(float(last_good[w]),
                                                            f"MuJoCo error: {g.batch.error(j)}")
                            live[w] = False
                    reset = g.time[ids] < t + 0.5 * g.timestep[ids]  # MuJoCo reset the data
                    for j, w in zip(ids[reset], worlds[reset], strict=True):
                        if live[w]:
                            self.divergence[w] = diagnose(
                                self.models[w], self.data(int(g.worlds[j])), float(last_good[w]))
                            live[w] = False
        finally:
            for g in self.groups:
                g.sensors(on=True)  # as compiled, whatever stopped the frame
        for g in self.groups:  # MuJoCo's warnings, and a non-finite state the last step made
            ids = np.flatnonzero(live[g.worlds])
            if not ids.size:
                continue
            settled = settled_rows(g.warning[:, :, 1], g.qpos, g.qvel, ids)
            for j in ids[~settled]:
                w = int(g.worlds[j])
                self.divergence[w] = diagnose(self.models[w], self.data(int(g.worlds[j])),
                                              float(g.time[j]))
        return list(self.divergence)

    # --- read-out ------------------------------------------------------------------------------
    def _read(self, how: str) -> list[tuple[np.ndarray, object]]:
        return [(g.worlds, getattr(g.layout, how)(g.sensordata)) for g in self.groups]

    def region_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """Per world and region: the force on its sensed skin and bone together (N), and the
        bone's part; shapes (W, regions)."""
        total = bone = None
        for worlds, (t, b) in self._read("region_forces"):
            if total is None:
                total = np.empty((self.num_worlds, t.shape[1]))
                bone = np.empty_like(total)
            total[worlds], bone[worlds] = t, b
        return total, bone

    def saturated_sensors(self) -> np.ndarray:
        out = np.zeros(self.num_worlds, int)
        for worlds, v in self._read("saturated"):
            out[worlds] = v
        return out

    def partner_feel(self) -> np.ndarray:
        parts = self._read("feel")
        out = np.empty((self.num_worlds, parts[0][1].shape[1]))
        for worlds, v in parts:
            out[worlds] = v
        return out

    def contacts_above(self, world: int, limits: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World ``world``'s contacts beyond ``limits`` (MujocoPhysics.contacts_above); a world
        without contacts (the reach, the return) is answered without copying its data."""
        g = self.groups[self._group_of[world]]
        if g.ncon[self._local[world]] == 0:
            return np.zeros((0, 2), int), np.zeros(0), np.zeros(0)
        return contacts_above(self.data(world), limits)
