"""The physics of the handshake env, behind one seam: what a batched backend would implement.

:class:`TwoHandTouchEnv <softhand.envs.touch.TwoHandTouchEnv>` and its scenario keep the
partner's script, the controllers' interface, the reward and the observation; everything that
touches MuJoCo's state during an episode goes through :class:`MujocoPhysics`:

============================== =====================================================================
``reset(mount_pos, quat, ...)``MuJoCo's reset, the partner's mount placed, motors pre-shaped
``advance(ctrl, mount_path)``  one action period: ``frame_skip`` steps, the mount following its
                               prescribed path (one row per step), sensors read on the last step
``region_forces()``            force (N) of each region: its skin's contact sensor and its bones
                               bottoming out under it; and the bones' part
``saturated_sensors()``        region sensors that matched more contacts than they have slots
``partner_feel()``             net force (N) on each of the partner's phalanx tissues
``contacts_above(limits)``     the contacts whose normal force exceeds their pair's calibrated
                               range: geom pairs and forces
``qpos``, ``qvel``, ``time``   the state
============================== =====================================================================

A batched backend (MuJoCo Warp or MJX: many worlds stepped at once on an accelerator) implements
the same methods over arrays with a leading world axis; the env's script and reward are per world
and stay on the host. Timings of the handshake are of this class's ``advance``.
"""

from __future__ import annotations

import mujoco
import numpy as np

from softhand.hands.skeleton import SENSOR_SLOTS, contact_sensor_force

__all__ = ["MujocoPhysics"]

_NO_SENSORS = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)


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
        adr = np.array([m.sensor_adr[m.sensor(s).id] for s in region_sensors])
        # SENSOR_SLOTS slots of (found, force xyz in the contact frame); slot 0's found counts
        # every match
        self._sensor_idx = adr[:, None] + np.arange(4 * SENSOR_SLOTS)[None, :]
        self._found_idx = adr
        bones = [(i, m.sensor_adr[m.sensor(s).id]) for i, names in enumerate(bone_sensors or [])
                 for s in names]
        self._bone_region = np.array([i for i, _ in bones], int)
        self._bone_idx = (np.array([a for _, a in bones], int)[:, None]
                          + np.arange(4 * SENSOR_SLOTS)[None, :] if bones
                          else np.zeros((0, 4 * SENSOR_SLOTS), int))
        self._n_regions = len(region_sensors)
        feel = np.array([m.sensor_adr[m.sensor(s).id] for s in feel_sensors])
        self._feel_idx = feel[:, None] + np.arange(1, 4)[None, :]  # net force xyz per tissue
        self._mocap = m.body(mocap_body).mocapid[0]
        # views into MjData (its buffers never move): written or read every step
        self._row = self.data.mocap_pos[self._mocap]
        self.ctrl, self._sensordata = self.data.ctrl, self.data.sensordata
        self.qpos, self.qvel = self.data.qpos, self.data.qvel

    @property
    def time(self) -> float:
        return float(self.data.time)

    def reset(self, mount_pos: np.ndarray, mount_quat: np.ndarray,
              preset: tuple[tuple[int, int, float], ...] = ()) -> None:
        """MuJoCo's reset, the mount placed, and each ``(qpos address, act address, value)`` of
        ``preset`` set: a joint and its integrated-velocity servo's setpoint (a motor pre-shaped
        before the episode)."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        d.mocap_pos[self._mocap] = mount_pos
        d.mocap_quat[self._mocap] = mount_quat
        for qadr, aadr, value in preset:
            d.qpos[qadr] = value
            if aadr >= 0:  # a servo with a state (integrated velocity); a position servo has none
                d.act[aadr] = value
        mujoco.mj_forward(m, d)

    def advance(self, mount_path: np.ndarray) -> None:
        """``frame_skip`` steps with the controls already in :attr:`ctrl`, the mount at
        ``mount_path[i]`` on step i (shape (frame_skip, 3)). Sensors are computed on the last
        step only: they do not act on the dynamics (35 contact sensors, read once per action)."""
        m, d, row, opt = self.model, self.data, self._row, self.model.opt
        flags = opt.disableflags
        opt.disableflags = flags | _NO_SENSORS
        try:
            for pos in mount_path[:-1]:
                row[:] = pos
                mujoco.mj_step(m, d)
            opt.disableflags = flags
            row[:] = mount_path[-1]
            mujoco.mj_step(m, d)
        finally:
            opt.disableflags = flags

    def region_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """Per region: the force on its sensed skin and bone together (N), and the bone's part."""
        skin = contact_sensor_force(self._sensordata[self._sensor_idx].reshape(-1, SENSOR_SLOTS, 4))
        bone = np.zeros(self._n_regions)
        if self._bone_idx.size:
            np.add.at(bone, self._bone_region, contact_sensor_force(
                self._sensordata[self._bone_idx].reshape(-1, SENSOR_SLOTS, 4)))
        return skin + bone, bone

    def saturated_sensors(self) -> int:
        return int((self._sensordata[self._found_idx] > SENSOR_SLOTS).sum())

    def partner_feel(self) -> np.ndarray:
        return np.linalg.norm(self._sensordata[self._feel_idx], axis=1)

    def contacts_above(self, limits: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(geom pairs (k, 2), normal forces (k,), limits (k,)) of the contacts whose normal force
        exceeds ``limits[geom1, geom2]`` (a geom x geom table; inf where there is no limit)."""
        d = self.data
        if d.ncon == 0:
            return np.zeros((0, 2), int), np.zeros(0), np.zeros(0)
        con = d.contact
        adr = con.efc_address
        live = adr >= 0
        geoms = con.geom[live]
        force = d.efc_force[adr[live]]  # elliptic cones: a contact's first row is its normal
        top = limits[geoms[:, 0], geoms[:, 1]]
        over = force > top
        return geoms[over], force[over], top[over]
