"""The prosthetic right hand: a commercial-class multi-articulating hand with 18 sensored skin regions.

Actuation (6 motors, like an i-Limb / bebionic-class hand with powered thumb rotation, [Belter13]):

====================== ============================ =====================================
actuator               drives                       coupled joints (equality, ratio)
====================== ============================ =====================================
``{finger}_motor`` x4  ``{finger}_mcp``             pip = 1 x mcp, dip = 2/3 x pip
``thumb_flex_motor``   ``thumb_mcp``                cmc = 15/50 x mcp, ip = 80/50 x mcp
``thumb_rot_motor``    ``thumb_rot``                -
====================== ============================ =====================================

The coupling ratios make every joint of a digit reach its upper limit together
(constants.PROSTHETIC_RANGE_DEG); DIP = 2/3 PIP is the human free-motion coupling [Rijpkema91].

Actuator model: integrated-velocity servos (MuJoCo ``intvelocity``). Commercial hands run a geared
DC motor per digit behind a non-back-drivable worm stage, commanded by an open/close speed. Here
``ctrl`` is the speed of the driven joint in rad/s (positive closes), clamped to
range / closing_time, so full command closes a digit in ``closing_time_s``; the integrated
setpoint (actuator activation, clamped to the joint range) is held by a stiff servo, so a digit stays
where it stopped under load, like a worm gear; the servo force is clamped to the stall torque
grip_force / 5 x digit length / 2 (the power grip shared by five digits acting at mid-length).

Skin regions (names as in the paper, Fig. 1; 1 = proximal, 3 = distal): one ellipsoid skin geom
``skin_{Region}`` per region on the contact side of its link, contype = conaffinity = 0 (contacts
come only from explicit ``<pair>`` elements added by the calibration stage), a site
``touch_{Region}`` enclosing it and a touch sensor ``touch_{Region}`` on that site.

- Thumb1 / Thumb2: palmar pads of the thumb's proximal / distal phalanx (the thumb has no middle
  phalanx; its metacarpal has no region).
- Index1..Little3: palmar pads of the proximal, middle and distal phalanges.
- Palm1: proximal palm (between the thenar and hypothenar eminences, wrist crease to mid-palm).
- Palm2: distal palm, the pad under the metacarpal heads (MCP joints).
- Back1: proximal back of the hand (over the carpus and metacarpal bases).
- Back2: distal back of the hand (over the metacarpal heads, the knuckles).

The paper's text gives only "two areas on the palm and two on the back" (Fig. 1 is an image); the
proximal/distal split above follows its 1 = proximal numbering and is an interpretation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

from softhand.hands import constants as const
from softhand.hands.config import ProstheticConfig
from softhand.hands.layout import HandLayout, hand_layout
from softhand.hands.skeleton import LIMIT_SOLREF, add_skeleton, add_touch_sensor, new_spec
from softhand.paper import paper

__all__ = [
    "REGION_SEGMENTS",
    "RegionInfo",
    "add_prosthetic_hand",
    "build_prosthetic_hand",
    "paper_regions",
    "prosthetic_actuators",
    "regions",
]

_ELLIPSOID = mujoco.mjtGeom.mjGEOM_ELLIPSOID
_TRUE = mujoco.mjtLimited.mjLIMITED_TRUE

#: Link (segment key) that carries each region's skin.
REGION_SEGMENTS: dict[str, str] = {
    "Thumb1": "thumb_proximal",
    "Thumb2": "thumb_distal",
    **{
        f"{f.capitalize()}{i}": f"{f}_{seg}"
        for f in const.FINGERS
        for i, seg in enumerate(("proximal", "middle", "distal"), start=1)
    },
    "Palm1": "palm",
    "Palm2": "palm",
    "Back1": "palm",
    "Back2": "palm",
}

#: Gap between a skin ellipsoid and the touch site that encloses it, per semi-axis (m).
_SKIN_RGBA = (0.93, 0.80, 0.70, 0.6)
_BONE_RGBA = (0.35, 0.36, 0.40, 1.0)
_SITE_RGBA = (0.2, 0.6, 1.0, 0.15)


@dataclass(frozen=True)
class RegionInfo:
    """Names of the elements of one skin region.

    Attributes:
        region: paper name, e.g. "Middle2".
        body: body that carries the skin.
        geom: the skin ellipsoid geom.
        site: the touch-sensor zone enclosing the skin.
        sensor: the touch sensor on that site.
    """

    region: str
    body: str
    geom: str
    site: str
    sensor: str


def paper_regions() -> tuple[str, ...]:
    names = tuple(paper()["handshake"]["regions"])
    if set(names) != set(REGION_SEGMENTS):
        raise RuntimeError(
            f"paper regions {names} do not match REGION_SEGMENTS {tuple(REGION_SEGMENTS)}"
        )
    return names


def _phalanx_pad(length: float, radius: float) -> tuple[list[float], list[float]]:
    """Palmar skin pad of a phalanx in its digit frame: (centre, semi-axes), outer surface at -radius."""
    half = (0.45 * length, 0.85 * radius, 0.6 * radius)
    centre = (0.5 * length, 0.0, -radius + half[2])
    return list(centre), list(half)


def _palm_pads(layout: HandLayout) -> dict[str, tuple[list[float], list[float]]]:
    """Palm1/Palm2 (palmar, z < 0) and Back1/Back2 (dorsal, z > 0) pads in the hand frame."""
    xm, half_w, t = layout.palm_length_m, 0.5 * layout.width_m, layout.thickness_m
    az = 0.35 * t
    pads = {}
    for side, sign in (("Palm", -1.0), ("Back", 1.0)):
        z = sign * (0.5 * t - az)
        pads[f"{side}1"] = ([0.265 * xm, 0.0, z], [0.205 * xm, 0.75 * half_w, az])
        pads[f"{side}2"] = ([0.760 * xm, 0.0, z], [0.230 * xm, 0.90 * half_w, az])
    return pads


def _add_region(
    spec: mujoco.MjSpec,
    body: mujoco.MjsBody,
    prefix: str,
    region: str,
    centre: list[float],
    half: list[float],
) -> None:
    body.add_geom(
        name=f"{prefix}skin_{region}",
        type=_ELLIPSOID,
        pos=centre,
        size=half,
        contype=0,
        conaffinity=0,
        mass=0.0,
        group=1,
        rgba=list(_SKIN_RGBA),
    )
    add_touch_sensor(spec, body, f"{prefix}touch_{region}", size=half, type=_ELLIPSOID,
                     pos=centre, rgba=list(_SITE_RGBA))


def _couple(spec: mujoco.MjSpec, name: str, follower: str, driver: str, ratio: float) -> None:
    """Joint equality: follower = ratio x driver (both zero at qpos0)."""
    eq = spec.add_equality(
        name=name,
        type=mujoco.mjtEq.mjEQ_JOINT,
        name1=follower,
        name2=driver,
        solref=list(LIMIT_SOLREF),
    )
    eq.data[0:5] = [0.0, ratio, 0.0, 0.0, 0.0]


def _motor(
    spec: mujoco.MjSpec,
    name: str,
    joint: str,
    *,
    lo: float,
    hi: float,
    time_s: float,
    torque: float,
    config: ProstheticConfig,
) -> None:
    """Integrated-velocity servo: ctrl in rad/s, setpoint clamped to [lo, hi], force to +-torque."""
    act = spec.add_actuator(name=name, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    act.set_to_intvelocity(kp=torque / config.stall_deflection_rad, dampratio=1.0)
    speed = (hi - lo) / time_s
    act.ctrllimited, act.ctrlrange = _TRUE, [-speed, speed]
    act.actlimited, act.actrange = _TRUE, [lo, hi]
    act.forcelimited, act.forcerange = _TRUE, [-torque, torque]


def prosthetic_actuators(prefix: str = "pro_") -> tuple[str, ...]:
    """Names of the 6 motors, in ctrl order: four fingers (radial to ulnar), thumb flexion, rotation."""
    return (
        *(f"{prefix}{f}_motor" for f in const.FINGERS),
        f"{prefix}thumb_flex_motor",
        f"{prefix}thumb_rot_motor",
    )


def add_prosthetic_hand(
    spec: mujoco.MjSpec,
    parent_body: mujoco.MjsBody,
    config: ProstheticConfig | None = None,
    prefix: str = "pro_",
) -> mujoco.MjsBody:
    """Add the prosthetic right hand under ``parent_body`` (whose frame becomes the hand frame).

    Args:
        spec: the spec to edit; ``spec.compiler.degree`` may be either setting.
        parent_body: body whose frame is the hand frame: origin at the wrist crease, +x distal,
            +y radial, +z dorsal. The hand has no wrist joint: fix ``parent_body`` (or give it joints).
        config: the hand; default ProstheticConfig().
        prefix: prefix of every element name.

    Returns:
        The palm body.
    """
    config = config or ProstheticConfig()
    if not isinstance(config, ProstheticConfig):
        raise ValueError(f"config = {config!r}: expected a ProstheticConfig")
    layout = hand_layout(config.hand)
    rng = const.PROSTHETIC_RANGE_DEG
    driven = {"armature": config.armature_kg_m2}
    coupled = {"armature": const.PROSTHETIC["coupled_armature_kg_m2"]}
    skel = add_skeleton(
        spec,
        parent_body,
        layout,
        prefix=prefix,
        ranges_deg=rng,
        bone_bits=const.BONE_BITS["prosthetic"],
        bone_rgba=_BONE_RGBA,
        joint_options={
            **{k: coupled for k in ("pip", "dip", "thumb_cmc", "thumb_ip")},
            **{k: driven for k in ("mcp", "thumb_mcp", "thumb_rot")},
        },
    )
    regions_ = paper_regions()

    # Skins, sites and touch sensors.
    palm_pads = _palm_pads(layout)
    for region in regions_:
        seg = REGION_SEGMENTS[region]
        if seg == "palm":
            centre, half = palm_pads[region]
        else:
            digit, part = seg.split("_")
            d = layout.digits[digit]
            centre, half = _phalanx_pad(d.lengths_m[part], d.radii_m[part])
        _add_region(spec, skel.bodies[seg], prefix, region, centre, half)

    # Couplings and motors. Ratios make all joints of a digit reach their upper limits together.
    grip_share = config.grip_force_n / const.PROSTHETIC["grip_digits"]
    j = skel.joints
    for f in const.FINGERS:
        _couple(
            spec,
            f"{prefix}{f}_pip_coupling",
            j[(f, "pip")],
            j[(f, "mcp")],
            rng["pip"][1] / rng["mcp"][1],
        )
        _couple(
            spec,
            f"{prefix}{f}_dip_coupling",
            j[(f, "dip")],
            j[(f, "pip")],
            rng["dip"][1] / rng["pip"][1],
        )
        d = layout.digits[f]
        reach = d.lengths_m["proximal"] + d.lengths_m["middle"] + d.lengths_m["distal"]
        _motor(
            spec,
            f"{prefix}{f}_motor",
            j[(f, "mcp")],
            lo=math.radians(rng["mcp"][0]),
            hi=math.radians(rng["mcp"][1]),
            time_s=config.closing_time_s,
            torque=grip_share * reach / 2.0,
            config=config,
        )
    d = layout.digits["thumb"]
    reach = d.lengths_m["proximal"] + d.lengths_m["distal"]
    for short in ("cmc", "ip"):
        _couple(
            spec,
            f"{prefix}thumb_{short}_coupling",
            j[("thumb", short)],
            j[("thumb", "mcp")],
            rng[f"thumb_{short}"][1] / rng["thumb_mcp"][1],
        )
    thumb_torque = grip_share * reach / 2.0
    _motor(
        spec,
        f"{prefix}thumb_flex_motor",
        j[("thumb", "mcp")],
        lo=math.radians(rng["thumb_mcp"][0]),
        hi=math.radians(rng["thumb_mcp"][1]),
        time_s=config.closing_time_s,
        torque=thumb_torque,
        config=config,
    )
    _motor(
        spec,
        f"{prefix}thumb_rot_motor",
        j[("thumb", "rot")],
        lo=math.radians(rng["thumb_rot"][0]),
        hi=math.radians(rng["thumb_rot"][1]),
        time_s=config.thumb_rotation_time_s,
        torque=thumb_torque,
        config=config,
    )
    return skel.bodies["palm"]


def build_prosthetic_hand(
    config: ProstheticConfig | None = None, prefix: str = "pro_"
) -> mujoco.MjSpec:
    """A spec with the prosthetic hand alone, fixed to the world at a wrist body ``{prefix}wrist``.

    The hand frame is the world frame (fingers along +x, palm facing -z), options as the scene.
    """
    spec = new_spec("softhand_prosthetic_hand")
    wrist = spec.worldbody.add_body(name=f"{prefix}wrist")
    add_prosthetic_hand(spec, wrist, config, prefix)
    return spec


def regions(
    model_or_spec: mujoco.MjModel | mujoco.MjSpec, prefix: str = "pro_"
) -> dict[str, RegionInfo]:
    """Region name -> names of its body, skin geom, site and touch sensor, in the paper's order.

    Raises:
        ValueError: if an element of a region is missing from ``model_or_spec``.
    """
    out: dict[str, RegionInfo] = {}
    for region in paper_regions():
        info = RegionInfo(
            region=region,
            body=f"{prefix}{REGION_SEGMENTS[region]}",
            geom=f"{prefix}skin_{region}",
            site=f"{prefix}touch_{region}",
            sensor=f"{prefix}touch_{region}",
        )
        for kind, name in (
            ("body", info.body),
            ("geom", info.geom),
            ("site", info.site),
            ("sensor", info.sensor),
        ):
            if not _has(model_or_spec, kind, name):
                raise ValueError(
                    f"region {region!r}: {kind} {name!r} not found (prefix = {prefix!r})"
                )
        out[region] = info
    return out


def _has(model_or_spec: mujoco.MjModel | mujoco.MjSpec, kind: str, name: str) -> bool:
    if isinstance(model_or_spec, mujoco.MjSpec):
        return getattr(model_or_spec, kind)(name) is not None
    obj = {
        "body": mujoco.mjtObj.mjOBJ_BODY,
        "geom": mujoco.mjtObj.mjOBJ_GEOM,
        "site": mujoco.mjtObj.mjOBJ_SITE,
        "sensor": mujoco.mjtObj.mjOBJ_SENSOR,
    }[kind]
    return mujoco.mj_name2id(model_or_spec, obj, name) >= 0
