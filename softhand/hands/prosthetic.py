"""The prosthetic right hand: a commercial-class multi-articulating hand with 18 sensored skin regions.

Actuation (6 motors, like an i-Limb / bebionic-class hand with powered thumb rotation, [Belter13]):

| actuator | drives | coupled joints (equality, ratio) |
|---|---|---|
| ``{finger}_motor`` x4 | ``{finger}_mcp`` | pip = 1 x mcp, dip = 2/3 x pip |
| ``thumb_flex_motor`` | ``thumb_mcp`` | cmc = 15/50 x mcp, ip = 80/50 x mcp |
| ``thumb_rot_motor`` | ``thumb_rot`` | - |

The coupling ratios make every joint of a digit reach its upper limit together
(constants.PROSTHETIC_RANGE_DEG); DIP = 2/3 PIP is the human free-motion coupling [Rijpkema91].

Actuator model: integrated-velocity servos (MuJoCo ``intvelocity``). Commercial hands run a geared
DC motor per digit behind a non-back-drivable worm stage, commanded by an open/close speed. Here
``ctrl`` is the speed of the driven joint in rad/s (positive closes), clamped to
range / closing_time, so full command closes a digit in ``closing_time_s``; the integrated
setpoint (actuator activation, clamped to the joint range) is held by a stiff servo, so a digit stays
where it stopped under load, like a worm gear; the servo force is clamped to the stall torque
grip_force / 5 x digit length / 2 (the power grip shared by five digits acting at mid-length).

Skin (`softhand.hands.envelope`): the hand's whole soft envelope is skin, one layer of convex
pieces with no piece inside another at rest: a trimmed capsule on every phalanx and on the thumb
metacarpal (the thenar), and the palm, one convex mesh round the palmar face, both borders and
the back (its hypothenar eminence included), so that no seam lies under a finger that wraps the
palm's border. Every piece is a geom ``skin_{Key}`` with contype = conaffinity = 0 (contacts only
through explicit ``<pair>`` elements added by the calibration stage) and wears a design
(SKIN_KEYS: a phalanx's own region's, the palm's and the thenar's Palm1's):

- the 18 sensing regions (names as in the paper, Fig. 1; 1 = proximal, 3 = distal) each have a
  sensor zone, a box site ``touch_{Region}`` over the contact side of its skin, with a MuJoCo
  contact sensor ``touch_{Region}`` on the contacts of that skin inside it (SENSOR_SLOTS slots; the
  region's reading is the sum of their normal forces): the palmar half of a phalanx (whose skin is
  the region's own piece), and on the one palm surface (SURFACES) a quarter's face: palmar or
  dorsal, proximal or distal of mid-palm, the central 80 % of the palm's width. The zones of one
  surface do not overlap, so a contact is read by one region at most. Contacts elsewhere on a
  skin (a phalanx's dorsal half, the palm's borders) are *unsensed* skin: same design, force
  reported apart, with the region of the nearest zone (`zone_of`).
- Thumb1 / Thumb2: proximal / distal phalanx of the thumb (it has no middle phalanx).
- Index1..Little3: proximal, middle and distal phalanges.
- Palm1 / Palm2: proximal / distal palmar quarter of the palm (Palm2 under the metacarpal heads).
- Back1 / Back2: proximal / distal dorsal quarter (Back2 over the knuckles).
- ``skin_Thenar``: the thenar, non-sensing skin wearing Palm1's design (UNSENSED_SKINS).

The paper's text gives only "two areas on the palm and two on the back" (Fig. 1 is an image); the
proximal/distal split above follows its 1 = proximal numbering and is an interpretation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from softhand.hands import constants as const
from softhand.hands.config import ProstheticConfig
from softhand.hands.envelope import Piece, hand_pieces
from softhand.hands.layout import HandLayout, hand_layout
from softhand.hands.skeleton import (
    LIMIT_SOLREF,
    SENSOR_ZONE_MARGIN_M,
    add_contact_sensor,
    add_piece,
    add_skeleton,
    new_spec,
)
from softhand.paper import paper

__all__ = [
    "REGION_PIECES",
    "REGION_SEGMENTS",
    "SKIN_KEYS",
    "SURFACES",
    "UNSENSED_SKINS",
    "RegionInfo",
    "add_prosthetic_hand",
    "build_prosthetic_hand",
    "paper_regions",
    "prosthetic_actuators",
    "regions",
    "skin_key",
]

_BOX = mujoco.mjtGeom.mjGEOM_BOX
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

#: Skins that carry several sensing regions as zones: skin key -> its regions. The palm is one
#: continuous surface (palmar face, borders and back): a finger on its border presses one skin.
SURFACES: dict[str, tuple[str, ...]] = {"Palm": ("Palm1", "Palm2", "Back1", "Back2")}
#: Envelope piece (softhand.hands.envelope) that carries each region's skin.
REGION_PIECES: dict[str, str] = {
    **{r: seg for r, seg in REGION_SEGMENTS.items() if seg != "palm"},
    **{r: "palm" for r in SURFACES["Palm"]},
}
#: Non-sensing skin: name -> (envelope piece, region whose design it wears).
UNSENSED_SKINS: dict[str, tuple[str, str]] = {"Thenar": ("thumb_metacarpal", "Palm1")}
#: Every skin geom ``skin_{key}`` a hand can have: key -> the region whose design it wears (a
#: region's own skin: the region; the palm's surface and the thenar: Palm1). A hand has the
#: palm's surface or its four quarters (ProstheticConfig.palm), not both.
SKIN_KEYS: dict[str, str] = {
    **{r: r for r in REGION_SEGMENTS},
    **{key: zones[0] for key, zones in SURFACES.items()},
    **{name: region for name, (_, region) in UNSENSED_SKINS.items()},
}
_QUARTERS = dict(zip(SURFACES["Palm"], ("palm_proximal", "palm_distal", "back_proximal",
                                        "back_distal"), strict=True))


def skin_key(region: str, palm: str = "surface") -> str:
    """The key of the skin geom ``skin_{key}`` that carries ``region`` on a hand whose palm is
    ``palm`` (PALM_SKINS): a surface's, or the region's own."""
    for key, zones in SURFACES.items():
        if region in zones and palm == "surface":
            return key
    return region
#: Share of the palm's half-width watched by a palm region's sensor zone (the borders are
#: unsensed skin). assumption: the paper's palm sensors sat on the palm's faces, not its edges.
_PALM_ZONE_WIDTH = 0.8

_SKIN_RGBA = (0.93, 0.80, 0.70, 0.6)
_BONE_RGBA = (0.35, 0.36, 0.40, 1.0)
_SITE_RGBA = (0.2, 0.6, 1.0, 0.15)


@dataclass(frozen=True)
class RegionInfo:
    """Names of the elements of one skin region.

    Attributes:
        region: paper name, e.g. "Middle2".
        body: body that carries the skin.
        geom: the skin geom that carries it (a capsule on a phalanx; the palm's one convex mesh,
            shared by the palm's four zones).
        site: the sensor zone, a box over the skin's contact side.
        sensor: the contact sensor on the skin's contacts inside that site.
        bone_sensors: contact sensors on the region body's bones inside that site (a
            bone bottoming out on the other hand's bone under the region's skin).
    """

    region: str
    body: str
    geom: str
    site: str
    sensor: str
    bone_sensors: tuple[str, ...] = ()


def paper_regions() -> tuple[str, ...]:
    names = tuple(paper()["handshake"]["regions"])
    if set(names) != set(REGION_SEGMENTS):
        raise RuntimeError(
            f"paper regions {names} do not match REGION_SEGMENTS {tuple(REGION_SEGMENTS)}"
        )
    return names


def _zone(piece: Piece, layout: HandLayout) -> tuple[list[float], list[float]]:
    """Sensor zone of a region's piece, as a box (centre, half sizes) in the piece's body frame:
    the contact side of the piece, reaching SENSOR_ZONE_MARGIN_M out beyond its surface and not
    past the piece's cut faces (so no contact is counted by two regions)."""
    lo, hi = (np.array(v, dtype=float) for v in piece.bounds())
    m = SENSOR_ZONE_MARGIN_M
    if piece.kind == "capsule":  # a phalanx, in its digit frame: the palmar (-z) half
        lo = np.array([piece.fromto[0] - piece.radius, lo[1] - m, lo[2] - m])
        hi = np.array([piece.fromto[3] + piece.radius, hi[1] + m, 0.0])
    else:  # a palm quarter in the hand frame: its face (palmar or dorsal), central width
        half_w = _PALM_ZONE_WIDTH * 0.5 * layout.width_m
        lo[1], hi[1] = -half_w, half_w
        if hi[2] <= 1e-9:  # palmar quarter: from the outside to the mid-plane
            lo[2] -= m
        else:
            hi[2] += m
        lo[0] = lo[0] if lo[0] > 1e-9 else 0.0
    return list(0.5 * (lo + hi)), list(0.5 * (hi - lo))


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
    """Integrated-velocity servo: ctrl in rad/s, setpoint clamped to [lo, hi], force to +-torque.
    A relaxed human hand (ProstheticConfig.actuation) gets a position servo instead: ctrl is the
    joint's target in [lo, hi], of the relaxed stiffness constants.RELAXED_HUMAN."""
    act = spec.add_actuator(name=name, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    if config.actuation == "relaxed-human":
        act.set_to_position(kp=const.RELAXED_HUMAN["mcp_kp_nm_per_rad"], dampratio=1.0)
        act.ctrllimited, act.ctrlrange = _TRUE, [lo, hi]
        act.forcelimited, act.forcerange = _TRUE, [-torque, torque]
        return
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

    # Skins: every envelope piece, the palm whole; each sensing region gets a zone and a contact
    # sensor on its skin. The palm's zones are its quarters' faces (the quarters are cut only to
    # place the zones: the skin stays one surface).
    surface = config.palm == "surface"
    pieces = {p.name: p for p in hand_pieces(layout, palm="whole" if surface else "quarters")}
    quarters = {p.name: p for p in hand_pieces(layout, palm="quarters") if p.body == "palm"}
    piece_of = {r: p for r, p in REGION_PIECES.items() if p != "palm"}
    if surface:
        piece_of.update({key: REGION_PIECES[zones[0]] for key, zones in SURFACES.items()})
    else:
        piece_of.update(_QUARTERS)
    piece_of.update({name: piece for name, (piece, _) in UNSENSED_SKINS.items()})
    if set(piece_of.values()) != set(pieces):
        raise RuntimeError(f"skin pieces {sorted(piece_of.values())} do not match the "
                           f"envelope's {sorted(pieces)}")
    for key, piece_name in piece_of.items():
        piece = pieces[piece_name]
        add_piece(spec, skel.bodies[piece.body], piece, f"{prefix}skin_{key}", contype=0,
                  conaffinity=0, mass=0.0, group=1, rgba=list(_SKIN_RGBA))
    for region in regions_:
        key = skin_key(region, config.palm)
        piece = quarters[_QUARTERS[region]] if region in _QUARTERS else pieces[piece_of[key]]
        body = skel.bodies[piece.body]
        centre, half = _zone(piece, layout)
        body.add_site(name=f"{prefix}touch_{region}", type=_BOX, pos=centre, size=half,
                      group=4, rgba=list(_SITE_RGBA))
        add_contact_sensor(spec, f"{prefix}touch_{region}", f"{prefix}skin_{key}",
                           site=f"{prefix}touch_{region}")
        # the region's bones bottoming out inside its zone: felt there too (normal forces,
        # as the skin's sensor; bone on bone is outside every law's calibration)
        for i, bone in enumerate(_bones_of(body, prefix)):
            add_contact_sensor(spec, f"{prefix}touch_bone_{region}_{i}", bone,
                               site=f"{prefix}touch_{region}")

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


def _bone_sensors(model_or_spec: mujoco.MjModel | mujoco.MjSpec, stem: str) -> tuple[str, ...]:
    """Names of the sensors ``{stem}0``, ``{stem}1``, ... present in the model or spec."""
    out = []
    while _has(model_or_spec, "sensor", f"{stem}{len(out)}"):
        out.append(f"{stem}{len(out)}")
    return tuple(out)


def _bones_of(body: mujoco.MjsBody, prefix: str) -> list[str]:
    """Names of the bone geoms carried by ``body`` (a phalanx: one; the palm: its metacarpals)."""
    return [g.name for g in body.geoms if g.name.startswith(f"{prefix}bone_")]


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
    """Region name -> names of its body, skin geom, site and contact sensor, in the paper's order
    (the palm's regions: zones of its surface, or its quarters, as the hand was built).

    Raises:
        ValueError: if an element of a region is missing from ``model_or_spec``.
    """
    out: dict[str, RegionInfo] = {}
    quarters = _has(model_or_spec, "geom", f"{prefix}skin_{SURFACES['Palm'][0]}")
    for region in paper_regions():
        info = RegionInfo(
            region=region,
            body=f"{prefix}{REGION_SEGMENTS[region]}",
            geom=f"{prefix}skin_{skin_key(region, 'quarters' if quarters else 'surface')}",
            site=f"{prefix}touch_{region}",
            sensor=f"{prefix}touch_{region}",
            bone_sensors=_bone_sensors(model_or_spec, f"{prefix}touch_bone_{region}_"),
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
