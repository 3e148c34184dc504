"""The partner's human right hand, on a mount the env moves (a mocap body), driven by a scripted grip.

Structure under the mount (``parent_body``, whose frame is the partner's hand frame at zero wrist
angles): ``forearm`` (a rigid stub, no joints) then ``palm`` with two wrist joints
(``wrist_flex``: flexion positive; ``wrist_dev``: radial deviation positive), thumb and fingers
with human joint ranges ([AAOS65], constants.AAOS_RANGE_DEG, hyperextension included).

Actuation: joint impedance, 18 position servos (ctrl is a target angle in rad): one per digit
joint (``{prefix}{joint}`` for each of PARTNER_JOINTS: thumb rot, cmc, mcp, ip; each finger's mcp,
pip, dip), then ``wrist_flex`` and ``wrist_dev``. The env's partner script
(`softhand.envs.partner`) sets the targets: an open hand on the reach, the solved grasp
posture (`softhand.hands.grasp`) plus a grip effort (a flexion offset on every digit joint,
regulated to the sampled grip force) while it holds the other hand. A servo's stiffness is
PartnerConfig.finger_kp_nm_per_rad x JOINT_KP_SHARE of its joint; torques are capped at the
maximal grip force shared by four fingers acting at the proximal phalanx ([Mathiowetz85]).

Contact geoms: ``tissue_{piece}`` (contacts with the other hand only through explicit
``<pair>`` elements; the thumb's and the fingers' phalanx tissues also touch each other, through
MuJoCo's own contacts, `constants.PARTNER_SELF_BITS`, with a stiff soft contact, `SELF_SOLREF`,
so that the thumb does not pass through the fingers): the hand's soft envelope as one layer of convex pieces
(`softhand.hands.envelope`, the same construction as the prosthetic's skin): a trimmed capsule
on the thumb metacarpal (thenar) and on every phalanx, and the palm's convex hull as one piece,
``tissue_palm`` (palmar and dorsal sides and borders: the grasp's fingers wrap the ulnar border,
where a seam between two pieces resisted one indentation twice). No point lies inside two tissue
geoms at rest, so no indentation is resisted by two laws at once.
The forearm stub wears ``tissue_forearm``, a capsule of the forearm's radius over its bone (the
skin's thickness of soft tissue, taken as the hand's: assumption, no forearm indentation data
used), so that a sensored finger meeting the partner's wrist meets tissue, not a bare bone; the
grasp's targets leave it out (softhand.hands.grasp sees the hand's pieces only).
List them with partner_tissue_geoms(). Each has a contact sensor ``feel_{piece}`` on its contacts
(one net-force slot: found, force xyz in the world frame): what the partner feels there (the
scene narrows it to the other hand's contacts, `softhand.hands.scene`: its own thumb on its
fingers is not the grip it regulates). Rigid bones (``bone_*``) collide with the prosthetic bones.
"""

from __future__ import annotations

import math
from types import MappingProxyType

import mujoco

from softhand.hands import constants as const
from softhand.hands.config import PartnerConfig
from softhand.hands.envelope import hand_pieces
from softhand.hands.layout import hand_layout
from softhand.hands.skeleton import (
    add_contact_sensor,
    add_piece,
    add_skeleton,
    angle,
    joint_key,
    new_spec,
)

__all__ = [
    "FOREARM_TISSUE",
    "JOINT_KP_SHARE",
    "PARTNER_JOINTS",
    "TISSUE_SEGMENTS",
    "add_partner_hand",
    "build_partner_hand",
    "partner_actuators",
    "partner_tissue_geoms",
]

_CAPSULE = mujoco.mjtGeom.mjGEOM_CAPSULE
_TRUE = mujoco.mjtLimited.mjLIMITED_TRUE
_BONE_RGBA = (0.55, 0.42, 0.38, 1.0)
_TISSUE_RGBA = (0.87, 0.68, 0.58, 0.5)

#: Segments carrying a tissue geom, in the order partner_tissue_geoms() returns them.
TISSUE_SEGMENTS: tuple[str, ...] = (
    "palm",
    "thumb_metacarpal",
    "thumb_proximal",
    "thumb_distal",
    *(f"{f}_{seg}" for f in const.FINGERS for seg in ("proximal", "middle", "distal")),
)
#: solref (time constant s, damping ratio) of the thumb's contacts with the fingers
#: (`constants.PARTNER_SELF_BITS`): MuJoCo's default 20 ms, scaled by a phalanx's small inertia,
#: let the grip's servos push the thumb tip 3.9 mm into the middle fingertip; 4 ms, two steps of
#: the handshake's 2 ms (the stiffest MuJoCo integrates there: it clamps shorter ones to two
#: steps), holds it to 0.7-0.9 mm (seeds 0, 1, 4). A stop, not the tissues' law: what the
#: partner's thumb presses on its own fingers is not part of the study.
SELF_SOLREF: tuple[float, float] = (0.004, 1.0)

