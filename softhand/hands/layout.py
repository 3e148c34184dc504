"""Hand geometry as numbers: joint positions, segment lengths, radii and masses in the hand frame.

Hand frame (both hands): origin at the centre of the distal wrist crease, mid-thickness of the palm;
+x distal along the third metacarpal, +y radial (thumb side), +z dorsal. A segment's *envelope* is
a capsule of radius R along its length: the bone is that capsule shrunk by the skin thickness, and
masses are density x envelope volume.

How the published numbers fix the layout (L = hand length, W = hand width, t = palm thickness):

- finger lengths: [Buchholz92] ratios x L;
- fingertips: the middle tip at x = L (definition of hand length), the others
  FINGERTIP_OFFSET_M proximal to it ([Chatzioglou24]); so MCP_x = tip_x - (PP + MP + DP);
- CMC joints: MCP_x - metacarpal length ([Buchholz92]);
- across the palm: the skin over the index and little metacarpals lies at +-W/2, so that the
  breadth across the MCPs is W (paper Table 1); the MCP centres in between are spaced in
  proportion to the finger breadth shares (assumption, constants.FINGER_BREADTH_SHARE);
- thumb: CMC at constants.THUMB_CMC_FRACTION (assumption); its spread angle in the palm plane is
  chosen so that the extended thumb tip lies FINGERTIP_OFFSET_M["thumb_to_index"] proximal to
  the index tip ([Chatzioglou24]).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from softhand.hands import constants as const
from softhand.hands.config import HandConfig

__all__ = ["DigitLayout", "HandLayout", "hand_layout"]

#: Fraction of the W x t x palm-length slab filled by the palm (rounded edges). assumption.
_PALM_FILL = 0.9
#: Largest phalanx envelope diameter as a share of its length (the trimmed capsules of the
#: envelope need length >= diameter). assumption.
_LENGTH_FILL = 0.999
#: Smallest bone capsule radius allowed under the skin (m).
_MIN_BONE_RADIUS_M = 0.001


@dataclass(frozen=True)
class DigitLayout:
    """One digit in the hand frame.

    Attributes:
        name: "thumb", "index", "middle", "ring" or "little".
        base_m: position of the digit's base joint (m): the MCP for fingers, the CMC for the thumb.
        cmc_m: position of the CMC joint (m).
        lengths_m: kinematic segment lengths (m), keyed by segment name.
        radii_m: envelope radius of each segment (m), keyed by segment name.
        bone_radii_m: radius of each segment's rigid bone (m): the envelope less the skin, except
            the thumb metacarpal, whose bone has the thumb proximal bone's radius under the thenar.
        masses_kg: segment masses (kg), keyed by segment name (finger metacarpals: 0, their mass is
            in the palm).
    """

    name: str
    base_m: tuple[float, float, float]
    cmc_m: tuple[float, float, float]
    lengths_m: dict[str, float]
    radii_m: dict[str, float]
    masses_kg: dict[str, float]
    bone_radii_m: dict[str, float]

    @property
    def segments(self) -> tuple[str, ...]:
        return const.THUMB_SEGMENTS if self.name == "thumb" else const.FINGER_SEGMENTS

    @property
    def phalanges(self) -> tuple[str, ...]:
        """Segments that are separate bodies: thumb metacarpal + phalanges, finger phalanges."""
        return self.segments if self.name == "thumb" else self.segments[1:]


@dataclass(frozen=True)
class HandLayout:
    """All numbers needed to build a hand, derived from a HandConfig.

    Attributes:
        config: the configuration it was derived from.
        length_m, width_m, thickness_m, skin_m: hand length, width, palm thickness, skin (m).
        metacarpal_bone_radius_m: radius of the four finger metacarpal bone capsules (m).
        palm_length_m: mean MCP x: length of the palm from the wrist crease (m).
        palm_mass_kg: mass of the palm, carried by the four metacarpal bones (kg).
        thumb_spread_rad: angle of the adducted thumb metacarpal from +x in the palm plane (rad).
        digits: the five digits, thumb first.
    """

    config: HandConfig
    length_m: float
    width_m: float
    thickness_m: float
    skin_m: float
    metacarpal_bone_radius_m: float
    palm_length_m: float
    palm_mass_kg: float
    thumb_spread_rad: float
    digits: dict[str, DigitLayout]

    @property
    def total_mass_kg(self) -> float:
        return self.palm_mass_kg + sum(sum(d.masses_kg.values()) for d in self.digits.values())


def _capsule_volume(radius: float, length: float, *, closed_end: bool) -> float:
    """Envelope volume of a segment: a cylinder, plus a hemisphere at the tip of a distal segment."""
    if closed_end:
        body = max(length - radius, 0.0)
        return math.pi * radius**2 * body + 2.0 / 3.0 * math.pi * radius**3
    return math.pi * radius**2 * length


#: Skin thickness when HandConfig.skin_thickness_m is None, where the hand's phalanges allow it
#: (m).
DEFAULT_SKIN_M = 0.006
#: Bone radius kept under a default skin on the thinnest phalanx (m): the smallest allowed
#: (_MIN_BONE_RADIUS_M) and 0.2 mm to spare. The paper's experimenter's hand keeps the 6 mm skin
#: (its thinnest bone, the thumb's distal phalanx, is 1.35 mm in radius).
_DEFAULT_MIN_BONE_RADIUS_M = 0.0012


def hand_layout(config: HandConfig) -> HandLayout:
    """Derive joint positions, lengths, radii and masses of a right hand from ``config``."""
    if config.skin_thickness_m is not None:
        return _hand_layout(config, config.skin_thickness_m)
    envelope = _hand_layout(config, 0.0)
    thinnest = min(d.radii_m[s] for d in envelope.digits.values() for s in d.phalanges)
    return _hand_layout(config, min(DEFAULT_SKIN_M, thinnest - _DEFAULT_MIN_BONE_RADIUS_M))


def _hand_layout(config: HandConfig, skin: float) -> HandLayout:
    L, W = config.hand_length_m, config.hand_width_m
    t = config.thickness_m
    rho = config.density_kg_m3
    scale = L / const.FINGERTIP_OFFSET_REFERENCE_LENGTH_M
    # finger metacarpal bone: a slender shaft in the palm's soft envelope (radius t / 2)
    r_mc = min(const.METACARPAL_BONE_RADIUS_OVER_THICKNESS * t, 0.5 * t - skin)

    # Across the palm: the skin over the index and little metacarpals at +-W/2 (hand breadth is
    # measured on the skin); the MCP centres in between are spaced by the mean breadth share of
    # each pair of neighbours.
    span = W - t  # distance between the index and little MCP centres (envelopes of radius t / 2)
    shares = const.FINGER_BREADTH_SHARE
    total = sum(shares.values())
    gaps = [
        0.5 * (shares[a] + shares[b])
        for a, b in zip(const.FINGERS[:-1], const.FINGERS[1:], strict=True)
    ]
    y = [0.5 * span]
    for g in gaps:
        y.append(y[-1] - g / sum(gaps) * span)
    mcp_y = dict(zip(const.FINGERS, y, strict=True))
    # Proximal phalanx radius: half the finger's share of the hand width, but no wider than the
    # spacing of the MCP centres allows (adducted fingers' envelopes must not overlap).
    spacing = {f: min(abs(mcp_y[f] - mcp_y[g]) for g in const.FINGERS if g != f)
               for f in const.FINGERS}
    # ... and no wider than its shortest phalanx allows: a trimmed capsule needs a length of at
    # least its diameter (a short, wide hand: -2.5 SD length with +2.5 SD width, paper Table 1)
    r_pp = {f: min(0.5 * shares[f] / total * W, 0.5 * const.FINGER_SPACING_FILL * spacing[f],
                   _LENGTH_FILL * min(r * L / (2.0 * const.PHALANX_TAPER[s]) for r, s in zip(
                       const.SEGMENT_LENGTH_RATIO[f][1:], ("proximal", "middle", "distal"),
                       strict=True)))
            for f in const.FINGERS}

    digits: dict[str, DigitLayout] = {}
    for f in const.FINGERS:
        mc, pp, mp, dp = (r * L for r in const.SEGMENT_LENGTH_RATIO[f])
        tip_x = L - const.FINGERTIP_OFFSET_M[f] * scale
        mcp_x = tip_x - (pp + mp + dp)
        lengths = {"metacarpal": mc, "proximal": pp, "middle": mp, "distal": dp}
        radii = {
            "metacarpal": 0.5 * t,
            **{s: r_pp[f] * const.PHALANX_TAPER[s] for s in ("proximal", "middle", "distal")},
        }
        masses = {
            "metacarpal": 0.0,
            "proximal": rho * _capsule_volume(radii["proximal"], pp, closed_end=False),
            "middle": rho * _capsule_volume(radii["middle"], mp, closed_end=False),
            "distal": rho * _capsule_volume(radii["distal"], dp, closed_end=True),
        }
        digits[f] = DigitLayout(
            name=f,
            base_m=(mcp_x, mcp_y[f], 0.0),
            cmc_m=(mcp_x - mc, const.CMC_Y_OVER_MCP_Y * mcp_y[f], 0.0),
            lengths_m=lengths,
            radii_m=radii,
            masses_kg=masses,
            bone_radii_m={"metacarpal": r_mc, **{s: radii[s] - skin for s in
                                                   ("proximal", "middle", "distal")}},
        )

    # Thumb.
    mc, pp, dp = (r * L for r in const.SEGMENT_LENGTH_RATIO["thumb"])
    fx, fy, fz = const.THUMB_CMC_FRACTION
    cmc = (fx * L, fy * W, fz * t)
    index_tip_x = digits["index"].base_m[0] + sum(
        digits["index"].lengths_m[s] for s in ("proximal", "middle", "distal")
    )
    thumb_tip_x = index_tip_x - const.FINGERTIP_OFFSET_M["thumb_to_index"] * scale
    cos_spread = (thumb_tip_x - cmc[0]) / (mc + pp + dp)
    spread = math.acos(min(max(cos_spread, 0.0), 1.0))
    r_th = const.THUMB_BREADTH_OVER_INDEX * r_pp["index"]
    radii = {
        "metacarpal": const.THENAR_RADIUS_OVER_THUMB * r_th,
        "proximal": r_th,
        "distal": r_th * const.PHALANX_TAPER["distal"],
    }
    digits = {
        "thumb": DigitLayout(
            name="thumb",
            base_m=cmc,
            cmc_m=cmc,
            lengths_m={"metacarpal": mc, "proximal": pp, "distal": dp},
            radii_m=radii,
            masses_kg={
                "metacarpal": rho * _capsule_volume(radii["metacarpal"], mc, closed_end=False),
                "proximal": rho * _capsule_volume(radii["proximal"], pp, closed_end=False),
                "distal": rho * _capsule_volume(radii["distal"], dp, closed_end=True),
            },
            bone_radii_m={"metacarpal": r_th - skin, "proximal": r_th - skin,
                          "distal": radii["distal"] - skin},
        ),
        **digits,
    }

    # Every bone must keep a positive radius under the skin.
    thinnest = min((d.bone_radii_m[s] + skin, f"{d.name}_{s}") for d in digits.values()
                   for s in d.phalanges)
    if thinnest[0] - skin < _MIN_BONE_RADIUS_M:
        raise ValueError(
            f"skin_thickness_m = {skin!r} m leaves a bone radius of {thinnest[0] - skin:.4f} m in "
            f"{thinnest[1]} (envelope radius {thinnest[0]:.4f} m): allowed skin_thickness_m < "
            f"{thinnest[0] - _MIN_BONE_RADIUS_M:.4f} m for this hand"
        )

    palm_length = sum(digits[f].base_m[0] for f in const.FINGERS) / len(const.FINGERS)
    palm_mass = rho * _PALM_FILL * W * t * palm_length
    return HandLayout(
        config=config,
        length_m=L,
        width_m=W,
        thickness_m=t,
        skin_m=skin,
        metacarpal_bone_radius_m=r_mc,
        palm_length_m=palm_length,
        palm_mass_kg=palm_mass,
        thumb_spread_rad=spread,
        digits=digits,
    )
