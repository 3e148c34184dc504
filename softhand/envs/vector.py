"""``softhand/Handshake-v0`` as a Gymnasium vector env: W handshakes stepped together.

``gymnasium.make_vec("softhand/Handshake-v0", num_envs=W, vectorization_mode="vector_entry_point")``
returns a `HandshakeVectorEnv`. Its worlds may differ: ``worlds`` gives per-world
keywords of `HandshakeEnv` over the shared ones (other partners,
skins, hands, reward weights), and each reset takes a seed and options per world.

How it is built (one place for each concept):

* each world's setup is a `HandshakeEnv` (its arguments checked, its scene compiled, its
  laws, sensors, grasp, preset and range bookkeeping), whose own physics is never stepped;
* the physics of all worlds is one `BatchPhysics` (``mujoco.batch``,
  threads with the GIL released, bit-identical to each world stepped alone);
* the partner's script and grip regulator, the relaxed sensored hand, the phases and the reward
  are `HandshakeWorlds`, over arrays of worlds, which
  the single env runs with one world;
* the embedded sensors are one `SensorChain` of all worlds
  (`SensorChain.stack`: each world's laws' states, noise stream and sampling clock, stepped
  together; the single env's chain is one world of it);
* the range check reads each world's contacts from its batch data and counts them with the
  world's env (``_check_range``), so the episode's summary and its ``CalibratedRangeWarning``
  are those of a single env.

Spaces: ``single_action_space`` and ``single_observation_space`` are the single env's
(HandshakeEnv's docstring); ``action_space`` and ``observation_space`` stack W of them.

Steps: ``step(actions)`` takes (W, 6) actions and returns (W, obs) observations and (W,)
rewards, terminations and truncations, and ``info``, a dict of arrays with a leading world axis:
``region_forces_N``, ``sensor_readings_N``, ``sensor_load_estimate_N``, ``region_bone_N``
(W, 18; regions in ``region_names`` order), ``phase`` (W,) names, ``reward_terms`` (term ->
(W,)), ``time_s``, ``saturated_sensors``, ``thumb_rotation_rad``, ``contacts_beyond_range``,
``partner_grip_N``, ``partner_grip_measured_N``, ``partner_effort_rad``,
``grasp_thumb_rotation_rad`` (W,), ``unstable`` (W,) False or the divergence's text, and for the
worlds whose episode ended at this step ``beyond_range_summary`` (W,) (None elsewhere): the same
values as a single env's info, in arrays. Each number equals that of a single env with the
world's keywords, seed and options (to 1e-9 N; tests/test_vector_env.py).

Autoreset (``autoreset_mode``): ``AutoresetMode.SAME_STEP`` (default): a world whose episode
ended (truncated at its end, or terminated by a divergence, reward -100 and a zero observation as
the single env) is reset within the same step, unseeded (its random stream continues, as a single
env's reset without a seed); the step returns its first observation, and ``info["final_obs"]`` /
``info["final_info"]`` (with the masks ``_final_obs``, ``_final_info``) hold the ended episode's
last observation and its world's info. ``AutoresetMode.DISABLED``: a world whose episode ended
stands still (reward 0, not stepped) until ``reset(options={"reset_mask": mask})`` starts it
again (a population runs each partner's one episode so). A diverged world is reported in
``info["unstable"]`` and never stepped on.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from softhand.envs.batch import BatchPhysics
from softhand.envs.handshake import HandshakeEnv
from softhand.envs.partner import PHASES, check_reset_options
from softhand.envs.scenarios.handshake import HandshakeWorlds
from softhand.envs.spaces import region_values
from softhand.envs.touch import mount_path
from softhand.sensors.device import SensorChain
from softhand.validate import show

__all__ = ["HandshakeVectorEnv"]


def _world_envs(kwargs: list[dict]) -> list[HandshakeEnv]:
    """A single env per world; worlds with equal keywords share the first one's scene, laws and
    calibration (read-only here) and get their own scenario, sensors, range counts and random
    stream (what a world changes), instead of building the scene again (about 1.5 s each)."""
    envs: list[HandshakeEnv] = []
    built: dict[str, HandshakeEnv] = {}
    for kw in kwargs:
        key = repr(sorted(kw.items()))
        if key not in built:
            built[key] = HandshakeEnv(**kw)
            envs.append(built[key])
            continue
        env = copy.copy(built[key])  # its physics is never stepped: sharing it is harmless
        env.scenario = copy.deepcopy(env.scenario)
        env.sensors = copy.deepcopy(env.sensors)
        env._np_random, env._np_random_seed = None, None
        env._reset_range_counts()
        envs.append(env)
    return envs


def _world_seeds(seed, n: int) -> list[int | None]:
    """A seed per world: None, an integer (world i gets seed + i, as Gymnasium's vector envs),
    or a sequence of n seeds (each None or an integer >= 0)."""
    if seed is None:
        return [None] * n
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
        if seed < 0:
            raise ValueError(f"seed = {seed}: expected None, an integer >= 0 or {n} of them")
        return [int(seed) + i for i in range(n)]
    seeds = list(seed)
    if len(seeds) != n:
        raise ValueError(f"seed = {show(seed)}: expected {n} seeds (one per world), got "
                         f"{len(seeds)}")
    return seeds


def _world_options(options: Mapping | None, n: int) -> list[dict]:
    """reset()'s options per world: each key's value a number (every world) or n numbers."""
    if options is None:
        return [{} for _ in range(n)]
    if not isinstance(options, Mapping):
        raise ValueError(f"options = {show(options)}: expected None or a mapping of option -> a "
                         f"number or {n} numbers")
    out: list[dict] = [{} for _ in range(n)]
    for key, value in options.items():
        values = list(value) if isinstance(value, (Sequence, np.ndarray)) else [value] * n
        if len(values) != n:
            raise ValueError(f"options[{key!r}]: expected a number or {n} numbers (one per "
                             f"world), got {len(values)}")
        for i, v in enumerate(values):
            out[i][key] = v
    return [check_reset_options(o) for o in out]


#: memory of one world (bytes): the scene's MjData (its arena and buffer, 17 MB) with its
#: sensors and partner script
WORLD_BYTES = 20e6


def _max_worlds() -> int:
    """The most worlds one vector env holds on this machine: 80 % of its memory (4096 at most)."""
    try:
        memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # not POSIX: the cap alone
        return 4096
    return max(1, min(4096, int(0.8 * memory / WORLD_BYTES)))


MAX_WORLDS = _max_worlds()
#: the most threads of a mujoco.batch (more than the CPUs only queue)
MAX_THREADS = max(1, 4 * (os.cpu_count() or 1))


class HandshakeVectorEnv(VectorEnv):
    """W handshakes between the prosthetic hand and scripted partners, stepped together (module
    docstring).

    Args:
        num_envs: the number of worlds W (>= 1).
        worlds: per world, a mapping of HandshakeEnv keywords over ``env_kwargs`` (length
            ``num_envs``; e.g. ``{"partner_size": (180, 85)}``, ``{"design": "solid-pu"}``).
        nthread: threads of each mujoco.batch Batch (default: the CPUs this process may use).
        backend: ``"cpu"`` (default: ``mujoco.batch``, softhand.envs.batch) or ``"warp"``
            (MuJoCo Warp on a GPU, float32, worlds of one scene: softhand.envs.warp).
        device: with ``backend="warp"``, the Warp device ("cuda:0", "cpu"; default: a GPU where
            there is one).
        autoreset_mode: ``AutoresetMode.SAME_STEP`` or ``DISABLED`` (module docstring).
        envs: the worlds as single envs built already (instead of ``num_envs``, ``worlds`` and
            ``env_kwargs``): their scenes, laws and sensors; their own physics is not stepped.
        **env_kwargs: HandshakeEnv keywords of every world.

    Raises:
        ValueError: a bad ``num_envs`` or ``worlds``, a bad keyword of any world (the single env's
            message), or worlds whose action periods or observations differ.
    """

    metadata: ClassVar[dict] = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, num_envs: int = 1, *, worlds: Sequence[Mapping[str, Any]] | None = None,
                 nthread: int | None = None, backend: str = "cpu", device: str | None = None,
                 autoreset_mode: AutoresetMode = AutoresetMode.SAME_STEP,
                 envs: Sequence[HandshakeEnv] | None = None, **env_kwargs) -> None:
        if envs is not None:  # worlds built already (e.g. each under its own warnings record)
            if not envs or not all(isinstance(e, HandshakeEnv) for e in envs):
                raise ValueError(f"envs = {show(envs)}: expected HandshakeEnv worlds")
            num_envs = len(envs)
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) \
                or num_envs < 1:
            raise ValueError(f"num_envs = {show(num_envs)}: expected an integer >= 1")
        if num_envs > MAX_WORLDS:
            raise ValueError(f"num_envs = {show(num_envs)}: allowed 1-{MAX_WORLDS} on this "
                             f"machine (each world holds its own MjData, sensors and partner, "
                             f"about {WORLD_BYTES / 1e6:.0f} MB; 80 % of the memory); run more "
                             "as a population batch or on other machines (--cluster)")
        if nthread is not None and (isinstance(nthread, bool)
                                    or not isinstance(nthread, (int, np.integer))
                                    or not 1 <= nthread <= MAX_THREADS):
            raise ValueError(f"nthread = {show(nthread)}: allowed an integer 1-{MAX_THREADS} "
                             f"(this machine has {os.cpu_count()} CPUs), or None for the CPUs "
                             "this process may use")
        if device is not None and backend != "warp":
            raise ValueError(f"device = {show(device)} with backend = {show(backend)}: a device "
                             "is MuJoCo Warp's (backend = 'warp'); the cpu backend takes none")
        n = self.num_envs = int(num_envs)
        if worlds is not None and (isinstance(worlds, (str, Mapping)) or len(worlds) != n):
            raise ValueError(f"worlds = {show(worlds)}: expected {n} mappings of HandshakeEnv "
                             "keywords, one per world")
        if backend not in ("cpu", "warp"):
            raise ValueError(f"backend = {show(backend)}: allowed 'cpu' (mujoco.batch) or 'warp' "
                             "(MuJoCo Warp)")
        modes = (AutoresetMode.SAME_STEP, AutoresetMode.DISABLED)
        if autoreset_mode not in modes:
            raise ValueError(f"autoreset_mode = {show(autoreset_mode)}: allowed "
                             f"{', '.join(str(m) for m in modes)}")
        self.metadata = {**self.metadata, "autoreset_mode": autoreset_mode}
        #: each world's setup: a single env (checked arguments, scene, laws, sensors, grasp)
        self.envs = list(envs) if envs is not None else _world_envs(
            [{**env_kwargs, **dict(w)} for w in (worlds or [{}] * n)])
        first = self.envs[0]
        for i, e in enumerate(self.envs):
            if e.frame_skip * e.model.opt.timestep != first.frame_skip * first.model.opt.timestep \
                    or e.frame_skip != first.frame_skip:
                raise ValueError(f"world {i}: frame_skip {e.frame_skip} x timestep "
                                 f"{e.model.opt.timestep:g} s differs from world 0's "
                                 f"({first.frame_skip} x {first.model.opt.timestep:g} s): the "
                                 "worlds of a vector env share their action period")
            mine, theirs = e.observation_names, first.observation_names
            if mine != theirs:
                k = next((k for k, (a, b) in enumerate(zip(mine, theirs, strict=False))
                          if a != b),
                         min(len(mine), len(theirs)))
                raise ValueError(
                    f"world {i}: observation of {len(mine)} entries differs from world 0's "
                    f"({len(theirs)}) at entry {k}: {mine[k] if k < len(mine) else None!r} "
                    f"against {theirs[k] if k < len(theirs) else None!r} (observe, hand, "
                    "representation): the worlds of a vector env share their observation")
        self.region_names = first.region_names
        self.frame_skip = first.frame_skip
        self.single_action_space = first.action_space
        self.single_observation_space = first.observation_space
        #: the name and unit of each entry of a world's action and observation (the single env's)
        self.single_action_names = first.action_names
        self.single_observation_names = first.observation_names
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(self.single_observation_space, n)
        #: the worlds' physics, one mujoco.batch per model layout (softhand.envs.batch)
        models = [e.model for e in self.envs]
        if backend == "warp":
            from softhand.envs.warp import WarpPhysics

            self.physics = WarpPhysics(models, self.frame_skip, **first.physics_reads,
                                       device=device)
        else:
            self.physics = BatchPhysics(models, self.frame_skip, **first.physics_reads,
                                        nthread=nthread)
        self._pro_qpos = np.array([e._pro_qpos for e in self.envs])
        self._pro_dof = np.array([e._pro_dof for e in self.envs])
        self._pro_act = np.array([e._pro_act for e in self.envs])
        self._servos = np.array([e.partner_servos for e in self.envs])
        self._max_speed = np.array([e._max_speed for e in self.envs])
        self._human = np.array([e.hand == "human" for e in self.envs])
        self._thumb = np.array([[e.thumb_rotation_qpos] for e in self.envs])
        # the partner's grip acts once per action period (the first world's, as the single env)
        self._action_period_s = float(first.model.opt.timestep) * self.frame_skip
        self._duration = np.ones(n)
        self._step_index = np.zeros(n, int)
        self._mounts: list[np.ndarray] = [np.zeros((1, 3))] * n
        self._forces = np.zeros((n, len(self.region_names)))
        self._bone = np.zeros_like(self._forces)
        self._readings = np.zeros_like(self._forces)
        self._estimate = np.zeros_like(self._forces)
        self._saturated = np.zeros(n, int)
        #: the worlds' embedded sensors, one chain (each world's laws, noise and clock)
        self._sensors = SensorChain.stack([e.sensors for e in self.envs])
        self._worlds: HandshakeWorlds | None = None
        #: worlds whose episode ended and that wait for a reset (AutoresetMode.DISABLED)
        self._ended = np.zeros(n, bool)
        self._closed = False

    # --- gymnasium API -------------------------------------------------------------------------
    def reset(self, *, seed=None, options: Mapping | None = None):
        """Start every world's episode; ``seed`` None, an integer (world i: seed + i) or one
        per world; ``options`` maps each reset option (HandshakeEnv.reset) to a number or one
        per world, and ``reset_mask`` (W,) to the worlds to reset (default all; Gymnasium's
        convention, for AutoresetMode.DISABLED). Returns (W, obs) and the info arrays."""
        self._check_open()
        n = self.num_envs
        options = dict(options or {})
        mask = np.ones(n, bool)
        if "reset_mask" in options:
            mask = np.asarray(options.pop("reset_mask"))
            if mask.shape != (n,) or mask.dtype != bool:
                raise ValueError(f"options['reset_mask'] = {show(mask)}: expected {n} booleans")
            if self._worlds is None and not mask.all():
                raise ValueError("options['reset_mask']: the first reset() starts every world")
        seeds = _world_seeds(seed, n)
        opts = _world_options(options, n)
        ids = np.flatnonzero(mask)
        self._reset_worlds(ids, [seeds[i] for i in ids], [opts[i] for i in ids])
        self._ended[ids] = False
        return self._obs(), self._info(self._terms(np.zeros((n, 6))))

    def step(self, actions):
        """One action period of every world (module docstring)."""
        self._check_open()
        if self._worlds is None:
            raise RuntimeError("call reset() before step()")
        n = self.num_envs
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != (n, 6) or not (a.min() >= -1.0 - 1e-6 and a.max() <= 1.0 + 1e-6):
            raise ValueError(f"actions of shape {a.shape}: expected ({n}, 6) finite values in "
                             "[-1, 1], one row per world")
        phys, worlds = self.physics, self._worlds
        t = phys.time
        ctrl = a * self._max_speed
        if self._human.any():  # the relaxed hands follow the scenario; their actions are unused
            ctrl = np.where(self._human[:, None], worlds.sensored_targets(t), ctrl)
        phys.set_ctrl(self._pro_act, ctrl)
        # the partner's digits act once per action step, the arm every step
        targets = worlds.partner_targets(t, phys.partner_feel(), self._action_period_s)
        phys.set_ctrl(self._servos, targets)
        paths = np.empty((n, self.frame_skip, 3))
        for w in range(n):
            k, mount = self._step_index[w], self._mounts[w]
            end = k + self.frame_skip
            paths[w] = mount[k:end] if end <= len(mount) else \
                mount[np.minimum(np.arange(k, end), len(mount) - 1)]
        live = ~self._ended  # worlds waiting for a reset (AutoresetMode.DISABLED) stand still
        diverged = phys.advance(live, paths)
        self._step_index[live] += self.frame_skip
        unstable = np.array([d is not None for d in diverged])
        forces, bone = phys.region_forces()
        saturated = phys.saturated_sensors()
        now = phys.time
        ok = live & ~unstable  # a diverged world keeps its last good values
        self._forces[ok], self._bone[ok], self._saturated[ok] = forces[ok], bone[ok], saturated[ok]
        readings = self._sensors.step(forces, worlds=ok)
        self._readings[ok] = readings[ok]
        self._estimate[ok] = self._sensors.estimates[ok]
        for w in np.flatnonzero(ok):
            env = self.envs[w]
            env._bone = bone[w]
            env._check_range(*phys.contacts_above(int(w), env._range), float(now[w]))
            env._check_overload(self._forces[w], bone[w], float(now[w]))
        time_s = np.array([d.time_s if d is not None else now[w]
                           for w, d in enumerate(diverged)])
        terms = self._terms(a, time_s)
        reward = np.where(unstable, -100.0, np.where(live, sum(terms.values()), 0.0))
        truncated = (now >= self._duration - 1e-9) & ~unstable & live
        info = self._info(terms, time_s)
        info["unstable"] = np.array([str(d) if d is not None else False for d in diverged],
                                    dtype=object)
        obs = self._obs()
        obs[unstable] = 0.0
        ended = unstable | truncated
        if ended.any():
            summaries = np.full(n, None, dtype=object)
            for w in np.flatnonzero(ended):
                env = self.envs[w]
                summaries[w] = env._range_summary(float(time_s[w]))
                env._warn_range(summaries[w], "ended")
            info["beyond_range_summary"] = summaries
            info["_beyond_range_summary"] = ended.copy()
            info["final_obs"] = np.where(ended[:, None], obs, 0.0)
            info["_final_obs"] = ended.copy()
            info["final_info"] = {k: v for k, v in info.items() if not k.startswith(("final",
                                                                                      "_final"))}
            info["_final_info"] = ended.copy()
            if self.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP:
                ids = np.flatnonzero(ended)
                self._reset_worlds(ids, [None] * ids.size, [{} for _ in ids])
                fresh = self._obs()
                obs[ended] = fresh[ended]
            else:
                self._ended |= ended
        return obs, reward, unstable, truncated, info

    def close(self, **kwargs) -> None:
        if getattr(self, "_closed", True):
            return
        self._closed = True
        for e in self.envs:
            e.close()

    # --- helpers -------------------------------------------------------------------------------
    def _check_open(self) -> None:
        if self._closed:
            raise RuntimeError("the vector env is closed (close() was called): make a new one")

    def _reset_worlds(self, ids: np.ndarray, seeds: list, options: list[dict]) -> None:
        """Plan the episodes of worlds ``ids`` as their single envs' reset does, and reset their
        physics."""
        starts, quats, presets = [], [], []
        for w, seed, opts in zip(ids, seeds, options, strict=True):
            env = self.envs[w]
            if seed is not None or env._np_random is None:
                gym.Env.reset(env, seed=seed)  # gymnasium's seeding, as the single env's reset
            rng = env.np_random
            start, quat = env.scenario.reset(env, rng, opts)
            dt = env.model.opt.timestep
            self._mounts[w] = mount_path(env.scenario, dt, env.frame_skip)
            self._duration[w] = env.scenario.duration_s
            self._step_index[w] = 0
            self._sensors.reset(np.random.default_rng(int(rng.integers(2**63))), int(w))
            self._readings[w] = self._sensors.readings[w]
            self._estimate[w] = self._sensors.estimates[w]
            self._forces[w] = self._bone[w] = 0.0
            self._saturated[w] = 0
            env._bone = self._bone[w]
            env._reset_range_counts()
            starts.append(start)
            quats.append(quat)
            presets.append(env._preset)
        self.physics.reset(ids, np.array(starts), np.array(quats), presets)
        if self._worlds is None or len(ids) == self.num_envs:
            self._worlds = HandshakeWorlds([e.scenario for e in self.envs])
        else:
            for w in ids:
                self._worlds.set_world(int(w), self.envs[w].scenario)

    def _terms(self, action: np.ndarray, time_s: np.ndarray | None = None
               ) -> dict[str, np.ndarray]:
        t = self.physics.time if time_s is None else time_s
        self._phase = self._worlds.phase_index(t)
        return self._worlds.reward_terms(self._forces, action, self._phase)

    def _obs(self) -> np.ndarray:
        e = self.envs[0]
        n = self._pro_qpos.shape[1]
        obs = np.empty((self.num_envs, e._n_obs))
        obs[:, :n] = self.physics.qpos(self._pro_qpos)
        obs[:, n:2 * n] = self.physics.qvel(self._pro_dof)
        obs[:, 2 * n:-1] = region_values(e.observe, {
            "sensor_patch": self._readings, "region_load": self._forces,
            "load_estimate": self._estimate})
        obs[:, -1] = self.physics.time / self._duration
        return obs

    def _info(self, terms: dict[str, np.ndarray],
              time_s: np.ndarray | None = None) -> dict[str, Any]:
        script = self._worlds.script
        return {"region_forces_N": self._forces.copy(),
                "sensor_readings_N": self._readings.copy(),
                "sensor_load_estimate_N": self._estimate.copy(),
                "phase": np.array([PHASES[i] for i in self._phase], dtype=object),
                "reward_terms": terms,
                "time_s": self.physics.time if time_s is None else time_s,
                "saturated_sensors": self._saturated.copy(),
                "thumb_rotation_rad": self.physics.qpos(self._thumb)[:, 0],
                "contacts_beyond_range": np.array([e._beyond + e._bottomed
                                                   for e in self.envs]),
                "pairs_beyond_range_N": np.array([dict(e._beyond_N) for e in self.envs],
                                                 dtype=object),
                "region_bone_N": self._bone.copy(),
                "overload_started": np.array([dict(e._overload_started) for e in self.envs],
                                             dtype=object),
                "partner_grip_N": script.grip_forces_N.copy(),
                "partner_grip_measured_N": self._worlds.grip_measured_N.copy(),
                "partner_effort_rad": script.efforts.copy(),
                "grasp_thumb_rotation_rad": np.array([e.scenario.thumb_rotation_rad
                                                      for e in self.envs]),
                "unstable": np.full(self.num_envs, False, dtype=object)}