#: The forearm's tissue (a capsule over the forearm stub's bone, module docstring): a tissue geom
#: of the scene, not a piece of the hand's envelope.
FOREARM_TISSUE = "forearm"

#: The partner's digit joints (short names), thumb first: the order of its digit servos.
PARTNER_JOINTS: tuple[str, ...] = (
    "thumb_rot", "thumb_cmc", "thumb_mcp", "thumb_ip",
    *(f"{f}_{j}" for f in const.FINGERS for j in ("mcp", "pip", "dip")),
)
#: Stiffness of each joint's servo as a share of PartnerConfig.finger_kp_nm_per_rad. assumption: in
#: proportion to the lever of a load on the digit's pad (a pad load 1/2 and 1/4 of the way from
#: the tip loads the distal joints less), so that a grip effort flexes every joint alike.
JOINT_KP_SHARE = MappingProxyType({"mcp": 1.0, "pip": 0.6, "dip": 0.35, "rot": 1.0, "cmc": 1.0,
                                   "ip": 0.35})

_DIGIT_JOINTS = {"thumb": ("cmc", "mcp", "ip"), **{f: ("mcp", "pip", "dip") for f in const.FINGERS}}


def partner_actuators(prefix: str = "hum_") -> tuple[str, ...]:
    """Names of the 18 partner servos, in ctrl order: the digit joints (PARTNER_JOINTS), then
    ``wrist_flex`` and ``wrist_dev``."""
    return (*(f"{prefix}{j}" for j in PARTNER_JOINTS), f"{prefix}wrist_flex", f"{prefix}wrist_dev")


def _servo(
    spec: mujoco.MjSpec,
    name: str,
    target: str,
    trn: mujoco.mjtTrn,
    *,
    kp: float,
    lo: float,
    hi: float,
    torque: float,
) -> None:
    act = spec.add_actuator(name=name, target=target, trntype=trn)
    act.set_to_position(kp=kp, dampratio=1.0)
    act.ctrllimited, act.ctrlrange = _TRUE, [lo, hi]
    act.forcelimited, act.forcerange = _TRUE, [-torque, torque]


