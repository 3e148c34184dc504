"""The rigid skeleton shared by both hands: bodies, hinge joints and "bone" geoms, added to an MjSpec.

Names (``prefix`` + ...):

- ``palm``: palm body; carries the four finger metacarpal bones
- ``thumb_metacarpal``: thumb metacarpal body; joints ``thumb_rot`` then ``thumb_cmc``
- ``thumb_proximal``: joint ``thumb_mcp``
- ``thumb_distal``: joint ``thumb_ip``; site ``thumb_tip``
- ``{finger}_proximal``: joint ``{finger}_mcp`` (finger: index, middle, ring, little)
- ``{finger}_middle``: joint ``{finger}_pip``
- ``{finger}_distal``: joint ``{finger}_dip``; site ``{finger}_tip``
- ``bone_{segment}``: capsule bone geom of a segment (palm: ``bone_{finger}_metacarpal``)
- ``wrist_crease``: site at the palm origin: the hand-length landmark

Every joint flexes for a positive angle. Digit bodies use the digit frame: +x along the segment,
+y the flexion axis, -z the palmar (pad) side; long fingers share the hand frame's orientation.
The thumb's first joint ``thumb_rot`` is palmar abduction, about the axis in the palm plane
perpendicular to the adducted metacarpal, through the CMC: 0 is the adducted thumb lying in the palm
plane (pad facing the index), positive swings it palmar into opposition ([AAOS65] palmar abduction
0-70 deg), carrying its flexion plane along, so flexing an opposed thumb moves its pad across the
palm towards the fingers. Bones get the (contype, conaffinity) bits passed in, so that each hand's bones touch only
the other hand's bones; they carry the segment masses (density x envelope volume). Each bone is its
segment's trimmed envelope capsule (softhand.hands.envelope) shrunk by the skin thickness: the same
axis from R to L - R, radius R - skin, so it lies the skin thickness inside its own soft piece all
over, ends included, and stops that far short of each joint (a finger metacarpal likewise stops
bone radius + skin short of its CMC and MCP). Bones that ran joint to joint stood out of the
soft layer at the joints, where the trimmed capsules pinch.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import mujoco
import numpy as np

from softhand.hands import constants as const
from softhand.hands.envelope import Piece
from softhand.hands.layout import HandLayout

__all__ = [
    "LIMIT_SOLREF",
    "SENSOR_SLOTS",
    "SENSOR_ZONE_MARGIN_M",
    "Skeleton",
    "add_contact_sensor",
    "add_piece",
    "add_skeleton",
    "angle",
    "contact_sensor_force",
    "joint_key",
    "new_spec",
    "quat_from_axes",
    "segment_joints",
]

_CAPSULE = mujoco.mjtGeom.mjGEOM_CAPSULE
_SPHERE = mujoco.mjtGeom.mjGEOM_SPHERE
_HINGE = mujoco.mjtJoint.mjJNT_HINGE

#: How far a sensor zone reaches out beyond the skin surface it watches (m). A contact point lies
#: half-way through the overlap of the two geoms, so a zone must reach half the deepest pair
#: overlap out from the surface: 20 N, the calibrated top, takes at most ~13 mm for pocket2-sil
#: skin in series with human tissue (contacts deeper than that are reported beyond range anyway).
SENSOR_ZONE_MARGIN_M = 0.008
#: Contacts one region sensor can report per step (MuJoCo contact sensor slots, largest first);
#: a region that meets more tissue geoms at once is flagged (``found`` > slots).
SENSOR_SLOTS = 10

_MESH = mujoco.mjtGeom.mjGEOM_MESH


def add_piece(spec: mujoco.MjSpec, body: mujoco.MjsBody, piece: Piece, name: str,
              **attributes) -> mujoco.MjsGeom:
    """A geom named ``name`` with the shape of an envelope piece (a capsule, or a convex mesh
    ``{name}_mesh`` of the piece's hull vertices), in ``body``'s frame."""
    if piece.kind == "capsule":
        return body.add_geom(name=name, type=_CAPSULE, fromto=[float(v) for v in piece.fromto],
                             size=[piece.radius, 0.0, 0.0], **attributes)
    spec.add_mesh(name=f"{name}_mesh", uservert=[float(v) for v in piece.vertices.reshape(-1)])
    return body.add_geom(name=name, type=_MESH, meshname=f"{name}_mesh", **attributes)


def add_contact_sensor(spec: mujoco.MjSpec, name: str, geom: str, *, site: str | None = None,
                       netforce: bool = False) -> None:
    """A MuJoCo contact sensor ``name`` on the contacts of ``geom`` (inside ``site``'s volume when
    given): ``SENSOR_SLOTS`` slots of (found, normal, tangential, tangential force), largest force
    first, or one net-force slot (``netforce``, global frame)."""
    sensor = spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_CONTACT)
    if site is None:
        sensor.objtype, sensor.objname = mujoco.mjtObj.mjOBJ_GEOM, geom
    else:
        sensor.objtype, sensor.objname = mujoco.mjtObj.mjOBJ_SITE, site
        sensor.reftype, sensor.refname = mujoco.mjtObj.mjOBJ_GEOM, geom
    # data = found | force (bits 0, 1); reduce: maxforce 2, netforce 3
    sensor.intprm[0:3] = [3, 3 if netforce else 2, 1 if netforce else SENSOR_SLOTS]


def contact_sensor_force(values: np.ndarray) -> np.ndarray:
    """Sum of normal forces (N) per sensor from contact-sensor readings shaped (..., slots, 4)."""
    return values[..., 1].sum(axis=-1)


#: solref (time constant s, damping ratio) of joint limits and joint couplings. MuJoCo's default
#: (0.02, 1) scales the constraint stiffness with the tiny inertia of a phalanx, so a few N m from
#: the other hand would push a finger tens of degrees through its stop; 5 ms (2.5 steps of the
#: handshake's 2 ms) makes the stops 16x stiffer (keep it >= 2 time steps: MuJoCo clamps it there).
LIMIT_SOLREF: tuple[float, float] = (0.005, 1.0)


def new_spec(
    model_name: str, *, timestep_s: float = 0.001, gravity_m_s2: float = 9.81
) -> mujoco.MjSpec:
    """An empty spec with softhand's options: implicitfast, elliptic cones, radians, no floor,
    convex collision tolerance 0.1 mm."""
    if not (math.isfinite(timestep_s) and 0.0 < timestep_s <= 0.01):
        raise ValueError(f"timestep_s = {timestep_s!r} s: allowed range (0, 0.01] s")
    spec = mujoco.MjSpec()
    spec.modelname = model_name
    spec.compiler.degree = False
    spec.option.timestep = timestep_s
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.gravity = [0.0, 0.0, -gravity_m_s2]
    # convex collision (palm meshes, the old ellipsoid skins) converged to 0.1 mm instead of 1 um: a quarter of a
    # handshake step saved; region forces change by < 4 mN, depths by < 0.08 mm (measured at four
    # instants of a handshake against 1e-6)
    spec.option.ccd_tolerance = 1e-4
    # one contact per convex pair (MuJoCo's multiccd, on by default, gave a capsule lying on a palm
    # mesh two contacts, each carrying the per-contact skin law: that pair was twice as stiff as
    # calibrated; 15 % of the default handshake's force was in such pairs)
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_MULTICCD
    return spec


def angle(spec: mujoco.MjSpec, radians: float) -> float:
    """``radians`` in the angle unit the spec's compiler expects for joint ranges."""
    return math.degrees(radians) if spec.compiler.degree else radians


def quat_from_axes(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> list[float]:
    """Quaternion (w, x, y, z) of the rotation whose columns are the unit vectors x, y, z."""
    mat = np.column_stack([x, y, z]).reshape(-1)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, mat)
    return [float(v) for v in quat]


def joint_key(digit: str, joint: str) -> str:
    """Key of a joint in the range tables: "mcp"/"pip"/"dip" for fingers, "thumb_*" for the thumb."""
    return joint if digit != "thumb" else f"thumb_{joint}"


def segment_joints(digit: str, segment: str) -> tuple[str, ...]:
    """Short joint names (without digit) at the proximal end of ``segment`` of ``digit``."""
    if digit == "thumb":
        return {"metacarpal": ("rot", "cmc"), "proximal": ("mcp",), "distal": ("ip",)}[segment]
    return {"proximal": ("mcp",), "middle": ("pip",), "distal": ("dip",)}[segment]


@dataclass(frozen=True)
class Skeleton:
    """What add_skeleton made: bodies by segment key ("palm", "index_proximal", ...) and joint names.

    Attributes:
        bodies: spec bodies keyed by segment key.
        joints: full joint names keyed by range key per digit, e.g. ("index", "mcp") -> "pro_index_mcp".
    """

    bodies: dict[str, mujoco.MjsBody]
    joints: dict[tuple[str, str], str]


def _thumb_frame(spread: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Thumb metacarpal frame in the hand frame at thumb_rot = 0 (x along the bone, y flexion axis)."""
    x = np.array([math.cos(spread), math.sin(spread), 0.0])
    y = np.array([0.0, 0.0, -1.0])
    return x, y, np.cross(x, y)


def add_skeleton(
    spec: mujoco.MjSpec,
    parent: mujoco.MjsBody,
    layout: HandLayout,
    *,
    prefix: str,
    ranges_deg: Mapping[str, tuple[float, float]],
    bone_bits: tuple[int, int],
    bone_rgba: tuple[float, float, float, float],
    joint_options: Mapping[str, Mapping[str, float]] | None = None,
) -> Skeleton:
    """Add palm, thumb and four fingers under ``parent``, whose frame is the hand frame.

    Args:
        spec: the spec to edit.
        parent: body whose frame is the hand frame (wrist crease origin, x distal, z dorsal).
        layout: the numbers of the hand (softhand.hands.layout.hand_layout).
        prefix: name prefix of every element added.
        ranges_deg: joint range in degrees per range key ("mcp", "pip", "dip", "thumb_rot", ...).
        bone_bits: (contype, conaffinity) of the bone geoms.
        bone_rgba: colour of the bone geoms.
        joint_options: per range key, extra joint attributes (armature, damping, stiffness).

    Returns:
        The bodies and joint names made.
    """
    joint_options = joint_options or {}
    contype, conaffinity = bone_bits
    bodies: dict[str, mujoco.MjsBody] = {}
    joints: dict[tuple[str, str], str] = {}

    def bone(body: mujoco.MjsBody, name: str, p0, p1, radius: float, mass: float) -> None:
        body.add_geom(
            name=f"{prefix}bone_{name}",
            type=_CAPSULE,
            fromto=[*map(float, p0), *map(float, p1)],
            size=[radius, 0.0, 0.0],
            mass=mass,
            contype=contype,
            conaffinity=conaffinity,
            group=0,
            rgba=list(bone_rgba),
        )

    def hinge(body: mujoco.MjsBody, digit: str, short: str, axis) -> None:
        key = joint_key(digit, short)
        lo, hi = ranges_deg[key]
        name = f"{prefix}{digit}_{short}"
        joint = body.add_joint(
            name=name,
            type=_HINGE,
            axis=[float(a) for a in axis],
            range=[angle(spec, math.radians(lo)), angle(spec, math.radians(hi))],
            solref_limit=list(LIMIT_SOLREF),
        )
        for attr, value in joint_options.get(key, {}).items():
            setattr(joint, attr, value)
        joints[(digit, short)] = name

    skin = layout.skin_m
    palm = parent.add_body(name=f"{prefix}palm")
    bodies["palm"] = palm
    palm.add_site(name=f"{prefix}wrist_crease", type=_SPHERE, size=[0.002, 0, 0], group=4)
    for f in const.FINGERS:
        d = layout.digits[f]
        axis = np.asarray(d.base_m, float) - np.asarray(d.cmc_m, float)
        inset = (layout.metacarpal_bone_radius_m + skin) * axis / np.linalg.norm(axis)
        bone(
            palm,
            f"{f}_metacarpal",
            np.asarray(d.cmc_m, float) + inset,
            np.asarray(d.base_m, float) - inset,
            layout.metacarpal_bone_radius_m,
            layout.palm_mass_kg / len(const.FINGERS),
        )

    def chain(parent_body: mujoco.MjsBody, digit: str, pos, segments: tuple[str, ...]) -> None:
        """Phalanges of one digit in a row, each flexing about +y, and a fingertip site."""
        d = layout.digits[digit]
        body = parent_body
        for seg in segments:
            body = body.add_body(name=f"{prefix}{digit}_{seg}", pos=[float(v) for v in pos])
            bodies[f"{digit}_{seg}"] = body
            (short,) = segment_joints(digit, seg)
            hinge(body, digit, short, (0.0, 1.0, 0.0))
            length, radius = d.lengths_m[seg], d.bone_radii_m[seg]
            bone(body, f"{digit}_{seg}", (radius + skin, 0, 0), (length - radius - skin, 0, 0),
                 radius, d.masses_kg[seg])
            pos = (length, 0.0, 0.0)
        body.add_site(name=f"{prefix}{digit}_tip", type=_SPHERE, size=[0.002, 0, 0],
                      pos=[float(pos[0]), 0.0, 0.0], group=4)

    # Long fingers: same orientation as the hand frame, flexion about +y.
    for f in const.FINGERS:
        chain(palm, f, layout.digits[f].base_m, ("proximal", "middle", "distal"))

    # Thumb: metacarpal frame from the spread angle; thumb_rot about the hand's -x axis.
    d = layout.digits["thumb"]
    x, y, z = _thumb_frame(layout.thumb_spread_rad)
    # palmar abduction: about the thumb frame's z, the palm-plane axis perpendicular to the
    # adducted metacarpal, so that positive rotation swings the thumb out of the palm plane to the
    # palmar side while its flexion plane turns with it (flexion then carries the pad across the
    # palm towards the fingers); the old axis, the hand's -x, was nearly the thumb's own long axis
    # and turned the flexion plane dorsal (an opposed thumb folded over the back of the hand)
    rot_axis = np.array([0.0, 0.0, 1.0])
    body = palm.add_body(
        name=f"{prefix}thumb_metacarpal",
        pos=[float(v) for v in d.cmc_m],
        quat=quat_from_axes(x, y, z),
    )
    bodies["thumb_metacarpal"] = body
    hinge(body, "thumb", "rot", rot_axis)
    hinge(body, "thumb", "cmc", (0.0, 1.0, 0.0))
    radius = d.bone_radii_m["metacarpal"]
    bone(
        body,
        "thumb_metacarpal",
        (radius + skin, 0, 0),
        (d.lengths_m["metacarpal"] - radius - skin, 0, 0),
        radius,
        d.masses_kg["metacarpal"],
    )
    chain(body, "thumb", (d.lengths_m["metacarpal"], 0.0, 0.0), ("proximal", "distal"))
    return Skeleton(bodies=bodies, joints=joints)
