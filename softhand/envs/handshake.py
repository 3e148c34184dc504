"""``softhand/Handshake-v0``: a prosthetic hand with calibrated skins shakes hands with a human partner.

The docstring of `HandshakeEnv` is the specification. The env is the two-hand touch env
(softhand.envs.touch) with the handshake scenario (softhand.envs.scenarios.handshake).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from softhand.envs.picture import CameraView
from softhand.envs.scenarios.handshake import DEFAULT_REWARD_WEIGHTS, HandshakeScenario
from softhand.envs.touch import (
    ACTION_PERIOD_S,
    DEFAULT_TIMESTEP_S,
    HANDS,
    MAX_ACTION_PERIOD_S,
    TwoHandTouchEnv,
)
from softhand.hands.config import TIMESTEP_RANGE_S, ArmConfig
from softhand.sensors.device import SensorSpec

__all__ = ["ACTION_PERIOD_S", "DEFAULT_REWARD_WEIGHTS", "DEFAULT_TIMESTEP_S", "HANDS",
           "MAX_ACTION_PERIOD_S", "TIMESTEP_RANGE_S", "HandshakeEnv"]


class HandshakeEnv(TwoHandTouchEnv):
    """Handshake between a 6-motor prosthetic right hand and a scripted human partner hand.

    The prosthetic hand (fixed, thumb up) wears a calibrated skin on each of the paper's 18 regions
    (Fig. 1: Thumb1-2, Index1-3, Middle1-3, Ring1-3, Little1-3, Palm1-2, Back1-2; 1 = proximal).
    The partner reaches with an open hand, slides its web space into the prosthetic's (whose
    thumb is pre-rotated to the grasp), closes to its grasp posture and grips to a human grip
    force, shakes at 4 Hz, lets go and leaves (`softhand.envs.partner`, published timings).
    The grasp, both postures and the partner's pose, is solved from the handshake's contacts
    (`softhand.hands.grasp`: palms together, web spaces together, each thumb over the back of
    the other's index metacarpal, the fingers wrapped round the other's ulnar border). Its hand
    rides a compliant arm (a soft weld to the scripted target); its size is ``partner_size``.
    The prosthetic hand's whole envelope is skin (the 18 regions and
    the non-sensing thenar; `softhand.hands.envelope`), the partner's is one layer of tissue;
    every contact between them is a calibrated soft contact (the skin in series with human tissue,
    fitted to 20 N, calibrated to 7 N: contacts above that are counted every step in ``info`` and
    summarised once per episode, see Warnings below). Each region's reading is a contact sensor on its skin's contacts
    inside its sensor zone (the contact side; the rest is unsensed skin), plus its bone where it
    bottoms out there. The partner regulates the summed force its phalanges feel; its grip acts
    once per action step, its arm every step.

    Action space: ``Box(-1, 1, (6,), float32)``, motor speed as a fraction of the maximum
    (positive closes; 1 = full speed, which closes a digit from open in about 1 s). Each entry's
    name and unit is in ``env.unwrapped.action_names`` (`softhand.envs.spaces`):

    - 0 `speed/pro_index_motor [fraction of max]`: index finger
    - 1 `speed/pro_middle_motor [fraction of max]`: middle finger
    - 2 `speed/pro_ring_motor [fraction of max]`: ring finger
    - 3 `speed/pro_little_motor [fraction of max]`: little finger
    - 4 `speed/pro_thumb_flex_motor [fraction of max]`: thumb flexion
    - 5 `speed/pro_thumb_rot_motor [fraction of max]`: thumb rotation (towards opposition)

    Observation space: ``Box(-inf, inf, (2 n + 19,), float64)`` with n the prosthetic hand's
    joints (16 by default); ``(2 n + 37,)`` with ``observe="both"``. Each entry's name and unit
    is in ``env.unwrapped.observation_names`` (e.g. ``qpos/pro_index_mcp [rad]``,
    ``sensor_patch/Index1 [N]``, ``episode_fraction [-]``); the 18 region values, in
    ``region_names`` order, are chosen by ``observe``:

    - [0, n) `qpos/<joint> [rad]`: prosthetic joint positions, in the model's order (pro_index_mcp,
      ...; a relaxation pad's slide joints in m)
    - [n, 2n) `qvel/<joint> [rad/s]`: prosthetic joint velocities (slides: m/s)
    - [2n, 2n + 18) `sensor_patch/<region> [N]`: observe="sensor" (default) or "both": per region,
      the reading of the region's embedded sensor on its 4 x 4 mm patch, a fraction of the region's
      load (info["sensor_readings_N"])
    - [2n, 2n + 18) `load_estimate/<region> [N]`: observe="load": per region, the load a calibrated
      read-out infers from that reading, the transfer law inverted, 0 inside a pocket's dead band
      (info["sensor_load_estimate_N"])
    - [2n, 2n + 18) `region_load/<region> [N]`: observe="contact": per region, the true normal
      contact force on the region (info["region_forces_N"])
    - [2n + 18, 2n + 36) `region_load/<region> [N]`: observe="both": per region, the true normal
      contact force on the region (info["region_forces_N"])
    - last `episode_fraction [-]`: time since the start / handshake duration

    Embedded sensors (`softhand.envs.sensing`): each region's sensor sits under its skin at
    ``sensor_placement`` (default ``interface``, under the outer layer; ``bone``;
    ``pocket-floor`` for pocketed designs; skins without an FE model get an ideal ``surface``
    sensor) and reads the force on its 4 x 4 mm patch (N): the design's transfer law of the
    region's contact force (calibration/sensors/transfer.json: sensitivity, the pocket's dead
    band, the reading's relaxation), then ``sensor``'s electronics (`SensorSpec`, default
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

    Episode end: truncated when the handshake is over (4.15 s by default,
    softhand.envs.partner.Timeline); terminated on the step whose physics diverged: MuJoCo reset
    its simulation after a bad position, velocity or acceleration (its time went back), raised
    another warning (full contact or constraint buffer, bad control), or the state is not
    finite. ``info["unstable"]`` then names the cause, the time of the last good state and the
    dof (e.g. ``MuJoCo reset the simulation after a bad acceleration (mjWARN_BADQACC) in dof 133
    (joint pro_skin_Little1_pad) at t = 1.328 s``; False
    on every other step), ``info["time_s"]`` is that time, the observation is zeros, the reward
    -100 and the forces those of the last good step. ``run_handshake`` raises
    ``DivergenceError`` (softhand.envs.physics) with it; ``softhand handshake`` exits 3.

    Timestep: allowed 0.1-5 ms (``TIMESTEP_RANGE_S``); the skins are calibrated for 0.5-2 ms
    (their rest laws hold at every step in that range) and warn (``SkinRangeWarning``) outside it.
    2 ms, the default, reproduces the region forces of 0.5 ms within a few percent for all three
    controllers and runs faster than 1 ms (``softhand bench handshake``, speed and error against
    0.5 ms for each timestep: ``reports/bench-handshake.md``).

    ``info``: ``region_forces_N`` (dict region -> N, the true contact forces, always: the
    region's skin inside its sensor zone and its bone bottoming out there, flagged in
    ``region_bone_N`` and counted in ``contacts_beyond_range``, since bone on bone is outside every
    law's calibration),
    ``sensor_readings_N`` (dict region -> N on the sensor patch), ``sensor_load_estimate_N``
    (dict region -> N: the load a calibrated read-out infers from the reading by inverting the
    transfer law's static curve; 0 inside a dead band), ``phase`` (reach, grip, shake, hold, release,
    return, done), ``reward_terms`` (dict), ``time_s``, ``partner_grip_N`` (the target of the
    partner's summed digit force: its sampled grip per phalanx times ``GRIP_PHALANGES``),
    ``partner_grip_measured_N`` (that sum, measured), ``partner_effort_rad`` (its grip
    effort), ``grasp_thumb_rotation_rad`` (the solved grasp's prosthetic thumb rotation),
    ``pairs_beyond_range_N`` (dict pair -> N: the contact pairs above their law's calibrated
    range at this step; usually empty); on the episode's last step only,
    ``beyond_range_summary`` (see Warnings).

    Warnings: one ``CalibratedRangeWarning`` per episode that had contacts beyond their pair
    law's calibrated range (or a bone bottoming out), issued on the step that ends it (truncated
    or terminated), or by ``reset()`` or ``close()`` when they cut an episode short, and
    attributed to the code that called it (through Gymnasium's wrappers too). It summarises
    ``info["beyond_range_summary"]``: ``contact_steps`` (pair contacts beyond range summed over
    the steps), ``pairs``, ``bone_steps`` (together with ``contact_steps``: the sum of
    ``contacts_beyond_range``), the worst pair (largest force over its limit: ``worst_pair``,
    ``worst_skin``, ``worst_force_N``, ``worst_limit_N``, ``worst_time_s``), ``steps`` and
    ``time_s``. At construction, skin pairs outside their calibration (a timestep outside
    0.5-2 ms) give one ``SkinRangeWarning``: per kind of problem, how many pairs and the worst.

    Skin representations (`softhand.skin.representations`; ``representation`` for every
    region, ``skins`` values ``DESIGN@REPRESENTATION`` for one):

    * ``soft-contact`` (default): each pair carries the skin's law in series with the tissue's in
      its solref/solimp (no memory: the 0.5 mm/s loading curve);
    * ``soft-contact+relaxation``: each skin geom rides a relaxation pad (a slide joint along its
      outward normal, the QLV law's spline spring and Maxwell branches, joint armature 10 g,
      `HandPad`), its pairs carry the tissue's law alone
      (skin and tissue in series mechanically). Runs under the scene's ``implicitfast`` at
      0.5-2 ms, at a higher cost per step (2 Prony terms x 6 branch knots + 1 dofs per skin geom;
      its cost against ``rigid``: ``softhand bench handshake``, ``reports/bench-handshake.md``);
      refused above 2 ms, the timestep its pads are tested at under a hard grip (their
      explicitly integrated spring is stable inside the calibrated 7 N up to 2.48-2.96 ms, but a
      squeeze-5 grip loads regions to 12-45 N: ``softhand.envs.skins.check_pad_timestep``).
      The pad compresses along its normal only: a contact from the side (the palm's borders, a
      thumb's side) meets the tissue's law alone, and the force accounting says how much of the
      force went through the pads (HandshakeRun.force_accounting,
      ``softhand handshake --representation soft-contact+relaxation --json``);
      HandshakeRun.relaxation() measures each pad against the QLV law;
    * ``rigid``: MuJoCo's stock contact against the tissue (only the tissue indents).

    ``flex`` is refused: it needs the ``discrete`` integrator, under which the soft contacts do
    not hold; a flex region has its own scene (softhand.hands.flex_region).

    Args (None, where allowed, is the default; an empty string never is):
        design: skin of every region, one of ``SKIN_CHOICES`` (a design such as
            ``pocket2-sil``, ``prosthetic-102l`` or ``rigid``); default: the most lifelike design.
        skins: mapping of region (Fig. 1 names) -> skin override, ``DESIGN`` or
            ``DESIGN@REPRESENTATION`` (strings).
        representation: representation of every region, one of ``HAND_REPRESENTATIONS``;
            default ``soft-contact``.
        frame_skip: physics steps per action, an integer >= 1 with frame_skip x timestep_s <=
            0.1 s (actions at 10 Hz or faster); default: the most physics steps that fit in
            ``ACTION_PERIOD_S`` (10 ms: 5 steps of 2 ms; 3 of 2.75 ms, an 8.25 ms action step,
            so that the sensors' default 10 ms sampling is never finer than the env step).
        timestep_s: physics timestep, in [0.0001, 0.005] s (``TIMESTEP_RANGE_S``; the skins are
            calibrated at 0.0005-0.002 s); default 2 ms (SceneConfig).
        squeeze: multiplier of the partner's grip force, in (0, 5]: 5 is the hard case and the
            partner's hardest grip (``MAX_SQUEEZE``: above about 3 its grip effort reaches its
            limit and from 4 up the forces no longer follow the squeeze;
            softhand.envs.partner.MAX_SQUEEZE has the measurements).
        overload_N: region force (N) above which the overload penalty applies, finite and > 0.
        reward_weights: mapping, override of ``DEFAULT_REWARD_WEIGHTS`` entries, each finite and
            >= 0 (a weight is a magnitude: the sign of each term is fixed above).
        calibration_dir: folder of the skin calibration files, a non-empty path (default: the
            shipped ones); every skin used is read and checked before the scene is built.
        randomize: True or False: vary the partner (timing +-5 %, grip +-10 %, shake phase)
            from the seed.
        sensor: the sensors' electronics, a `SensorSpec` (default
            `FLEXIFORCE_A101`); the noise is drawn from the episode's seed.
        sensor_placement: one placement for every region (``bone``, ``interface`` or
            ``pocket-floor``), or a mapping region -> placement (the rest ``interface``).
        observe: ``sensor`` (default: the sensor patches' readings), ``load`` (the calibrated
            read-out's load estimates), ``contact`` (the true region loads) or ``both`` (the
            readings, then the true loads); see the observation space.
        sensor_dir: folder of ``transfer.json``, a non-empty path (default: the shipped
            ``calibration/sensors``).
        sensored_arm, partner_arm: the arms the two hands ride (`softhand.hands.ArmConfig`:
            endpoint stiffness, damping, rotational stiffness, moving mass and palm press, each
            checked against softhand.hands.config.ARM_RANGES); None: the prosthesis user's arm
            (``hand="prosthetic"``) or the experimenter's relaxed arm (``hand="human"``), and the
            partner's active arm (softhand.hands.constants.ARMS).
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
        contact_laws: ``geometry`` (default): each skin pair takes the law of its contact class,
            its two geoms' shapes (a phalanx or a palm piece, pressed by a finger or a flat;
            `softhand.skin.contact_classes`); ``plate``: every pair the paper's plate
            protocol. ``env.unwrapped.pair_laws`` names the law of every pair.
        render_mode: None (default) or ``rgb_array``: `render` returns the state as an
            (H, W, 3) uint8 picture, ``softhand render``'s (offscreen ``mujoco.Renderer``; needs
            ``MUJOCO_GL=egl`` or ``osmesa`` set before mujoco is imported, without a display),
            one per env step at ``metadata["render_fps"]`` (100 by default), so that Gymnasium's
            wrappers take it (``RenderCollection``; ``RecordVideo`` with moviepy installed).
        render_size: (width, height) of the picture, each 64-4096 pixels; default (640, 480).
        render_view: the camera, a `CameraView`; default
            ``softhand render``'s (``RENDER_VIEW``: azimuth 150 deg, elevation -30 deg, 0.3 m
            from the hands).

    Raises:
        ValueError: at construction, a bad argument or calibration file, naming it, the value
            and the allowed range, before any model is built; in `reset`, a bad seed or
            option (``options``: ``grip_N`` per phalanx in [1e-6, 12.5] N, ``duration_s`` in
            [2, 6] s, ``shake_phase_rad`` in [-2 pi, 2 pi]); in `step`, an action that is not
            6 finite real numbers in [-1, 1] (a numpy masked array with masked entries included:
            the data under a mask is arbitrary).
        RuntimeError: `step` before `reset` or after the episode ended;
            `step`, `reset` or `render` after `close`; `render`
            without a render mode.

    Physics: every MuJoCo call of an episode goes through `physics`
    (`MujocoPhysics`), the seam the batched backend implements
    (`BatchPhysics`, for ``gymnasium.make_vec(...,
    vectorization_mode="vector_entry_point")``: `HandshakeVectorEnv`).
    Structure: this is the generic `TwoHandTouchEnv` with the
    handshake scenario (`scenario`, `HandshakeScenario`:
    the partner's script, the phases, the reward); another touch is another scenario.

    Version history: v0 (softhand 0.1, unreleased): first release; before the release the default
    timestep went from 1 to 2 ms and the partner's joints got armature (region forces changed);
    ``observe="load"``, ``observation_names``, ``action_names`` and ``render_mode="rgb_array"``
    were added (the default observation is unchanged).
    """

    def __init__(self, *, design: str | None = None, skins: Mapping[str, str] | None = None,
                 representation: str | None = None, frame_skip: int | None = None,
                 timestep_s: float = DEFAULT_TIMESTEP_S, squeeze: float = 1.0,
                 overload_N: float = 10.0, reward_weights: Mapping[str, float] | None = None,
                 calibration_dir: str | Path | None = None, randomize: bool = True,
                 sensor: SensorSpec | None = None,
                 sensor_placement: str | Mapping[str, str] | None = None,
                 observe: str = "sensor", sensor_dir: str | Path | None = None,
                 partner_size: tuple[float, float] | None = None,
                 hand: str = "prosthetic", contact_laws: str = "geometry",
                 render_mode: str | None = None, render_size: tuple[int, int] = (640, 480),
                 render_view: CameraView | None = None, sensored_arm: ArmConfig | None = None,
                 partner_arm: ArmConfig | None = None) -> None:
        scenario = HandshakeScenario(squeeze=squeeze, overload_N=overload_N,
                                     reward_weights=reward_weights, randomize=randomize)
        super().__init__(scenario=scenario, design=design, skins=skins,
                         representation=representation, frame_skip=frame_skip,
                         timestep_s=timestep_s, calibration_dir=calibration_dir, sensor=sensor,
                         sensor_placement=sensor_placement, observe=observe,
                         sensor_dir=sensor_dir, partner_size=partner_size, hand=hand,
                         contact_laws=contact_laws, render_mode=render_mode,
                         render_size=render_size, render_view=render_view,
                         sensored_arm=sensored_arm, partner_arm=partner_arm)
