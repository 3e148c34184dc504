"""The GPU physics backend: W handshake scenes stepped together by MuJoCo Warp.

`WarpPhysics` implements the seam of `BatchPhysics` (the same
methods, arrays with a leading world axis) on ``mujoco_warp`` (MJWarp), MuJoCo's GPU port written
in NVIDIA Warp: one ``mjw.Model`` for all worlds and one ``mjw.Data`` of ``nworld`` worlds, stepped
by ``mjw.step`` on a CUDA device, or on Warp's CPU device where there is none (slow, and its
kernels compile for about a minute the first time; for checking, not for speed). The vector env
selects it with ``backend="warp"`` (``pip install 'softhand[gpu]'``).

What differs from the CPU batch, by design of MJWarp:

* **single precision**: MJWarp computes in float32; its states drift from MuJoCo's float64 ones
  (tests/test_vector_env.py compares the region forces of a few worlds against the CPU batch with
  a tolerance, not bit for bit);
* **one scene**: all worlds share one compiled model (the vector env's worlds with equal keywords:
  other seeds and reset options); worlds of other skins or partner sizes run on the CPU batch;
* **every world steps**: ``mjw.step`` advances all worlds, so a world that must stand still
  (AutoresetMode.DISABLED after its episode, or a diverged world) gets its state back after the
  action period;
* **sensors every step**: the contact sensors are computed on every physics step (the CPU batch
  skips them on all but the last; they do not act on the dynamics);
* **divergence**: MJWarp neither warns nor resets a bad state, so a world diverged when its state
  is not finite after the action period.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np

from softhand.envs.physics import Divergence, SensorLayout

__all__ = ["STATE_FIELDS", "WarpPhysics", "warp_available"]

#: The fields of a world's state that a world standing still gets back after an action period.
STATE_FIELDS = ("time", "qpos", "qvel", "act", "qacc_warmstart", "ctrl", "mocap_pos",
                "mocap_quat")
#: Contacts per world and constraint rows per world that mjw.Data holds (the handshake peaks at
#: about 60 contacts, 4 rows each with elliptic cones, plus joint limits and couplings).
NCONMAX, NJMAX = 256, 1536


def warp_available() -> str | None:
    """None when MuJoCo Warp can run here, else why not (one line)."""
    try:
        import mujoco_warp  # noqa: F401
        import warp  # noqa: F401
    except ImportError as exc:
        return (f"MuJoCo Warp is not installed ({exc.name}): pip install 'softhand[gpu]'")
    return None


class WarpPhysics:
    """W scenes' physics on MuJoCo Warp, ``frame_skip`` steps per action.

    Args:
        models: one compiled scene per world; all the same model object.
        frame_skip, region_sensors, feel_sensors, mocap_body, bone_sensors: as
            `BatchPhysics`.
        device: the Warp device ("cuda:0", "cpu"; default: Warp's default, a GPU where there is
            one).

    Raises:
        ValueError: worlds of different models, or MuJoCo Warp missing (its install line).
    """

    def __init__(self, models: Sequence[mujoco.MjModel], frame_skip: int,
                 region_sensors: list[str], feel_sensors: list[str], mocap_body: str,
                 bone_sensors: list[tuple[str, ...]] | None = None,
                 device: str | None = None) -> None:
        why = warp_available()
        if why is not None:
            raise ValueError(f"backend 'warp': {why}")
        import mujoco_warp as mjw
        import warp as wp

        if not models or any(m is not models[0] for m in models):
            raise ValueError("backend 'warp' runs worlds of one scene (equal HandshakeEnv "
                             "keywords: other seeds and reset options); worlds of other skins or "
                             "partner sizes run on backend 'cpu'")
        wp.config.quiet = True
        self.wp, self.mjw = wp, mjw
        self.model = m = models[0]
        self.num_worlds = len(models)
        self.frame_skip = int(frame_skip)
        self.device = wp.get_device(device)
        self.layout = SensorLayout(m, region_sensors, feel_sensors, bone_sensors)
        self._mocap = int(m.body(mocap_body).mocapid[0])
        self._timestep = float(m.opt.timestep)
        with wp.ScopedDevice(self.device):
            self.mw = mjw.put_model(m)
            d0 = mujoco.MjData(m)
            mujoco.mj_forward(m, d0)
            self.dw = mjw.put_data(m, d0, nworld=self.num_worlds, nconmax=NCONMAX, njmax=NJMAX)
        self.scratch = mujoco.MjData(m)
        self.ctrl = np.zeros((self.num_worlds, m.nu))
        self._pull()
        self.divergence: list[Divergence | None] = [None] * self.num_worlds

    # --- host copies -----------------------------------------------------------------------------
    def _pull(self) -> None:
        """Host copies of what the env reads after a step (one transfer per field)."""
        dw = self.dw
        self._time = dw.time.numpy().astype(float)
        self._qpos = dw.qpos.numpy().astype(float)
        self._qvel = dw.qvel.numpy().astype(float)
        self._sensordata = dw.sensordata.numpy().astype(float)
        self._contacts = None  # pulled when first asked for (contacts_above)

    def _state(self) -> dict[str, np.ndarray]:
        """Host copies of the state fields (copies: on Warp's CPU device ``numpy()`` is a view
        of the live array, which the next step would overwrite)."""
        return {f: getattr(self.dw, f).numpy().copy() for f in STATE_FIELDS}

    def _restore(self, saved: dict[str, np.ndarray], worlds: np.ndarray) -> None:
        """Give ``worlds`` (indices) their ``saved`` state back."""
        if worlds.size:
            for f in STATE_FIELDS:
                now = getattr(self.dw, f).numpy()
                now[worlds] = saved[f][worlds]
                getattr(self.dw, f).assign(now)

    # --- state -------------------------------------------------------------------------------------
    @property
    def time(self) -> np.ndarray:
        return self._time.copy()

    def qpos(self, index: np.ndarray) -> np.ndarray:
        return np.take_along_axis(self._qpos, np.asarray(index), axis=1)

    def qvel(self, index: np.ndarray) -> np.ndarray:
        return np.take_along_axis(self._qvel, np.asarray(index), axis=1)

    def set_ctrl(self, index: np.ndarray, values: np.ndarray) -> None:
        np.put_along_axis(self.ctrl, np.asarray(index), values, axis=1)

    def data(self, world: int) -> mujoco.MjData:
        """World ``world``'s state as a MuJoCo MjData (a scratch copy, overwritten next call)."""
        self.mjw.get_data_into(self.scratch, self.model, self.dw, int(world))
        return self.scratch

    # --- episode -----------------------------------------------------------------------------------
    def reset(self, worlds: Sequence[int], mount_pos: np.ndarray, mount_quat: np.ndarray,
              presets: Sequence[tuple[tuple[int, int, float], ...]]) -> None:
        """As BatchPhysics.reset: MuJoCo's reset of ``worlds``, mounts placed, presets set, then
        the forward dynamics (the other worlds keep their state)."""
        wp, mjw, dw = self.wp, self.mjw, self.dw
        worlds = np.asarray(worlds, int)
        saved = self._state()
        mask = np.zeros(self.num_worlds, bool)
        mask[worlds] = True
        with wp.ScopedDevice(self.device):
            mjw.reset_data(self.mw, dw, reset=wp.array(mask, dtype=bool))
            state = self._state()
            for k, w in enumerate(worlds):
                state["mocap_pos"][w, self._mocap] = mount_pos[k]
                state["mocap_quat"][w, self._mocap] = mount_quat[k]
                for qadr, aadr, value in presets[k]:
                    state["qpos"][w, qadr] = value
                    if aadr >= 0:
                        state["act"][w, aadr] = value
            for f in STATE_FIELDS:
                getattr(dw, f).assign(state[f])
            mjw.forward(self.mw, dw)
            self._restore(saved, np.flatnonzero(~mask))
        self.ctrl[worlds] = state["ctrl"][worlds]
        for w in worlds:
            self.divergence[w] = None
        self._pull()

    def advance(self, live: np.ndarray, mount_paths: np.ndarray) -> list[Divergence | None]:
        """As BatchPhysics.advance; the worlds not ``live`` get their state back afterwards."""
        wp, mjw, dw = self.wp, self.mjw, self.dw
        live = np.asarray(live, bool)
        saved = self._state() if not live.all() else None
        self.divergence = [None] * self.num_worlds
        with wp.ScopedDevice(self.device):
            dw.ctrl.assign(self.ctrl.astype(np.float32))
            mocap = dw.mocap_pos.numpy()
            for i in range(self.frame_skip):
                mocap[:, self._mocap] = mount_paths[:, i]
                dw.mocap_pos.assign(mocap)
                mjw.step(self.mw, dw)
            if saved is not None:
                self._restore(saved, np.flatnonzero(~live))
        self._pull()
        for w in np.flatnonzero(live):
            if not math.isfinite(self._qpos[w].sum() + self._qvel[w].sum()):
                self.divergence[w] = Divergence(
                    float(self._time[w]) - self.frame_skip * self._timestep,
                    "the state is not finite (MuJoCo Warp)")
        return list(self.divergence)

    # --- read-out ----------------------------------------------------------------------------------
    def region_forces(self) -> tuple[np.ndarray, np.ndarray]:
        return self.layout.region_forces(self._sensordata)

    def saturated_sensors(self) -> np.ndarray:
        return self.layout.saturated(self._sensordata)

    def partner_feel(self) -> np.ndarray:
        return self.layout.feel(self._sensordata)

    def contacts_above(self, world: int, limits: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World ``world``'s contacts beyond ``limits`` (MujocoPhysics.contacts_above), from the
        contact arrays of all worlds, pulled once per action period."""
        if self._contacts is None:
            dw = self.dw
            n = min(int(dw.nacon.numpy()[0]), dw.contact.geom.shape[0])
            self._contacts = (dw.contact.geom.numpy()[:n], dw.contact.efc_address.numpy()[:n, 0],
                              dw.contact.worldid.numpy()[:n], dw.efc.force.numpy())
        geom, adr, wid, force = self._contacts
        mine = (wid == world) & (adr >= 0)
        g, f = geom[mine].astype(int), force[world, adr[mine]].astype(float)
        top = limits[g[:, 0], g[:, 1]]
        over = f > top
        return g[over], f[over], top[over]
