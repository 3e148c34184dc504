"""The two-hand touch env: a sensored hand with calibrated skins and a scripted human partner, one
social touch at a time (a `Scenario`).

`TwoHandTouchEnv` owns what every touch shares: both hands and their skins, the embedded
sensors, the physics behind `MujocoPhysics`, the prosthetic's
action, the observation, the contacts' calibrated ranges and the per-region forces. The touch
itself (the partner's plan, its phases, the reward) is the scenario's.
``softhand.envs.handshake.HandshakeEnv`` is this env with the handshake scenario; its docstring
is the specification of the action, observation and ``info`` that every touch shares.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces

from softhand.compiled import count_above, within
from softhand.envs.models import skinned_scene_spec
from softhand.envs.partner import check_partner_size, check_reset_options
from softhand.envs.physics import MujocoPhysics
from softhand.envs.picture import (
    RENDER_VIEW,
    CameraView,
    ScenePicture,
    check_size,
    posed_data,
    region_colours,
    skin_forces,
)
from softhand.envs.scenario import Scenario
from softhand.envs.sensing import parse_placements, region_laws
from softhand.envs.skins import (
    CalibratedRangeWarning,
    check_contact_laws,
    check_pad_timestep,
    pair_choices,
    parse_skins,
    series_law,
    skin_of_pair,
)
from softhand.envs.spaces import OBSERVE, action_names, observation_names, region_values
from softhand.hands import SceneConfig, partner_actuators, prosthetic_actuators, regions
from softhand.hands.config import (
    TIMESTEP_RANGE_S,
    ArmConfig,
    HandConfig,
    PartnerConfig,
    ProstheticConfig,
)
from softhand.hands.partner import PARTNER_JOINTS
from softhand.hands.prosthetic import paper_regions
from softhand.laws.references import HUMAN
from softhand.sensors.device import FLEXIFORCE_A101, SensorChain, SensorSpec
from softhand.skin.files import SKINS_DIR, shipped_skins
from softhand.validate import check_number, check_path, show
from softhand.warn import warn_at_caller

__all__ = ["ACTION_PERIOD_S", "DEFAULT_TIMESTEP_S", "HANDS", "MAX_ACTION_PERIOD_S",
           "RENDER_MODES", "TwoHandTouchEnv", "default_frame_skip"]

ACTION_PERIOD_S = 0.01  # default action period: 100 Hz
MAX_ACTION_PERIOD_S = 0.1  # slowest action rate allowed (10 Hz): frame_skip x timestep_s


def mount_path(scenario: Scenario, dt: float, frame_skip: int) -> np.ndarray:
    """The partner's mount at every physics step of the planned episode (a scripted arm: no
    feedback from the contacts), one action period past its end; shape (steps, 3)."""
    n_steps = int(np.ceil(scenario.duration_s / dt)) + frame_skip
    return scenario.mount_path(np.arange(n_steps) * dt)


def _span(index: np.ndarray) -> slice | np.ndarray:
    """``index`` as a slice when its entries are consecutive (the same entries), else as is."""
    index = np.asarray(index)
    if index.size and np.array_equal(index, np.arange(index[0], index[0] + index.size)):
        return slice(int(index[0]), int(index[0]) + index.size)
    return index


def default_frame_skip(timestep_s: float) -> int:
    """Physics steps per action by default: the most that fit in ``ACTION_PERIOD_S`` (at least 1).

    Floor, not round: 2.75 ms rounded to 4 steps made an 11 ms env step, coarser than the
    embedded sensors' default 10 ms sampling period, and the env refused its own defaults."""
    return max(1, int(ACTION_PERIOD_S / timestep_s + 1e-9))
DEFAULT_TIMESTEP_S = SceneConfig.timestep_s
#: The sensored hand: the prosthetic hand (default, its 6 motors driven by the action), or the
#: paper's experimenter's relaxed human hand (human tissue on every region, soft joint
#: impedance, a neutral grip that waits for the partner; the action is not used).
HANDS = ("prosthetic", "human")
#: Gymnasium render modes: an (H, W, 3) uint8 picture of the state, ``softhand render``'s.
RENDER_MODES = ("rgb_array",)