def add_partner_hand(
    spec: mujoco.MjSpec,
    parent_body: mujoco.MjsBody,
    config: PartnerConfig | None = None,
    prefix: str = "hum_",
) -> mujoco.MjsBody:
    """Add the partner's right hand under ``parent_body`` (normally a mocap body).

    Args:
        spec: the spec to edit.
        parent_body: mount whose frame is the partner's hand frame at zero wrist angles (origin at
            the wrist crease, +x distal, +y radial, +z dorsal).
        config: the partner; default PartnerConfig().
        prefix: prefix of every element name.

    Returns:
        The palm body.
    """
    config = config or PartnerConfig()
    if not isinstance(config, PartnerConfig):
        raise ValueError(f"config = {config!r}: expected a PartnerConfig")
    layout = hand_layout(config.hand)
    rng = const.AAOS_RANGE_DEG
    skin, t = layout.skin_m, layout.thickness_m

    # Forearm stub (rigid, massless: it moves with the mount) and wrist joints on the palm.
    forearm = parent_body.add_body(name=f"{prefix}forearm")
    r_arm = 0.6 * t  # assumption: forearm near the wrist ~ 1.2 palm thicknesses across
    if config.forearm_length_m > r_arm:
        forearm.add_geom(
            name=f"{prefix}bone_forearm",
            type=_CAPSULE,
            size=[r_arm - skin, 0, 0],
            fromto=[-config.forearm_length_m, 0, 0, -r_arm, 0, 0],
            mass=0.0,
            contype=const.BONE_BITS["partner"][0],
            conaffinity=const.BONE_BITS["partner"][1],
            rgba=list(_BONE_RGBA),
        )
        # its tissue ends where the palm's begins (the wrist crease, x = 0): the capsule's cap
        # reaches x = 0 from its end at -r_arm
        forearm.add_geom(name=f"{prefix}tissue_{FOREARM_TISSUE}", type=_CAPSULE, size=[r_arm, 0, 0],
                         fromto=[-config.forearm_length_m, 0, 0, -r_arm, 0, 0], mass=0.0,
                         contype=0, conaffinity=0, group=2, rgba=list(_TISSUE_RGBA))
        add_contact_sensor(spec, f"{prefix}feel_{FOREARM_TISSUE}",
                           f"{prefix}tissue_{FOREARM_TISSUE}", netforce=True)

    # Armature = damping x mechanical time constant (constants.PARTNER: why). No passive springs:
    # each joint's impedance is its servo (below).
    damping = config.joint_damping_nm_s_per_rad
    armature = damping * config.mechanical_time_constant_s
    options = {joint_key(digit, short): {"damping": [damping, 0.0, 0.0], "armature": armature}
               for digit, shorts in _DIGIT_JOINTS.items() for short in shorts}
    options["thumb_rot"] = {"damping": [damping, 0.0, 0.0], "armature": armature}
    skel = add_skeleton(
        spec,
        forearm,
        layout,
        prefix=prefix,
        ranges_deg=rng,
        bone_bits=const.BONE_BITS["partner"],
        bone_rgba=_BONE_RGBA,
        joint_options=options,
    )
    palm = skel.bodies["palm"]
    for short, axis in (("flex", (0.0, 1.0, 0.0)), ("dev", (0.0, 0.0, 1.0))):
        lo, hi = rng[f"wrist_{short}"]
        palm.add_joint(
            name=f"{prefix}wrist_{short}",
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=list(axis),
            range=[angle(spec, math.radians(lo)), angle(spec, math.radians(hi))],
            damping=[10 * damping, 0.0, 0.0],
            armature=10 * armature,
        )

    # Tissues: one layer of envelope pieces, each with the sensor of what the partner feels there.
    pieces = {p.name: p for p in hand_pieces(layout, palm="whole")}
    if set(pieces) != set(TISSUE_SEGMENTS):
        raise RuntimeError(f"tissue pieces {sorted(pieces)} do not match {TISSUE_SEGMENTS}")
    for name in TISSUE_SEGMENTS:
        piece = pieces[name]
        digit, _, segment = name.partition("_")
        bits = (const.PARTNER_SELF_BITS["thumb"] if digit == "thumb" else
                const.PARTNER_SELF_BITS["finger"]
                if segment in ("proximal", "middle", "distal") else (0, 0))
        add_piece(spec, skel.bodies[piece.body], piece, f"{prefix}tissue_{name}", contype=bits[0],
                  conaffinity=bits[1], mass=0.0, group=2, rgba=list(_TISSUE_RGBA),
                  solref=list(SELF_SOLREF))
        add_contact_sensor(spec, f"{prefix}feel_{name}", f"{prefix}tissue_{name}", netforce=True)

    # Joint impedance: one position servo per digit joint (ctrl = the joint's target angle), of
    # stiffness finger_kp x the joint's lever share (JOINT_KP_SHARE), torque-capped at the maximal
    # grip shared by four fingers acting at the proximal phalanx ([Mathiowetz85]).
    share = config.max_grip_force_n / const.PARTNER["grip_fingers"]
    for name in PARTNER_JOINTS:  # ctrl order of partner_actuators()
        digit, short = name.split("_", 1)
        lo, hi = (math.radians(v) for v in rng[joint_key(digit, short)])
        _servo(
            spec,
            f"{prefix}{name}",
            skel.joints[(digit, short)],
            mujoco.mjtTrn.mjTRN_JOINT,
            kp=config.finger_kp_nm_per_rad * JOINT_KP_SHARE[short],
            lo=lo,
            hi=hi,
            torque=share * layout.digits[digit].lengths_m["proximal"],
        )
    for short in ("flex", "dev"):
        lo, hi = (math.radians(v) for v in rng[f"wrist_{short}"])
        _servo(
            spec,
            f"{prefix}wrist_{short}",
            f"{prefix}wrist_{short}",
            mujoco.mjtTrn.mjTRN_JOINT,
            kp=config.wrist_kp_nm_per_rad,
            lo=lo,
            hi=hi,
            torque=config.wrist_torque_nm,
        )
    return palm


def build_partner_hand(config: PartnerConfig | None = None, prefix: str = "hum_") -> mujoco.MjSpec:
    """A spec with the partner hand alone on a mocap mount ``{prefix}base`` at the world origin."""
    spec = new_spec("softhand_partner_hand")
    base = spec.worldbody.add_body(name=f"{prefix}base", mocap=True)
    add_partner_hand(spec, base, config, prefix)
    return spec


def partner_tissue_geoms(
    model_or_spec: mujoco.MjModel | mujoco.MjSpec, prefix: str = "hum_"
) -> tuple[str, ...]:
    """Names of the partner's tissue geoms (order of TISSUE_SEGMENTS, then the forearm's where
    the hand has a forearm stub), checked to exist.

    Raises:
        ValueError: if one is missing from ``model_or_spec``.
    """

    def found(name: str) -> bool:
        if isinstance(model_or_spec, mujoco.MjSpec):
            return model_or_spec.geom(name) is not None
        return mujoco.mj_name2id(model_or_spec, mujoco.mjtObj.mjOBJ_GEOM, name) >= 0

    names = tuple(f"{prefix}tissue_{seg}" for seg in TISSUE_SEGMENTS)
    for name in names:
        if not found(name):
            raise ValueError(f"partner tissue geom {name!r} not found (prefix = {prefix!r})")
    forearm = f"{prefix}tissue_{FOREARM_TISSUE}"
    return (*names, forearm) if found(forearm) else names
