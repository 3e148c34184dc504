"""Typed, validated configuration of the two hands and the handshake scene (SI units throughout).

Each dataclass is frozen and checks its fields on construction: a bad value raises one
``ValueError`` that names the field, quotes the value and gives the allowed range.
Defaults come from the paper (hand length and width, ``softhand.paper``) and from
``softhand.hands.constants`` (everything else, each with its reference).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from softhand.hands import constants as const
from softhand.paper import paper
from softhand.validate import check_number

__all__ = ["ACTUATIONS", "ARM_RANGES", "PALM_SKINS", "TIMESTEP_RANGE_S", "ArmConfig", "HandConfig",
           "PartnerConfig", "ProstheticConfig", "SceneConfig"]

#: Allowed simulation timestep of the handshake scene, closed interval (s). The skins were
#: calibrated and are tested at 0.5-2 ms (``softhand.skin.rig.CHECKED_TIMESTEPS_S``; the env tests
#: run 0.5, 1 and 2 ms); outside that band, inside this range, every skin pair is outside its
#: checked range (one ``SkinRangeWarning`` for the scene, counting them). 5 ms: the rig's impact
#: and overload test stays bounded there and a handshake with each controller stays finite, but
#: its forces are not checked against 0.5 ms.
#: 0.1 ms: five times finer than the reference step; an episode precomputes one mount target per
#: physics step (36,300 at 0.1 ms, under 1 MB), so a smaller step would grow without bound.
TIMESTEP_RANGE_S = (1e-4, 5e-3)
#: How the sensored hand's 6 drives act (ProstheticConfig.actuation).
ACTUATIONS = ("motors", "relaxed-human")
#: How the prosthetic palm's skin is made (`ProstheticConfig.palm`): ``surface`` one continuous
#: skin (palmar face, borders, back) whose regions are zones; ``quarters`` four skins (palmar /
#: dorsal x proximal / distal), one per region, each able to ride its own relaxation pad
PALM_SKINS = ("surface", "quarters")


def _paper_mm(key: str) -> float:
    return float(paper()["anthropometry"][key]) / 1000.0


def _check(name: str, value: float, lo: float, hi: float, unit: str) -> None:
    """Raise ValueError unless ``lo < value < hi`` (open interval) and finite."""
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise ValueError(f"{name} = {value!r}: expected a number in {unit}")
    if not (math.isfinite(value) and lo < value < hi):
        raise ValueError(f"{name} = {value!r} {unit}: allowed range ({lo}, {hi}) {unit}")


#: Allowed range of each ArmConfig field, closed intervals (units in the field names). The
#: stiffness covers relaxed to strongly co-contracted arms (tens of N/m to a few kN/m at the hand,
#: [Tsuji95], [Perreault04] in softhand.hands.constants); the press stays under the skins'
#: calibrated 20 N.
ARM_RANGES = {
    "stiffness_n_per_m": (20.0, 5000.0),
    "damping_ns_per_m": (0.5, 200.0),
    "rot_stiffness_nm_per_rad": (0.1, 50.0),
    "mass_kg": (0.05, 5.0),
    "press_n": (0.0, 10.0),
}


@dataclass(frozen=True)
class ArmConfig:
    """The arm a hand rides: its endpoint impedance at the wrist and its push on the palm.

    The hand's wrist body is free and held to its arm's anchor (a fixed point for the sensored
    hand, the scripted mount for the partner) by a spring-damper of these constants, as a
    person's arm holds the hand (softhand.hands.scene). Each field is checked against
    `ARM_RANGES`.

    Attributes:
        stiffness_n_per_m: translational endpoint stiffness at the wrist, isotropic (N/m).
        damping_ns_per_m: translational endpoint damping (N s/m).
        rot_stiffness_nm_per_rad: rotational stiffness of the hand about the wrist (N m/rad).
        mass_kg: the arm's mass moving with the wrist, besides the hand's own (kg).
        press_n: the arm's push of its palm towards the other hand's, along its palm normal (N):
            the anchor lies press / stiffness beyond the hand's place in the grasp.
    """

    stiffness_n_per_m: float
    damping_ns_per_m: float
    rot_stiffness_nm_per_rad: float
    mass_kg: float
    press_n: float = const.PALM_PRESS_N

    def __post_init__(self) -> None:
        for key, (lo, hi) in ARM_RANGES.items():
            check_number(f"arm {key}", getattr(self, key), lo=lo, hi=hi,
                         why="(softhand.hands.config.ARM_RANGES)")

    @classmethod
    def of(cls, kind: str, **changes: float) -> ArmConfig:
        """The arm ``kind`` of softhand.hands.constants.ARMS (``relaxed``, ``prosthesis-user``,
        ``active``), with ``changes`` over its fields."""
        if kind not in const.ARMS:
            raise ValueError(f"arm {kind!r} is unknown; allowed: {', '.join(const.ARMS)}")
        return cls(**{**dict(const.ARMS[kind]), **changes})


@dataclass(frozen=True)
class HandConfig:
    """Anthropometry of one adult right hand.

    Attributes:
        hand_length_m: distal wrist crease to the tip of the middle finger (m). Default: the
            paper's experimenter, Table 1 (190 mm).
        hand_width_m: breadth across the metacarpal heads, radial edge of the index MCP to the ulnar
            edge of the little MCP (m). Default: paper Table 1 (88 mm).
        palm_thickness_m: dorsal to palmar skin at the metacarpals (m). None: 0.16 x hand length
            (constants.PALM_THICKNESS_RATIO, an assumption).
        skin_thickness_m: soft layer over the rigid bone (m): bones are this much smaller than the
            segment envelope, so skins and tissues touch first. None (default): 6 mm, or the
            thinnest phalanx envelope less a 1.2 mm bone radius where that is less (a small hand,
            -2.5 SD of the paper's subjects). 6 mm: deeper than the skin
            and the human tissue each indent at a handshake's forces (pocket2-sil 2.7 mm and the
            human finger 3.7 mm at 2 N, so bones meet only past about 12 mm together); the
            paper's phalanx skins are 9 mm of elastomer on a rigid base (assumption for the hand).
        density_kg_m3: tissue density for segment masses = density x envelope volume (kg/m^3).
    """

    hand_length_m: float = field(default_factory=lambda: _paper_mm("experimenter_hand_length_mm"))
    hand_width_m: float = field(default_factory=lambda: _paper_mm("experimenter_hand_width_mm"))
    palm_thickness_m: float | None = None
    skin_thickness_m: float | None = None
    density_kg_m3: float = const.DENSITY_KG_M3

    def __post_init__(self) -> None:
        _check("hand_length_m", self.hand_length_m, 0.10, 0.30, "m")
        _check("hand_width_m", self.hand_width_m, 0.05, 0.15, "m")
        ratio = self.hand_width_m / self.hand_length_m
        if not 0.30 < ratio < 0.70:
            raise ValueError(
                f"hand_width_m / hand_length_m = {ratio:.3f} ({self.hand_width_m!r} m / "
                f"{self.hand_length_m!r} m): allowed range (0.3, 0.7)"
            )
        if self.palm_thickness_m is not None:
            _check("palm_thickness_m", self.palm_thickness_m, 0.01, 0.06, "m")
        if self.skin_thickness_m is not None:
            _check("skin_thickness_m", self.skin_thickness_m, 0.0, 0.3 * self.thickness_m, "m")
        _check("density_kg_m3", self.density_kg_m3, 100.0, 5000.0, "kg/m^3")

    @property
    def thickness_m(self) -> float:
        """Palm thickness actually used (m)."""
        if self.palm_thickness_m is not None:
            return self.palm_thickness_m
        return const.PALM_THICKNESS_RATIO * self.hand_length_m


@dataclass(frozen=True)
class ProstheticConfig:
    """A commercial-class multi-articulating prosthetic right hand (6 motors).

    Attributes:
        hand: anthropometry of the hand shell.
        closing_time_s: time for a finger motor to close its finger from fully open to fully
            flexed at full command (s); sets each motor's speed limit ([Belter13] ~1 s).
        thumb_rotation_time_s: time for the thumb rotation motor to sweep its range (s).
        grip_force_n: maximum power-grip force (N); sets the motors' stall torques ([Belter13]).
        stall_deflection_rad: servo deflection at stall torque (rad); sets the servo stiffness.
        armature_kg_m2: reflected rotor inertia on each motor-driven joint (kg m^2).
        actuation: ``motors`` (the prosthetic hand's 6 non-back-drivable motors) or
            ``relaxed-human`` (the same hand as the paper's sensored human hand: the 6 drives are
            soft position servos, constants.RELAXED_HUMAN, and hold a posture the env sets).
        palm: the palm's skin (PALM_SKINS): ``surface`` (default) one continuous skin, Palm1,
            Palm2, Back1 and Back2 its zones, so that no seam lies under a finger on the palm's
            border; ``quarters`` one skin per region, which a relaxation pad needs (a pad is one
            rigid body on one slide: a surface pressed from both faces would only feel the
            difference of the two pushes), at the price of seams at the borders and mid-palm.
    """

    hand: HandConfig = field(default_factory=HandConfig)
    closing_time_s: float = const.PROSTHETIC["closing_time_s"]
    thumb_rotation_time_s: float = const.PROSTHETIC["closing_time_s"]
    grip_force_n: float = const.PROSTHETIC["grip_force_n"]
    stall_deflection_rad: float = const.PROSTHETIC["stall_deflection_rad"]
    armature_kg_m2: float = const.PROSTHETIC["armature_kg_m2"]
    actuation: str = "motors"
    palm: str = "surface"

    def __post_init__(self) -> None:
        if self.actuation not in ACTUATIONS:
            raise ValueError(f"actuation = {self.actuation!r}: allowed {', '.join(ACTUATIONS)}")
        if self.palm not in PALM_SKINS:
            raise ValueError(f"palm = {self.palm!r}: allowed {', '.join(PALM_SKINS)}")
        _check("closing_time_s", self.closing_time_s, 0.05, 10.0, "s")
        _check("thumb_rotation_time_s", self.thumb_rotation_time_s, 0.05, 10.0, "s")
        _check("grip_force_n", self.grip_force_n, 0.0, 1000.0, "N")
        _check("stall_deflection_rad", self.stall_deflection_rad, 0.0, 0.5, "rad")
        _check("armature_kg_m2", self.armature_kg_m2, -1e-12, 1e-2, "kg m^2")


@dataclass(frozen=True)
class PartnerConfig:
    """The partner's human right hand, driven by a scripted grip.

    Attributes:
        hand: anthropometry of the partner's hand.
        max_grip_force_n: maximal grip force (N); caps the finger flexion actuators.
        finger_kp_nm_per_rad: stiffness of an MCP joint's impedance servo (N m/rad); the other
            digit joints get a share of it (softhand.hands.partner.JOINT_KP_SHARE).
        wrist_kp_nm_per_rad: wrist servo stiffness (N m/rad).
        wrist_torque_nm: wrist actuator torque limit (N m).
        joint_damping_nm_s_per_rad: damping of each finger joint (N m s/rad); the wrist has 10x.
        mechanical_time_constant_s: each partner joint gets armature = damping x this (kg m^2), so
            that no joint relaxes faster than the largest supported timestep (constants.PARTNER).
        forearm_length_m: length of the rigid forearm stub between the mount and the wrist (m).
    """

    hand: HandConfig = field(default_factory=HandConfig)
    max_grip_force_n: float = const.PARTNER["max_grip_force_n"]
    finger_kp_nm_per_rad: float = const.PARTNER["finger_kp_nm_per_rad"]
    wrist_kp_nm_per_rad: float = const.PARTNER["wrist_kp_nm_per_rad"]
    wrist_torque_nm: float = const.PARTNER["wrist_torque_nm"]
    joint_damping_nm_s_per_rad: float = const.PARTNER["joint_damping_nm_s_per_rad"]
    mechanical_time_constant_s: float = const.PARTNER["mechanical_time_constant_s"]
    forearm_length_m: float = 0.10

    def __post_init__(self) -> None:
        _check("max_grip_force_n", self.max_grip_force_n, 0.0, 2000.0, "N")
        _check("finger_kp_nm_per_rad", self.finger_kp_nm_per_rad, 0.0, 100.0, "N m/rad")
        _check("wrist_kp_nm_per_rad", self.wrist_kp_nm_per_rad, 0.0, 1000.0, "N m/rad")
        _check("wrist_torque_nm", self.wrist_torque_nm, 0.0, 100.0, "N m")
        _check(
            "joint_damping_nm_s_per_rad", self.joint_damping_nm_s_per_rad, 0.0, 10.0, "N m s/rad"
        )
        _check("mechanical_time_constant_s", self.mechanical_time_constant_s, -1e-12, 0.1, "s")
        _check("forearm_length_m", self.forearm_length_m, 0.0, 0.5, "m")


@dataclass(frozen=True)
class SceneConfig:
    """The handshake scene: options, the two hands and the arms they ride.

    World frame: +X is the prosthetic hand's pointing direction, +Z up, gravity along -Z.
    The prosthetic hand is in a handshake pose: thumb up, palm facing +Y. The partner hand faces it:
    fingers along -X, thumb up, palm facing -Y.

    Attributes:
        prosthetic: the prosthetic hand.
        partner: the partner's hand.
        timestep_s: simulation time step (s), in [0.0001, 0.005] (`TIMESTEP_RANGE_S`; the
            skins are calibrated and tested at 0.0005-0.002 and warn outside it). Default 2 ms: the
            handshake's region forces agree with 0.5 ms within a few percent, and it runs faster
            than 1 ms (both measured by ``softhand bench handshake``,
            ``reports/bench-handshake.md``).
        gravity_m_s2: magnitude of gravity, along -Z (m/s^2).
        sensored_arm: the arm the sensored hand rides; None (default): the prosthesis user's
            (``ArmConfig.of("prosthesis-user")``) for the prosthetic's motors, the experimenter's
            relaxed arm (``"relaxed"``) for ``actuation="relaxed-human"`` (the paper's protocol).
            `arm` gives the one in use.
        partner_arm: the partner's arm (default ``ArmConfig.of("active")``): its mount follows
            the script, the hand follows the mount through this impedance.
        prosthetic_wrist_pos_m: world position of the prosthetic hand's wrist-crease origin (m),
            the sensored arm's rest place in the grasp.
        crossing_angle_deg: starting angle of the grasp solve (softhand.hands.grasp) between the
            two hands' long axes in the plane of the touching palms, from antiparallel (0) to
            crossed at right angles (90), in degrees, shared equally
            by the two hands. In a handshake each hand tilts ulnarly, its fingers pointing forward
            and down, so that each hand's fingers wrap around the other's ulnar border onto its
            back. Default 60 (30 deg of tilt per hand, each forearm 30 deg from horizontal): an
            assumption, no published measurement found.
        partner_start_offset_m: partner mount start position relative to its contact pose (m, in
            the partner's hand frame: +x distal, +y radial, +z dorsal); the env moves the mocap
            from there to the contact pose (reach) and back. Default: 150 mm back along the
            forearm and 20 mm off the palm: the partner slides its hand in along its own axis,
            web space into web space, under the prosthetic's pre-rotated thumb (from 100 mm off
            the palm it swept into that thumb: 18 N bone on bone, 18 % of the force inside the
            laws' range; from 20 mm, 0.7 N and 92 %, seed 0, neutral).
    """

    prosthetic: ProstheticConfig = field(default_factory=ProstheticConfig)
    partner: PartnerConfig = field(default_factory=PartnerConfig)
    sensored_arm: ArmConfig | None = None
    partner_arm: ArmConfig = field(default_factory=lambda: ArmConfig.of("active"))
    timestep_s: float = 0.002
    gravity_m_s2: float = 9.81
    prosthetic_wrist_pos_m: tuple[float, float, float] = (0.0, 0.0, 1.0)
    crossing_angle_deg: float = 60.0
    partner_start_offset_m: tuple[float, float, float] = (-0.15, 0.0, 0.02)

    def __post_init__(self) -> None:
        check_number("timestep_s", self.timestep_s, lo=TIMESTEP_RANGE_S[0], hi=TIMESTEP_RANGE_S[1],
                     why="s (skins calibrated at 0.0005-0.002 s)")
        _check("gravity_m_s2", self.gravity_m_s2, -1e-12, 100.0, "m/s^2")
        _check("crossing_angle_deg", self.crossing_angle_deg, -1e-12, 90.0 + 1e-12, "deg")
        for name in ("sensored_arm", "partner_arm"):
            value = getattr(self, name)
            if not (isinstance(value, ArmConfig) or (value is None and name == "sensored_arm")):
                raise ValueError(f"{name} = {value!r}: expected an ArmConfig")
        for name in ("prosthetic_wrist_pos_m", "partner_start_offset_m"):
            value = getattr(self, name)
            if len(value) != 3:
                raise ValueError(f"{name} = {value!r}: expected 3 coordinates in m")
            for i, v in enumerate(value):
                _check(f"{name}[{i}]", v, -10.0, 10.0, "m")

    @property
    def arm(self) -> ArmConfig:
        """The sensored hand's arm in use (`sensored_arm`, or its default for the actuation)."""
        if self.sensored_arm is not None:
            return self.sensored_arm
        relaxed = self.prosthetic.actuation == "relaxed-human"
        return ArmConfig.of("relaxed" if relaxed else "prosthesis-user")