def _check_placements_honoured(asked: str | Mapping[str, str] | None,
                               placements: Mapping[str, str], used: Mapping[str, str],
                               skins: Mapping[str, str]) -> None:
    """A sensor placement is honoured or refused, never ignored: a skin without an FE model
    (human tissue, rigid, the commercial 102L) has its sensor on the surface, so a placement
    asked for such a region (or, asked for every region, honoured by none) is a ValueError."""
    if asked is None:
        return
    regions = list(asked) if isinstance(asked, Mapping) else list(placements)
    refused = [r for r in regions if used[r] != placements[r]]
    if refused and (isinstance(asked, Mapping) or len(refused) == len(regions)):
        r = refused[0]
        raise ValueError(f"sensor placement {placements[r]!r} for region {r}: its skin "
                         f"{skins[r]} has no FE model of an embedded sensor, so its sensor reads "
                         "the surface (the paper's pads on the human hand): leave the placement "
                         "out for it")


class TwoHandTouchEnv(gym.Env):
    """A sensored hand touched by a scripted human partner, in the way ``scenario`` scripts.

    Args: see ``softhand.envs.handshake.HandshakeEnv`` (all but the scenario's own); ``scenario``
    is the touch (a `Scenario`).
    """

    metadata: ClassVar[dict] = {"render_modes": list(RENDER_MODES), "render_fps": 100}

    def __init__(self, *, scenario: Scenario, design: str | None = None,
                 skins: Mapping[str, str] | None = None, representation: str | None = None,
                 frame_skip: int | None = None, timestep_s: float = DEFAULT_TIMESTEP_S,
                 calibration_dir: str | Path | None = None, sensor: SensorSpec | None = None,
                 sensor_placement: str | Mapping[str, str] | None = None,
                 observe: str = "sensor", sensor_dir: str | Path | None = None,
                 partner_size: tuple[float, float] | None = None,
                 hand: str = "prosthetic", contact_laws: str = "geometry",
                 render_mode: str | None = None, render_size: tuple[int, int] = (640, 480),
                 render_view: CameraView | None = None, sensored_arm: ArmConfig | None = None,
                 partner_arm: ArmConfig | None = None) -> None:
        # every argument (and every calibration file used) is checked before any work is done
        if not isinstance(scenario, Scenario):
            raise ValueError(f"scenario = {show(scenario)}: expected a softhand.envs.scenario."
                             "Scenario")
        if not isinstance(observe, str) or observe not in OBSERVE:
            raise ValueError(f"observe = {show(observe)}: allowed {', '.join(OBSERVE)}")
        self._check_render(render_mode, render_size, render_view)
        self.scenario = scenario
        self._closed = False
        self._picture: ScenePicture | None = None  # the renderer, made at the first render()
        #: which laws the skin pairs take (softhand.envs.skins.CONTACT_LAWS)
        self.contact_laws = check_contact_laws(contact_laws)
        # folders: None is the shipped one; an empty string is refused, not taken as the default
        if calibration_dir is not None:
            calibration_dir = check_path("calibration_dir", calibration_dir)
        if sensor_dir is not None:
            sensor_dir = check_path("sensor_dir", sensor_dir)
        check_number("timestep_s", timestep_s, lo=TIMESTEP_RANGE_S[0], hi=TIMESTEP_RANGE_S[1],
                     why="s (skins calibrated at 0.0005-0.002 s)")
        self.partner_size_mm = check_partner_size(partner_size)
        partner = PartnerConfig(hand=HandConfig(hand_length_m=self.partner_size_mm[0] / 1e3,
                                                hand_width_m=self.partner_size_mm[1] / 1e3))
        if hand not in HANDS:
            raise ValueError(f"hand = {show(hand)}: allowed {', '.join(HANDS)}")
        self.hand = hand
        prosthetic = ProstheticConfig(actuation="relaxed-human" if hand == "human" else "motors")
        arms = {"sensored_arm": sensored_arm, "partner_arm": partner_arm}
        for key, arm in arms.items():
            if arm is not None and not isinstance(arm, ArmConfig):
                raise ValueError(f"{key} = {show(arm)}: expected None or a softhand.hands."
                                 "ArmConfig (ArmConfig.of('relaxed' | 'prosthesis-user' | "
                                 "'active', ...))")
        self.config = SceneConfig(timestep_s=timestep_s, partner=partner, prosthetic=prosthetic,
                                  **{k: v for k, v in arms.items() if v is not None})
        timestep_s = self.config.timestep_s
        max_skip = int(MAX_ACTION_PERIOD_S / timestep_s + 1e-9)
        if frame_skip is None:
            frame_skip = default_frame_skip(timestep_s)
        check_number("frame_skip", frame_skip, lo=1, hi=max_skip, integer=True,
                     why=f"(frame_skip x timestep_s <= {MAX_ACTION_PERIOD_S:g} s)")
        if hand == "human":
            if design not in (None, HUMAN) or skins or representation not in (None,
                                                                             "soft-contact"):
                raise ValueError(
                    f"hand = 'human' wears human tissue ({HUMAN}, soft contact) on every region; "
                    f"design = {show(design)}, skins = {show(skins)} and representation = "
                    f"{show(representation)} are for hand = 'prosthetic'")
            self.skins = dict.fromkeys(paper_regions(), HUMAN)
            self.representations = dict.fromkeys(paper_regions(), "soft-contact")
        else:
            extra = () if calibration_dir is None else tuple(shipped_skins(calibration_dir))
            self.skins, self.representations = parse_skins(design, skins, representation,
                                                           calibrated=extra)
        self.frame_skip = int(frame_skip)
        self.observe = observe
        # frames per second of a rendered episode: one picture per env step
        self.metadata = {**self.metadata,
                         "render_fps": round(1.0 / (self.frame_skip * timestep_s))}
        spec = FLEXIFORCE_A101 if sensor is None else sensor
        if not isinstance(spec, SensorSpec):
            raise ValueError(f"sensor = {show(sensor)}: expected a SensorSpec")
        placements = parse_placements(tuple(self.skins), sensor_placement)
        laws, self.sensor_placements = region_laws(self.skins, placements, sensor_dir)
        _check_placements_honoured(sensor_placement, placements, self.sensor_placements,
                                   self.skins)
        #: the regions' embedded sensors: transfer laws, then the electronics
        step_s = self.frame_skip * timestep_s
        if sensor is None and spec.period_s < step_s - 1e-9:  # the user chose the step, not this
            raise ValueError(
                f"frame_skip = {self.frame_skip} x timestep_s = {timestep_s:g} s makes an env step "
                f"of {step_s:g} s, longer than the default sensor's sampling period "
                f"{spec.period_s:g} s (the sensor model steps with the env); allowed: frame_skip "
                f"x timestep_s <= {spec.period_s:g} s, or a sensor whose period_s >= {step_s:g} s")
        self.sensors = SensorChain(laws, spec, step_s)
        directory = SKINS_DIR if calibration_dir is None else calibration_dir
        self.calibration_dir = str(directory)  # where the skins' laws came from
        for skin in sorted({*self.skins.values(), "rigid"}):
            series_law(skin, str(directory))  # reads and checks the file (cached)
        # a relaxation pad's spring is explicit: refused where the timestep cannot resolve it
        check_pad_timestep(self.skins, self.representations, timestep_s, directory)
        # the laws are written into the spec, and the model is compiled from the spec's MJCF text,
        # so that models/mjcf/handshake_scene.xml is exactly the simulated model (the XML writer
        # rounds numbers: a model compiled from the spec itself differs in the last digits)
        spec = skinned_scene_spec(self.skins, self.config, representations=self.representations,
                                  contact_laws=self.contact_laws,
                                  directory=directory)
        spec.compile()
        m = mujoco.MjModel.from_xml_string(spec.to_xml())
        self.region_names = tuple(self.skins)
        infos = regions(m, "pro_")
        self.region_geoms = tuple(infos[r].geom for r in self.region_names)
        # what the partner's digits feel (data gloves measure the fingers' and thumb's phalanges),
        # not its palm or thenar: a hard push on the palm must not make the partner open its hand
        feel = [m.sensor(i).name for i in range(m.nsensor)
                if m.sensor(i).name.startswith("hum_feel_")
                and m.sensor(i).name.rsplit("_", 1)[-1] in ("proximal", "middle", "distal")]
        #: the physics, behind the seam a batched backend would implement (envs.physics)
        #: what the physics reads (region, feel and bone sensors; the partner's mount), as
        #: MujocoPhysics' arguments: a batched backend reads the same (softhand.envs.batch)
        self.physics_reads = {"region_sensors": [infos[r].sensor for r in self.region_names],
                              "feel_sensors": feel, "mocap_body": "hum_base",
                              "bone_sensors": [infos[r].bone_sensors for r in self.region_names]}
        self.physics = MujocoPhysics(m, self.frame_skip, **self.physics_reads)
        self.model, self.data = m, self.physics.data
        # the sensored hand's joints (its arm's free joint is the arm's state, not the hand's)
        self._pro_joints = np.array([j for j in range(m.njnt) if m.joint(j).name.startswith("pro_")
                                     and m.jnt_type[j] != mujoco.mjtJoint.mjJNT_FREE])
        self._pro_qpos = m.jnt_qposadr[self._pro_joints]
        self._pro_dof = m.jnt_dofadr[self._pro_joints]
        #: qpos address of the sensored thumb's rotation (a scenario may pre-shape it)
        self.thumb_rotation_qpos = int(m.jnt_qposadr[m.joint("pro_thumb_rot").id])
        self._pro_act = np.array([m.actuator(a).id for a in prosthetic_actuators()])
        self._max_speed = m.actuator_ctrlrange[self._pro_act, 1].copy()
        hum = [m.actuator(a).id for a in partner_actuators()]
        #: actuator ids of the partner's digit servos, in PARTNER_JOINTS order (a scenario sets them)
        self.partner_servos = np.array(hum[:len(PARTNER_JOINTS)])
        self._ctrl, self._qpos, self._qvel = self.physics.ctrl, self.physics.qpos, self.physics.qvel
        # what a step reads and writes, as slices where the addresses are consecutive (as in
        # every scene built here): numpy takes a slice without an index array or a copy
        self._q_at, self._v_at = _span(self._pro_qpos), _span(self._pro_dof)
        self._act_at, self._servo_at = _span(self._pro_act), _span(self.partner_servos)
        self._action_period_s = float(m.opt.timestep) * self.frame_skip
        # calibrated force range of every contact pair, as a geom x geom table (inf: no pair)
        #: the law of every skin pair, and why (softhand.envs.skins.pair_choices)
        self.pair_laws = pair_choices(m, self.skins, self.representations, directory=directory,
                                      contact_laws=self.contact_laws)
        self._range = np.full((m.ngeom, m.ngeom), np.inf)
        self._pair_name = {}
        for pid in range(m.npair):
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_PAIR, pid) or str(pid)
            g1, g2 = int(m.pair_geom1[pid]), int(m.pair_geom2[pid])
            top = self.pair_laws[name].calibrated_max_N
            self._range[g1, g2] = self._range[g2, g1] = top
            self._pair_name[(min(g1, g2), max(g1, g2))] = name
        self._reset_range_counts()
        self.action_space = spaces.Box(-1.0, 1.0, (6,), np.float32)
        kinds = {int(mujoco.mjtJoint.mjJNT_HINGE): "hinge",
                 int(mujoco.mjtJoint.mjJNT_SLIDE): "slide"}
        #: the name and unit of every action and observation entry (softhand.envs.spaces)
        self.action_names = action_names()
        self.observation_names = observation_names(
            [(m.joint(j).name, kinds[int(m.jnt_type[j])]) for j in self._pro_joints],
            self.region_names, observe)
        self._n_obs = len(self.observation_names)
        self.observation_space = spaces.Box(-np.inf, np.inf, (self._n_obs,), np.float64)
        #: the sensored hand's drives pre-shaped before each episode (the scenario's)
        self._preset = scenario.prepare(self)
        self._planned = False
        self._ended: str | None = None  # why the episode ended ("truncated", "terminated")

    # --- gymnasium API -----------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode; ``seed`` is None or an integer >= 0; ``options`` go to the scenario
        (checked: softhand.envs.partner.check_reset_options). An episode cut short by this reset
        issues its range summary first (`_warn_range`).

        Raises:
            RuntimeError: the env is closed.
        """
        self._check_open()
        if seed is not None and (not isinstance(seed, (int, np.integer)) or isinstance(seed, bool)
                                 or seed < 0):
            raise ValueError(f"seed = {show(seed)}: expected None or an integer >= 0")
        options = check_reset_options(options)
        if self._planned and self._ended is None:
            self._warn_range(self._range_summary(), "cut short by reset()")
        super().reset(seed=None if seed is None else int(seed))
        rng = self.np_random
        start, quat = self.scenario.reset(self, rng, options)
        dt = self.model.opt.timestep
        # the mount's path at every physics step (a scripted arm: no feedback from the contacts)
        self._mount = mount_path(self.scenario, dt, self.frame_skip)
        self._duration_s = self.scenario.duration_s  # the episode's length, fixed at its reset
        self._step_index = 0
        self.physics.reset(start, quat, self._preset)
        self._forces = np.zeros(len(self.region_names))
        self._bone = np.zeros(len(self.region_names))
        # the sensors' noise: its own stream, drawn after the partner's (which it leaves as is)
        self.sensors.reset(np.random.default_rng(int(rng.integers(2**63))))
        self._readings = self.sensors.reading
        self._estimate = self.sensors.estimate
        self._saturated = 0
        self._reset_range_counts()
        self._planned = True
        self._ended = None
        return self._obs(), self._info({}, self.scenario.phase(0.0))

    def step(self, action):
        """Advance one action period; see HandshakeEnv's docstring for the action and outputs."""
        self._check_open()
        if isinstance(action, np.ma.MaskedArray) and np.ma.getmaskarray(action).any():
            # the data under a mask is arbitrary: np.asarray would pass it on as the action
            raise ValueError(f"action {action} has masked entries (at "
                             f"{np.flatnonzero(np.ma.getmaskarray(action)).tolist()}): expected 6 "
                             "finite real values in [-1, 1], none masked")
        try:
            raw = np.asarray(action)
        except (TypeError, ValueError):  # ragged nested sequences
            raw = np.asarray(None)
        if raw.dtype.kind not in "iuf":  # complex, strings, objects, booleans
            raise ValueError(f"action {show(action)} is outside the action space: 6 finite real "
                             f"values in [-1, 1] (got dtype {raw.dtype})")
        a = raw.astype(np.float64, copy=False)
        if a.shape != (6,) or not within(a, -1.0 - 1e-6, 1.0 + 1e-6):  # NaN is not within
            got = f" (got shape {a.shape})" if a.shape != (6,) else ""
            shown = np.array2string(a, floatmode="unique")  # 1.0001 shown as it is, not "1."
            raise ValueError(f"action {shown} is outside the action "
                             f"space: 6 finite values in [-1, 1]{got}")
        if not self._planned:
            raise RuntimeError("call reset() before step()")
        if self._ended is not None:
            raise RuntimeError(f"the episode is over ({self._ended} at t = {self._ended_s:.3f} "
                               "s): call reset() before step()")
        physics, scenario = self.physics, self.scenario
        ctrl = self._ctrl
        t = physics.time
        if self.hand == "human":  # the relaxed hand follows the scenario; the action is unused
            ctrl[self._act_at] = scenario.sensored_targets(t)
        else:
            ctrl[self._act_at] = a * self._max_speed
        # the partner's digits act once per action step (100 Hz by default), the arm every step
        ctrl[self._servo_at] = scenario.partner_targets(t, physics.partner_feel(),
                                                        self._action_period_s)
        k, mount = self._step_index, self._mount
        end = k + self.frame_skip
        # None, or why the physics diverged (MuJoCo reset itself, warned, or went non-finite)
        diverged = physics.advance(mount[k:end] if end <= len(mount) else
                                   mount[np.minimum(np.arange(k, end), len(mount) - 1)])
        self._step_index = end
        unstable = diverged is not None
        if not unstable:  # a diverged step keeps the last good forces and readings
            self._forces, self._bone = physics.region_forces()
            self._readings = self.sensors.step(self._forces)
            self._estimate = self.sensors.estimate
            self._saturated = physics.saturated_sensors()
            self._check_range(*physics.contacts_above(self._range), physics.time)
            self._check_overload(self._forces, self._bone, physics.time)
        d = self.data
        now = diverged.time_s if unstable else d.time
        phase = scenario.phase(now)
        terms = scenario.reward_terms(self._forces, a, phase)
        reward = sum(terms.values()) if not unstable else -100.0
        truncated = d.time >= self._duration_s - 1e-9
        info = self._info(terms, phase)
        info["unstable"] = str(diverged) if unstable else False
        if unstable:  # the time of the last good state, not of MuJoCo's reset state
            info["time_s"] = now
        obs = self._obs() if not unstable else np.zeros(self._n_obs)
        truncated = bool(truncated and not unstable)
        if unstable or truncated:
            self._ended = "terminated" if unstable else "truncated"
            self._ended_s = info["time_s"]  # after a divergence: the last good state's time
        if self._ended is not None:  # the episode's one summary of its contacts beyond range
            info["beyond_range_summary"] = summary = self._range_summary(info["time_s"])
            self._warn_range(summary, "ended")
        return obs, reward, unstable, truncated, info

    def __reduce_ex__(self, protocol):
        """Pickling and deep copies (``copy.deepcopy``) are refused in one line: the env holds a
        live simulation with its partner script, sensor electronics and accounting state, which
        a copy would have to rebuild to stay one episode; make another env instead."""
        raise TypeError(f"{type(self).__name__} cannot be pickled or deep-copied: it holds a live "
                        "MuJoCo simulation and the state of its partner, sensors and accounting; "
                        "make another with the same arguments (gymnasium.make('softhand/"
                        "Handshake-v0', ...)) and reset it with the same seed, or pickle "
                        "env.model and env.data (MuJoCo's own) for the physics alone")

    def __deepcopy__(self, memo):
        return self.__reduce_ex__(2)

    def __copy__(self):
        """A shallow copy shares the simulation (the vector env's worlds of one scene do)."""
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        return new

    def close(self) -> None:
        """Release the env: `step` and `reset` refuse afterwards (closing twice is
        harmless). An episode cut short here issues its range summary (`_warn_range`)."""
        if getattr(self, "_closed", True):  # closed, or __init__ stopped before the scene
            return
        if getattr(self, "_planned", False) and self._ended is None:
            self._warn_range(self._range_summary(), "cut short by close()")
        self._closed = True
        if self._picture is not None:
            self._picture.close()
        super().close()

    def render(self) -> np.ndarray:
        """The current state as an (H, W, 3) uint8 picture (``render_mode="rgb_array"``),
        ``render_size`` (W, H) pixels from ``render_view``: ``softhand render``'s picture, made
        by the same code (`ScenePicture`), without its caption: the prosthetic's skin coloured by
        each region's force at the last step (`region_colours`), the partner's hand blue.
        The renderer is made at the first call and freed by `close`; it draws a copy of
        the state, so rendering never changes the episode.

        Raises:
            RuntimeError: the env was made without a render mode, is closed, or has not been
                reset (there is no episode to draw yet).
        """
        self._check_open()
        if self.render_mode is None:
            raise RuntimeError("render() needs a render mode: make the env with "
                               "render_mode='rgb_array'")
        if not self._planned:
            raise RuntimeError("call reset() before render(): there is no episode to draw yet")
        if self._picture is None:
            self._picture = ScenePicture(self.model, *self.render_size)
            self._picture_data = mujoco.MjData(self.model)
        d = self.data
        state = posed_data(self.model, d.qpos, d.mocap_pos, d.mocap_quat, self._picture_data)
        colours = region_colours(self.model, skin_forces(self.model, self.region_names,
                                                             self._forces))
        return self._picture.draw(state, self.render_view, colours=colours)

    # --- helpers -----------------------------------------------------------------------------
    def _check_open(self) -> None:
        if self._closed:
            raise RuntimeError("the env is closed (close() was called): make a new env")

    def _check_render(self, mode: str | None, size: tuple[int, int],
                      view: CameraView | None) -> None:
        """Check and keep the render keywords (before any work, as every keyword)."""
        if mode is not None and (not isinstance(mode, str) or mode not in RENDER_MODES):
            raise ValueError(f"render_mode = {show(mode)}: allowed None or "
                             f"{', '.join(map(repr, RENDER_MODES))}")
        if isinstance(size, (str, bytes)) or not hasattr(size, "__len__") or len(size) != 2:
            raise ValueError(f"render_size = {show(size)}: expected (width, height) in pixels")
        check_size(*size)
        if view is not None and not isinstance(view, CameraView):
            raise ValueError(f"render_view = {show(view)}: expected None or a "
                             "softhand.envs.picture.CameraView")
        self.render_mode = mode
        self.render_size = (int(size[0]), int(size[1]))
        self.render_view = RENDER_VIEW if view is None else view

    def _reset_range_counts(self) -> None:
        """Zero the episode's counts of contacts beyond their calibrated range."""
        self._beyond = 0  # pair contacts beyond range at this step
        self._bottomed = 0  # regions whose bone bottomed out at this step
        self._beyond_N: dict[str, float] = {}  # pair -> its force (N) at this step, if beyond
        self._episode_steps = 0
        self._beyond_steps = 0  # pair contacts beyond range, summed over the episode's steps
        self._bone_steps = 0  # regions with bone bottoming out, summed over the steps
        self._worst: dict[str, tuple[float, float, float]] = {}  # pair -> (N, limit N, t s)
        n = len(self.region_names)
        self._over = np.zeros(n, bool)  # regions over the scenario's overload_N at this step
        self._bottoming = np.zeros(n, bool)  # regions whose bone bottoms out at this step
        self._overload_started: dict[str, float] = {}  # what began to overload at this step
        self._first_overload: tuple[float, dict[str, float]] | None = None  # (t s, what)

    def _check_overload(self, forces: np.ndarray, bone: np.ndarray, t: float) -> None:
        """Name what begins to overload at this step (``info["overload_started"]``): each region
        whose load (N) passes the scenario's ``overload_N`` (none if it has none), as
        ``{region: N}``, and each region whose bone begins to bottom out under its skin, as
        ``{"{region} bone": N}``; the episode's first such step is kept for its summary
        (``first_overload_time_s``, ``first_overload``). The vector env calls it per world."""
        limit = getattr(self.scenario, "overload_N", math.inf)
        over, bottoming = forces > limit, bone > 0.0
        started: dict[str, float] = {}
        if over.any() or bottoming.any():
            names = self.region_names
            for i in np.flatnonzero(over & ~self._over).tolist():
                started[names[i]] = float(forces[i])
            for i in np.flatnonzero(bottoming & ~self._bottoming).tolist():
                started[f"{names[i]} bone"] = float(bone[i])
            if started and self._first_overload is None:
                self._first_overload = (float(t), dict(started))
        self._over, self._bottoming = over, bottoming
        self._overload_started = started

    def _check_range(self, geoms: np.ndarray, force: np.ndarray, top: np.ndarray,
                     t: float) -> None:
        """Count the contacts above their pair law's calibrated range at this step, at time ``t``
        (s; ``geoms``, ``force``, ``top``: MujocoPhysics.contacts_above), for ``info`` and into
        the episode's counts; the episode warns once, at its end (`_warn_range`). The
        vector env (softhand.envs.vector) keeps each world's counts with this too."""
        self._beyond = int(force.size)
        self._beyond_N = {}
        self._episode_steps += 1
        self._beyond_steps += self._beyond
        self._bottomed = count_above(self._bone, 0.0)  # regions whose bone bottomed out
        self._bone_steps += self._bottomed
        if not self._beyond:
            return
        for (g1, g2), f, lim in zip(geoms.tolist(), force.tolist(), top.tolist(), strict=True):
            name = self._pair_name[(min(g1, g2), max(g1, g2))]
            self._beyond_N[name] = max(f, self._beyond_N.get(name, 0.0))
            if f > self._worst.get(name, (0.0,))[0]:
                self._worst[name] = (f, lim, t)

    def _range_summary(self, time_s: float | None = None) -> dict[str, Any]:
        """The episode's contacts beyond their calibrated range so far (``info
        ["beyond_range_summary"]`` on the episode's last step): ``contact_steps`` (pair contacts
        beyond range summed over the steps), ``pairs`` (how many pairs went beyond),
        ``bone_steps`` (regions with bone bottoming out, summed over the steps: with
        ``contact_steps``, the sum of ``info["contacts_beyond_range"]``), the worst pair (largest
        force over its law's limit): ``worst_pair``, ``worst_skin``, ``worst_force_N``,
        ``worst_limit_N``, ``worst_time_s`` (None when no pair went beyond), and ``steps`` and
        ``time_s`` (default: the state's time) of the episode."""
        out: dict[str, Any] = {"contact_steps": self._beyond_steps, "pairs": len(self._worst),
                               "bone_steps": self._bone_steps, "worst_pair": None,
                               "worst_skin": None, "worst_force_N": None, "worst_limit_N": None,
                               "worst_time_s": None, "steps": self._episode_steps,
                               "time_s": float(self.data.time if time_s is None else time_s),
                               "first_overload_time_s": None, "first_overload": None}
        if self._first_overload is not None:
            out.update(first_overload_time_s=self._first_overload[0],
                       first_overload=dict(self._first_overload[1]))
        if self._worst:
            name, (f, lim, t) = max(self._worst.items(), key=lambda kv: kv[1][0] / kv[1][1])
            out.update(worst_pair=name, worst_skin=skin_of_pair(name, self.skins)[1],
                       worst_force_N=f, worst_limit_N=lim, worst_time_s=t)
        return out

    def _warn_range(self, summary: dict[str, Any], how: str) -> None:
        """One `CalibratedRangeWarning` for an episode that had contacts beyond range,
        attributed to the user's code that called step(), reset() or close() (through
        Gymnasium's wrappers too): issued on the step that ends the episode (``how`` "ended"), or
        when reset() or close() cuts it short."""
        parts = []
        if summary["contact_steps"]:
            law = ("human tissue's, the skin rigid" if summary["worst_skin"] == "rigid"
                   else f"{summary['worst_skin']} in series with human tissue, "
                   f"{self.pair_laws[summary['worst_pair']].law} law")
            parts.append(
                f"{summary['contact_steps']} contact-steps on {summary['pairs']} pair(s) beyond "
                f"their law's calibrated range; the worst, pair {summary['worst_pair']}, carried "
                f"{summary['worst_force_N']:.2f} N at t = {summary['worst_time_s']:.2f} s "
                f"against the {summary['worst_limit_N']:.2f} N its law ({law}) is calibrated to: "
                "the force above that is an extrapolation")
        if summary["bone_steps"]:
            parts.append(f"a bone bottomed out under a region in {summary['bone_steps']} "
                         "region-steps (outside every law's calibration)")
        if parts and summary["first_overload"]:
            what = ", ".join(f"{k} {v:.1f} N" for k, v in summary["first_overload"].items())
            parts.append(f"the first overload began at t = {summary['first_overload_time_s']:.2f}"
                         f" s ({what}; info['overload_started'])")
        if parts:
            where = " (info['beyond_range_summary'])" if how == "ended" else ""
            warn_at_caller(f"episode {how} at t = {summary['time_s']:.2f} s after "
                           f"{summary['steps']} steps: {'; '.join(parts)}{where}",
                           CalibratedRangeWarning)

    def _obs(self) -> np.ndarray:
        n = self._pro_qpos.size
        obs = np.empty(self._n_obs)
        obs[:n] = self._qpos[self._q_at]
        obs[n:2 * n] = self._qvel[self._v_at]
        obs[2 * n:-1] = region_values(self.observe, {
            "sensor_patch": self._readings, "region_load": self._forces,
            "load_estimate": self._estimate})
        obs[-1] = self.data.time / self._duration_s
        return obs

    def _info(self, terms: dict[str, float], phase: str) -> dict[str, Any]:
        names = self.region_names
        estimate = self._estimate
        return {"region_forces_N": dict(zip(names, self._forces.tolist(), strict=True)),
                "sensor_readings_N": dict(zip(names, self._readings.tolist(), strict=True)),
                "sensor_load_estimate_N": dict(zip(names, estimate.tolist(), strict=True)),
                "phase": phase, "reward_terms": terms, "time_s": float(self.data.time),
                "saturated_sensors": self._saturated,
                "thumb_rotation_rad": float(self._qpos[self.thumb_rotation_qpos]),
                "contacts_beyond_range": self._beyond + self._bottomed,
                "pairs_beyond_range_N": dict(self._beyond_N),
                "region_bone_N": dict(zip(names, self._bone.tolist(), strict=True)),
                "overload_started": dict(self._overload_started),
                **self.scenario.info()}
