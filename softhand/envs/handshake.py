"""``softhand/Handshake-v0``: a prosthetic hand with calibrated skins shakes hands with a human partner.

The docstring of :class:`HandshakeEnv` is the specification.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces

from softhand.envs.models import skinned_scene_spec
from softhand.envs.partner import (
    GRIP_FORCE_N,
    GRIP_PHALANGES,
    PartnerScript,
    RelaxedHand,
    Timeline,
    check_partner_size,
    check_reset_options,
    partner_postures,
)
from softhand.envs.physics import MujocoPhysics
from softhand.envs.sensing import OBSERVE, parse_placements, region_laws
from softhand.envs.skins import (
    CalibratedRangeWarning,
    calibrated_max_force,
    parse_skins,
    series_law,
    skin_of_pair,
)
from softhand.hands import (
    SceneConfig,
    partner_actuators,
    partner_contact_pose,
    partner_start_pose,
    prosthetic_actuators,
    regions,
    solve_grasp,
)
from softhand.hands.config import TIMESTEP_RANGE_S, HandConfig, PartnerConfig, ProstheticConfig
from softhand.hands.grasp import PROSTHETIC_MOTOR_JOINTS
from softhand.hands.partner import PARTNER_JOINTS
from softhand.hands.prosthetic import paper_regions
from softhand.laws.references import HUMAN
from softhand.sensors.device import FLEXIFORCE_A101, SensorChain, SensorSpec
from softhand.skin.files import SKINS_DIR
from softhand.validate import check_number, show

__all__ = [
    "ACTION_PERIOD_S",
    "DEFAULT_REWARD_WEIGHTS",
    "DEFAULT_TIMESTEP_S",
    "HANDS",
    "MAX_ACTION_PERIOD_S",
    "TIMESTEP_RANGE_S",
    "HandshakeEnv",
]

DEFAULT_REWARD_WEIGHTS = {"grip": 1.0, "contact": 0.5, "overload": 0.1, "effort": 0.01}
CONTACT_N = 0.05  # a region counts as touched above this force
_GRIPPING = ("grip", "shake")
ACTION_PERIOD_S = 0.01  # default action period: 100 Hz
MAX_ACTION_PERIOD_S = 0.1  # slowest action rate allowed (10 Hz): frame_skip x timestep_s
DEFAULT_TIMESTEP_S = SceneConfig.timestep_s
#: The sensored hand: the prosthetic hand (default, its 6 motors driven by the action), or the
#: paper's experimenter's relaxed human hand (human tissue on every region, soft joint
#: impedance, a neutral grip that waits for the partner; the action is not used).
HANDS = ("prosthetic", "human")


class HandshakeEnv(gym.Env):
    """Handshake between a 6-motor prosthetic right hand and a scripted human partner hand.

    The prosthetic hand (fixed, thumb up) wears a calibrated skin on each of the paper's 18 regions
    (Fig. 1: Thumb1-2, Index1-3, Middle1-3, Ring1-3, Little1-3, Palm1-2, Back1-2; 1 = proximal).
    The partner reaches with an open hand, slides its web space into the prosthetic's (whose
    thumb is pre-rotated to the grasp), closes to its grasp posture and grips to a human grip
    force, shakes at 4 Hz, lets go and leaves (:mod:`softhand.envs.partner`, published timings).
    The grasp, both postures and the partner's pose, is solved from the handshake's contacts
    (:mod:`softhand.hands.grasp`: palms together, web spaces together, each thumb over the back of
    the other's index metacarpal, the fingers wrapped round the other's ulnar border). Its hand
    rides a compliant arm (a soft weld to the scripted target); its size is ``partner_size``.
    The prosthetic hand's whole envelope is skin (the 18 regions and
    the non-sensing thenar; :mod:`softhand.hands.envelope`), the partner's is one layer of tissue;
    every contact between them is a calibrated soft contact (the skin in series with human tissue,
    fitted to 20 N, calibrated to 7 N: a contact above that raises a ``CalibratedRangeWarning``
    once per pair and episode). Each region's reading is a contact sensor on its skin's contacts
    inside its sensor zone (the contact side; the rest is unsensed skin). The partner regulates
    the force its digits feel; its grip acts once per action step, its arm every step.

    Action space: ``Box(-1, 1, (6,), float32)``, motor speed as a fraction of the maximum
    (positive closes; the maximum closes a digit from open in about 1 s):

    ===== ====================================== =====
    index actuator                               unit
    ===== ====================================== =====
    0-3   index, middle, ring, little finger      1 = full closing speed
    4     thumb flexion                           1 = full closing speed
    5     thumb rotation (towards opposition)     1 = full speed
    ===== ====================================== =====

    Observation space: ``Box(-inf, inf, (2 n + 19,), float64)`` with n the prosthetic hand's
    joints (16 by default); ``(2 n + 37,)`` with ``observe="both"``:

    ================= ====================================================== ======
    slice             quantity                                                unit
    ================= ====================================================== ======
    [0, n)            prosthetic joint positions                             rad
    [n, 2n)           prosthetic joint velocities                            rad/s
    [2n, 2n + 18)     per region, in the order above: its embedded sensor's   N
                      reading (``observe="sensor"``, the default), or its
                      true normal contact force (``observe="contact"``)
    [2n + 18, 2n+36)  ``observe="both"`` only: the true contact forces       N
    last              time since the start / handshake duration              1
    ================= ====================================================== ======

    Embedded sensors (:mod:`softhand.envs.sensing`): each region's sensor sits under its skin at
    ``sensor_placement`` (default ``interface``, under the outer layer; ``bone``;
    ``pocket-floor`` for pocketed designs; skins without an FE model get an ideal ``surface``
    sensor) and reads the force on its 4 x 4 mm patch (N): the design's transfer law of the
    region's contact force (calibration/sensors/transfer.json: sensitivity, the pocket's dead
    band, the reading's relaxation), then ``sensor``'s electronics (:class:`SensorSpec`, default
    a FlexiForce A101 with a 10-bit ADC at 100 Hz: latency, seeded noise, threshold, saturation,
    quantization, optional hysteresis), resolved to the env step (frame_skip x timestep_s).
    The reward uses the true contact forces.

    Reward (weights are constructor arguments, defaults in ``DEFAULT_REWARD_WEIGHTS``):

    * ``grip`` = -w_grip ((F_mean - F_h) / F_h)^2 while the partner grips or shakes, with F_mean the
      mean force over touched regions (> 0.05 N) and F_h the partner's grip per phalanx (2.5 N, Melnyk et
      al. 2014, times ``squeeze``): a human-like, matched grip;
    * ``contact`` = +w_contact (touched regions / 18) in the same phases: a full-hand grip;
    * ``overload`` = -w_overload sum_i max(0, F_i - overload_N)^2 at all times;
    * ``effort`` = -w_effort |a|^2.

    Episode end: truncated when the handshake is over (3.63 s by default); terminated if the
    simulation produces a non-finite state (then ``info["unstable"]`` is True).

    Timestep: allowed 0.1-5 ms (``TIMESTEP_RANGE_S``); the skins are calibrated for 0.5-2 ms
    (their rest laws hold at every step in that range) and warn (``SkinRangeWarning``) outside it.
    2 ms, the default, reproduces the region forces of 0.5 ms within a few percent for all three
    controllers and runs about 1.8x faster than 1 ms (``softhand bench handshake``: speed and
    error against 0.5 ms for each timestep).

    ``info``: ``region_forces_N`` (dict region -> N, the true contact forces, always: the
    region's skin inside its sensor zone and its bone bottoming out there, flagged in
    ``region_bone_N`` and counted in ``contacts_beyond_range``, since bone on bone is outside every
    law's calibration),
    ``sensor_readings_N`` (dict region -> N on the sensor patch), ``sensor_load_estimate_N``
    (dict region -> N: the load a calibrated read-out infers from the reading by inverting the
    transfer law's static curve; 0 inside a dead band), ``phase`` (reach, grip, shake, release,
    return, done), ``reward_terms`` (dict), ``time_s``, ``partner_grip_N`` (the target of the
    partner's summed digit force: its sampled grip per phalanx times ``GRIP_PHALANGES``),
    ``partner_grip_measured_N`` (that sum, measured), ``partner_effort_rad`` (its grip
    effort), ``grasp_thumb_rotation_rad`` (the solved grasp's prosthetic thumb rotation).

    Skin representations (:mod:`softhand.skin.representations`; ``representation`` for every
    region, ``skins`` values ``DESIGN@REPRESENTATION`` for one):

    * ``soft-contact`` (default): each pair carries the skin's law in series with the tissue's in
      its solref/solimp (no memory: the 0.5 mm/s loading curve);
    * ``soft-contact+relaxation``: each skin geom rides a relaxation pad (a slide joint along its
      outward normal, the QLV law's spline spring and Maxwell branches, joint armature 10 g,
      :class:`~softhand.skin.representations.HandPad`), its pairs carry the tissue's law alone
      (skin and tissue in series mechanically). Runs under the scene's ``implicitfast`` at
      0.5-2 ms, at about twice the cost (2 Prony terms x 6 branch knots + 1 dofs per skin geom).
      The pad compresses along its normal only: a contact from the side (the palm's borders, a
      thumb's side) meets the tissue's law alone, and the force accounting says so
      (HandshakeRun.force_accounting; 43 % of the force in the default scene);
      HandshakeRun.relaxation() measures each pad against the QLV law;
    * ``rigid``: MuJoCo's stock contact against the tissue (only the tissue indents).

    ``flex`` is refused: it needs the ``discrete`` integrator, under which the soft contacts do
    not hold; a flex region has its own scene (softhand.hands.flex_region).

    Args:
        design: skin of every region (a design such as ``pocket2-sil``, ``prosthetic-102l`` or
            ``rigid``; default: the most lifelike design).
        skins: region -> skin overrides, ``DESIGN`` or ``DESIGN@REPRESENTATION``.
        representation: representation of every region (default ``soft-contact``; allowed:
            ``HAND_REPRESENTATIONS``).
        frame_skip: physics steps per action, an integer >= 1 with frame_skip x timestep_s <=
            0.1 s (actions at 10 Hz or faster); default: actions at 100 Hz
            (``ACTION_PERIOD_S / timestep_s``, 5 steps of 2 ms).
        timestep_s: physics timestep, in [0.0001, 0.005] s (``TIMESTEP_RANGE_S``; the skins are
            calibrated at 0.0005-0.002 s); default 2 ms (SceneConfig).
        squeeze: multiplier of the partner's grip force (5 for the hard case), finite and > 0.
        overload_N: region force above which the overload penalty applies, finite and > 0.
        reward_weights: override of ``DEFAULT_REWARD_WEIGHTS`` entries, each finite and >= 0
            (a weight is a magnitude: the sign of each term is fixed above).
        calibration_dir: folder of the skin calibration files (default: the shipped ones); every
            skin used is read and checked before the scene is built.
        randomize: vary the partner (timing +-5 %, grip +-10 %, shake phase) from the seed.
        sensor: the sensors' electronics (default :data:`FLEXIFORCE_A101`); the noise is drawn
            from the episode's seed.
        sensor_placement: one placement for every region, or a mapping region -> placement
            (the rest ``interface``).
        observe: ``sensor`` (default), ``contact`` or ``both`` (see the observation space).
        sensor_dir: folder of ``transfer.json`` (default: the shipped ``calibration/sensors``).
        hand: ``prosthetic`` (default) or ``human``: the paper's protocol, the sensored hand as
            the experimenter's relaxed human hand (HANDS): human tissue on every region against
            the partner's (both the human law), soft joint impedance
            (constants.RELAXED_HUMAN) holding the grasp posture it closes to after the reach,
            surface sensors (the paper's FingerTPS pads); ``design``, ``skins`` and
            ``representation`` are the prosthetic's and refused here; actions are checked but
            not used.
        partner_size: the partner's hand (length, width) in mm, each within +-2.5 SD of the
            paper's 30 subjects (Table 1: 187.5 +- 11.37 mm, 89.53 +- 6.80 mm; any combination);
            default the experimenter's 190 x 88 mm. The grasp is solved for this pair of hands.

    Raises:
        ValueError: at construction, a bad argument or calibration file, naming it and the
            allowed range; in :meth:`reset`, a bad seed; in :meth:`step`, an action that is not 6
            finite real numbers in [-1, 1].
        RuntimeError: :meth:`step` before :meth:`reset` or after the episode ended.

    Physics: every MuJoCo call of an episode goes through :attr:`physics`
    (:class:`~softhand.envs.physics.MujocoPhysics`), the seam a batched backend would implement;
    the partner's script, the reward and the observation stay here.

    Version history: v0 (softhand 0.1, unreleased): first release; before the release the default
    timestep went from 1 to 2 ms and the partner's joints got armature (region forces changed).
    """

    metadata: ClassVar[dict] = {"render_modes": [], "render_fps": 100}

    def __init__(self, *, design: str | None = None, skins: Mapping[str, str] | None = None,
                 representation: str | None = None, frame_skip: int | None = None,
                 timestep_s: float = DEFAULT_TIMESTEP_S, squeeze: float = 1.0,
                 overload_N: float = 10.0, reward_weights: Mapping[str, float] | None = None,
                 calibration_dir: str | Path | None = None, randomize: bool = True,
                 sensor: SensorSpec | None = None,
                 sensor_placement: str | Mapping[str, str] | None = None,
                 observe: str = "sensor", sensor_dir: str | Path | None = None,
                 partner_size: tuple[float, float] | None = None,
                 hand: str = "prosthetic") -> None:
        # every argument (and every calibration file used) is checked before any work is done
        check_number("timestep_s", timestep_s, lo=TIMESTEP_RANGE_S[0], hi=TIMESTEP_RANGE_S[1],
                     why="s (skins calibrated at 0.0005-0.002 s)")
        self.partner_size_mm = check_partner_size(partner_size)
        partner = PartnerConfig(hand=HandConfig(hand_length_m=self.partner_size_mm[0] / 1e3,
                                                hand_width_m=self.partner_size_mm[1] / 1e3))
        if hand not in HANDS:
            raise ValueError(f"hand = {show(hand)}: allowed {', '.join(HANDS)}")
        self.hand = hand
        prosthetic = ProstheticConfig(actuation="relaxed-human" if hand == "human" else "motors")
        self.config = SceneConfig(timestep_s=timestep_s, partner=partner, prosthetic=prosthetic)
        timestep_s = self.config.timestep_s
        max_skip = int(MAX_ACTION_PERIOD_S / timestep_s + 1e-9)
        if frame_skip is None:
            frame_skip = max(1, round(ACTION_PERIOD_S / timestep_s))
        check_number("frame_skip", frame_skip, lo=1, hi=max_skip, integer=True,
                     why=f"(frame_skip x timestep_s <= {MAX_ACTION_PERIOD_S:g} s)")
        self.squeeze = check_number("squeeze", squeeze, lo=0.0, lo_open=True)
        self.overload_N = check_number("overload_N", overload_N, lo=0.0, lo_open=True)
        weights = dict(DEFAULT_REWARD_WEIGHTS)
        if reward_weights is not None and not isinstance(reward_weights, Mapping):
            raise ValueError(f"reward_weights = {show(reward_weights)}: expected a mapping of "
                             f"{', '.join(weights)} to numbers >= 0")
        for key, value in (reward_weights or {}).items():
            if key not in weights:
                raise ValueError(f"reward weight {key!r} is unknown; allowed: {', '.join(weights)}")
            weights[key] = check_number(f"reward_weights[{key!r}]", value, lo=0.0)
        if not isinstance(randomize, (bool, np.bool_)):
            raise ValueError(f"randomize = {show(randomize)}: expected True or False")
        self.weights = weights
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
            self.skins, self.representations = parse_skins(design, skins, representation)
        self.frame_skip = int(frame_skip)
        if observe not in OBSERVE:
            raise ValueError(f"observe = {show(observe)}: allowed {', '.join(OBSERVE)}")
        self.observe = observe
        spec = FLEXIFORCE_A101 if sensor is None else sensor
        if not isinstance(spec, SensorSpec):
            raise ValueError(f"sensor = {show(sensor)}: expected a SensorSpec")
        placements = parse_placements(tuple(self.skins), sensor_placement)
        laws, self.sensor_placements = region_laws(self.skins, placements, sensor_dir)
        #: the regions' embedded sensors: transfer laws, then the electronics
        self.sensors = SensorChain(laws, spec, self.frame_skip * timestep_s)
        self.randomize = bool(randomize)
        directory = calibration_dir or SKINS_DIR
        self.calibration_dir = str(directory)  # where the skins' laws came from
        for skin in sorted({*self.skins.values(), "rigid"}):
            series_law(skin, str(directory))  # reads and checks the file (cached)
        # the laws are written into the spec, and the model is compiled from the spec's MJCF text,
        # so that models/mjcf/handshake_scene.xml is exactly the simulated model (the XML writer
        # rounds numbers: a model compiled from the spec itself differs in the last digits)
        spec = skinned_scene_spec(self.skins, self.config, representations=self.representations,
                                  directory=directory)
        spec.compile()
        m = mujoco.MjModel.from_xml_string(spec.to_xml())
        self.region_names = tuple(self.skins)
        infos = regions(m, "pro_")
        self.region_geoms = tuple(infos[r].geom for r in self.region_names)
        # the grip force the partner regulates is what its digits feel (data gloves measure the
        # fingers' and thumb's phalanges), not what its palm or thenar feel: a hard push on the
        # palm must not make the partner open its fingers
        feel = [m.sensor(i).name for i in range(m.nsensor)
                if m.sensor(i).name.startswith("hum_feel_")
                and m.sensor(i).name.rsplit("_", 1)[-1] in ("proximal", "middle", "distal")]
        #: the physics, behind the seam a batched backend would implement (envs.physics)
        self.physics = MujocoPhysics(m, self.frame_skip,
                                     [infos[r].sensor for r in self.region_names], feel,
                                     "hum_base", [infos[r].bone_sensors for r in self.region_names])
        self.model, self.data = m, self.physics.data
        self._pro_joints = np.array([j for j in range(m.njnt) if m.joint(j).name.startswith("pro_")])
        self._pro_qpos = m.jnt_qposadr[self._pro_joints]
        self._pro_dof = m.jnt_dofadr[self._pro_joints]
        self._thumb_rot_qpos = int(m.jnt_qposadr[m.joint("pro_thumb_rot").id])
        self._pro_act = np.array([m.actuator(a).id for a in prosthetic_actuators()])
        self._max_speed = m.actuator_ctrlrange[self._pro_act, 1].copy()
        hum = [m.actuator(a).id for a in partner_actuators()]
        self._grip_act = np.array(hum[:len(PARTNER_JOINTS)])
        self._ctrl, self._qpos, self._qvel = self.physics.ctrl, self.physics.qpos, self.physics.qvel
        #: the handshake's grasp, solved from its contacts for these two hands (cached)
        self.grasp = solve_grasp(self.config)
        self._grip_phalanges = GRIP_PHALANGES
        self._grasp_thumb_rot = float(self.grasp.prosthetic_q[PROSTHETIC_MOTOR_JOINTS.index(
            "thumb_rot")])
        # the prosthetic's thumb is pre-rotated to the grasp before the episode (a user pre-shapes
        # the hand for a handshake, and the partner's hand slides into the web space under it)
        rot_motor = m.actuator("pro_thumb_rot_motor").id
        self._preset = ((self._thumb_rot_qpos, int(m.actuator_actadr[rot_motor]),
                         self._grasp_thumb_rot),)
        # calibrated force range of every contact pair, as a geom x geom table (inf: no pair)
        self._range = np.full((m.ngeom, m.ngeom), np.inf)
        self._pair_name = {}
        for pid in range(m.npair):
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_PAIR, pid) or str(pid)
            g1, g2 = int(m.pair_geom1[pid]), int(m.pair_geom2[pid])
            top = calibrated_max_force(skin_of_pair(name, self.skins)[1], self.calibration_dir)
            self._range[g1, g2] = self._range[g2, g1] = top
            self._pair_name[(min(g1, g2), max(g1, g2))] = name
        self._warned: set[str] = set()
        n = self._pro_joints.size
        self.action_space = spaces.Box(-1.0, 1.0, (6,), np.float32)
        self._n_obs = 2 * n + 19 + (18 if observe == "both" else 0)
        self.observation_space = spaces.Box(-np.inf, np.inf, (self._n_obs,), np.float64)
        self._timeline = Timeline()
        self._script: PartnerScript | None = None
        self._ended: str | None = None  # why the episode ended ("truncated", "terminated")

    # --- gymnasium API -----------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode; ``seed`` is None or an integer >= 0. ``options`` (None or a mapping)
        may set the partner of this episode instead of the seed's draw: ``grip_N`` (its grip per
        touching phalanx, N, in (0, 20]), ``duration_s`` (the handshake's duration, s, in
        [2, 6]; phases scale with it) and ``shake_phase_rad`` (finite)."""
        if seed is not None and (not isinstance(seed, (int, np.integer)) or isinstance(seed, bool)
                                 or seed < 0):
            raise ValueError(f"seed = {show(seed)}: expected None or an integer >= 0")
        options = check_reset_options(options)
        super().reset(seed=None if seed is None else int(seed))
        m = self.model
        rng = self.np_random
        factor = float(rng.uniform(0.95, 1.05)) if self.randomize else 1.0
        grip = GRIP_FORCE_N * self.squeeze * (float(rng.uniform(0.9, 1.1)) if self.randomize
                                              else 1.0)
        phase = float(rng.uniform(0, 2 * np.pi)) if self.randomize else 0.0
        if "duration_s" in options:
            factor = options["duration_s"] / self._timeline.total_s
        grip = options.get("grip_N", grip)
        phase = options.get("shake_phase_rad", phase)
        start, quat = partner_start_pose(self.config)
        contact, _ = partner_contact_pose(self.config)
        # the grip: GRIP_FORCE_N per phalanx (a data glove's mean per sensor, Melnyk et al. 2014)
        # on GRIP_PHALANGES phalanges, summed
        self._script = PartnerScript(self._timeline.scaled(factor), start, contact,
                                     grip_force_N=grip * self._grip_phalanges, shake_phase=phase,
                                     **partner_postures(self.grasp,
                                                        m.actuator_ctrlrange[self._grip_act, 1]))
        # the mount's path at every physics step (a scripted arm: no feedback from the contacts)
        n_steps = int(np.ceil(self._script.timeline.total_s / m.opt.timestep)) + self.frame_skip
        self._mount = np.array([self._script.mount(k * m.opt.timestep) for k in range(n_steps)])
        self._step_index = 0
        self.physics.reset(start, quat, self._preset)
        self._relaxed = RelaxedHand(self._script.timeline, self.grasp.prosthetic_q,
                                    PROSTHETIC_MOTOR_JOINTS.index("thumb_rot"))
        self._forces = np.zeros(len(self.region_names))
        self._bone = np.zeros(len(self.region_names))
        # the sensors' noise: its own stream, drawn after the partner's (which it leaves as is)
        self.sensors.reset(np.random.default_rng(int(rng.integers(2**63))))
        self._readings = self.sensors.reading
        self._saturated = 0
        self._beyond = 0
        self._partner_grip = 0.0
        self._warned = set()
        self._ended = None
        return self._obs(), self._info({}, "reach")

    def step(self, action):
        """Advance one action period; see the class docstring for the action and the outputs."""
        try:
            raw = np.asarray(action)
        except (TypeError, ValueError):  # ragged nested sequences
            raw = np.asarray(None)
        if raw.dtype.kind not in "iuf":  # complex, strings, objects, booleans
            raise ValueError(f"action {show(action)} is outside the action space: 6 finite real "
                             f"values in [-1, 1] (got dtype {raw.dtype})")
        a = raw.astype(np.float64, copy=False)
        # min/max are nan when any entry is: one comparison catches both
        if a.shape != (6,) or not (a.min() >= -1.0 - 1e-6 and a.max() <= 1.0 + 1e-6):
            got = f" (got shape {a.shape})" if a.shape != (6,) else ""
            raise ValueError(f"action {np.array2string(a, precision=3)} is outside the action "
                             f"space: 6 finite values in [-1, 1]{got}")
        if self._script is None:
            raise RuntimeError("call reset() before step()")
        if self._ended is not None:
            raise RuntimeError(f"the episode is over ({self._ended} at t = {self.data.time:.3f} "
                               "s): call reset() before step()")
        physics, script = self.physics, self._script
        ctrl, opt = self._ctrl, self.model.opt
        if self.hand == "human":  # the relaxed hand follows its own script; the action is unused
            ctrl[self._pro_act] = self._relaxed.targets(physics.time)
        else:
            ctrl[self._pro_act] = a * self._max_speed
        # the partner's grip acts once per action step (100 Hz by default), the arm every step
        t = physics.time
        grip = float(physics.partner_feel().sum())  # what the partner's digits press
        ctrl[self._grip_act] = script.grip(t, grip, opt.timestep * self.frame_skip)
        self._partner_grip = grip
        k, last = self._step_index, len(self._mount) - 1
        end = k + self.frame_skip
        physics.advance(self._mount[np.minimum(np.arange(k, end), last)])
        self._step_index = end
        self._forces, self._bone = physics.region_forces()
        self._readings = self.sensors.step(self._forces)
        self._saturated = physics.saturated_sensors()
        self._check_range()
        d = self.data
        phase = script.timeline.phase(d.time)
        # a sum is finite only if every entry is (an overflow to inf is unstable anyway)
        unstable = not np.isfinite(self._qpos.sum() + self._qvel.sum())
        terms = self._reward_terms(a, phase)
        reward = sum(terms.values()) if not unstable else -100.0
        truncated = d.time >= script.timeline.total_s - 1e-9
        info = self._info(terms, phase)
        info["unstable"] = unstable
        obs = self._obs() if not unstable else np.zeros(self._n_obs)
        truncated = bool(truncated and not unstable)
        if unstable or truncated:
            self._ended = "terminated" if unstable else "truncated"
        return obs, reward, unstable, truncated, info

    # --- helpers -----------------------------------------------------------------------------
    def _check_range(self) -> None:
        """Count the contacts above their pair law's calibrated range; warn once per pair."""
        geoms, force, top = self.physics.contacts_above(self._range)
        self._beyond = int(force.size)
        for (g1, g2), f, lim in zip(geoms, force, top, strict=True):
            name = self._pair_name[(min(g1, g2), max(g1, g2))]
            if name not in self._warned:
                self._warned.add(name)
                warnings.warn(f"pair {name}: {f:.2f} N is beyond the {lim:g} N its law "
                              f"({skin_of_pair(name, self.skins)[1]} in series with human tissue) "
                              "is calibrated to; the force above that is an extrapolation",
                              CalibratedRangeWarning, stacklevel=3)

    def _obs(self) -> np.ndarray:
        total = self._script.timeline.total_s if self._script else self._timeline.total_s
        n = self._pro_qpos.size
        obs = np.empty(self._n_obs)
        obs[:n] = self._qpos[self._pro_qpos]
        obs[n:2 * n] = self._qvel[self._pro_dof]
        obs[2 * n:2 * n + 18] = self._forces if self.observe == "contact" else self._readings
        if self.observe == "both":
            obs[2 * n + 18:2 * n + 36] = self._forces
        obs[-1] = self.data.time / total
        return obs

    def _reward_terms(self, a: np.ndarray, phase: str) -> dict[str, float]:
        w, f = self.weights, self._forces
        over = f[f > self.overload_N] - self.overload_N
        terms = {"grip": 0.0, "contact": 0.0,
                 "overload": -w["overload"] * float(over @ over),
                 "effort": -w["effort"] * float(a @ a)}
        if phase in _GRIPPING:
            target = self._script.grip_force_N / self._grip_phalanges  # per phalanx
            touched = f[f > CONTACT_N]
            mean = float(touched.mean()) if touched.size else 0.0
            terms["grip"] = -w["grip"] * ((mean - target) / target) ** 2
            terms["contact"] = w["contact"] * touched.size / f.size
        return terms

    def _info(self, terms: dict[str, float], phase: str) -> dict[str, Any]:
        names = self.region_names
        estimate = self.sensors.bank.load_estimate(self._readings)
        return {"region_forces_N": dict(zip(names, self._forces.tolist(), strict=True)),
                "sensor_readings_N": dict(zip(names, self._readings.tolist(), strict=True)),
                "sensor_load_estimate_N": dict(zip(names, estimate.tolist(), strict=True)),
                "phase": phase, "reward_terms": terms, "time_s": float(self.data.time),
                "partner_grip_N": self._script.grip_force_N if self._script else None,
                "partner_grip_measured_N": self._partner_grip,
                "partner_effort_rad": self._script.effort if self._script else 0.0,
                "saturated_sensors": self._saturated,
                "thumb_rotation_rad": float(self._qpos[self._thumb_rot_qpos]),
                "grasp_thumb_rotation_rad": self._grasp_thumb_rot,
                "contacts_beyond_range": self._beyond + int((self._bone > 0).sum()),
                "region_bone_N": dict(zip(names, self._bone.tolist(), strict=True))}
