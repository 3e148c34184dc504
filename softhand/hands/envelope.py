"""The soft envelope of a hand as one layer of convex pieces: where skin (prosthetic) or tissue
(partner) lies over the bones, with no piece inside another at rest.

Both hands use the same pieces, built from the layout (`softhand.hands.layout`):

- every phalanx and the thumb metacarpal (thenar): a capsule of the segment's envelope radius R
  *trimmed* to the segment, i.e. from R to L - R along its axis, so that it spans exactly the
  segment's length [0, L] and consecutive segments touch at the joint instead of overlapping by 2R
  (a full-length capsule's round ends reach R past each joint);
- the palm: the convex hull of the four finger metacarpals' envelopes (capsules of radius t / 2
  from CMC to MCP, so the palm is W wide at the MCPs and t thick), clipped by the wrist-crease plane,
  one plane through each pair of neighbouring MCP centres (where the proximal phalanges begin), a
  plane parallel to the thenar's axis at the thenar's radius (the thenar is its own piece); the
  partner keeps it whole (PALM_CUTS), the prosthetic's four regions cut it by further planes,
  palmar / dorsal (z = 0) and proximal / distal. Clipping a convex hull by planes keeps it
  convex, and pieces that share a cutting plane lie on opposite sides of it, so they cannot
  overlap.

Each piece is returned in its body's frame (the hand frame for the palm, the digit frame for a
phalanx; `softhand.hands.skeleton`). Joint flexion folds two trimmed capsules into each
other on the flexor side (as real finger creases do); tests/test_hands.py measures that depth over
a grid of postures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull

from softhand.hands import constants as const
from softhand.hands.layout import HandLayout

__all__ = ["PALM_CUTS", "Piece", "clip_hull", "hand_pieces", "palm_hull_points", "thenar_axis"]

_SPHERE_POINTS = 120  # points per end sphere of a metacarpal envelope (Fibonacci lattice)


@dataclass(frozen=True)
class Piece:
    """One convex piece of the envelope, in its body's frame (m).

    Attributes:
        name: piece name: a segment key (``index_proximal``, ``thumb_metacarpal``) or a palm
            piece (``palm``, ``back``; the prosthetic: ``palm_proximal``, ``palm_distal``,
            ``back_proximal``, ``back_distal``).
        body: segment key of the body it rides on (``palm`` for the palm pieces).
        kind: ``"capsule"`` (``fromto`` and ``radius``) or ``"mesh"`` (``vertices``, the piece's
            convex hull vertices).
    """

    name: str
    body: str
    kind: str
    fromto: tuple[float, ...] = ()
    radius: float = 0.0
    vertices: np.ndarray | None = None

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned bounds (lower, upper corner) in the body frame."""
        if self.kind == "mesh":
            return self.vertices.min(axis=0), self.vertices.max(axis=0)
        a, b = np.array(self.fromto[:3]), np.array(self.fromto[3:])
        return np.minimum(a, b) - self.radius, np.maximum(a, b) + self.radius


def _fibonacci_sphere(n: int) -> np.ndarray:
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = math.pi * (1 + 5**0.5) * i
    return np.column_stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)])


def palm_hull_points(layout: HandLayout) -> np.ndarray:
    """Points whose convex hull is the palm's envelope: spheres of radius t / 2 at each finger's
    CMC and MCP (a capsule is the hull of its two end spheres)."""
    unit = _fibonacci_sphere(_SPHERE_POINTS)
    r = 0.5 * layout.thickness_m
    centres = [layout.digits[f].cmc_m for f in const.FINGERS]
    centres += [layout.digits[f].base_m for f in const.FINGERS]
    return np.concatenate([np.asarray(c) + r * unit for c in centres])


def clip_hull(points: np.ndarray, normal, offset: float) -> np.ndarray:
    """Vertices of the convex hull of ``points`` clipped to the half-space normal . p <= offset.

    Returns the hull vertices inside it plus the points where hull edges cross the plane.

    Raises:
        ValueError: if nothing of the hull lies inside the half-space.
    """
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    hull = ConvexHull(points)
    verts = points[hull.vertices]
    side = points @ n - offset
    keep = [points[i] for i in hull.vertices if side[i] <= 0]
    edges = set()
    for tri in hull.simplices:
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            edges.add((min(a, b), max(a, b)))
    for a, b in edges:
        sa, sb = side[a], side[b]
        if (sa < 0 < sb) or (sb < 0 < sa):
            t = sa / (sa - sb)
            keep.append(points[a] + t * (points[b] - points[a]))
    if len(keep) < 4:
        raise ValueError(f"the plane {n.tolist()} . p <= {offset:.4g} leaves no volume of the hull "
                         f"(its vertices span {verts.min(axis=0)} to {verts.max(axis=0)})")
    out = np.asarray(keep)
    return out[ConvexHull(out).vertices]


def thenar_axis(layout: HandLayout) -> tuple[np.ndarray, np.ndarray]:
    """The adducted thumb metacarpal's axis in the hand frame: (CMC point, unit direction)."""
    d = layout.digits["thumb"]
    s = layout.thumb_spread_rad
    return np.asarray(d.cmc_m, float), np.array([math.cos(s), math.sin(s), 0.0])


def _palm_cuts(layout: HandLayout) -> list[tuple[np.ndarray, float]]:
    """Half-spaces (normal, offset) that bound the palm: wrist crease, MCP arch, thenar."""
    cuts = [(np.array([-1.0, 0.0, 0.0]), 0.0)]  # distal of the wrist crease
    # distal: one plane through each pair of neighbouring MCP centres (the MCP line is an arch),
    # each stopped where the nearest proximal phalanx's trimmed capsule begins (its round cap is
    # centred R along the finger from the MCP)
    # (a cap clear of its own pair's plane is outside the intersection of all of them)
    caps = {f: (np.asarray(layout.digits[f].base_m, float)
                + np.array([layout.digits[f].radii_m["proximal"], 0.0, 0.0]),
                layout.digits[f].radii_m["proximal"]) for f in const.FINGERS}
    for a, b in zip(const.FINGERS[:-1], const.FINGERS[1:], strict=True):
        pa, pb = (np.asarray(layout.digits[f].base_m, float) for f in (a, b))
        along = (pa - pb) / np.linalg.norm(pa - pb)
        distal = np.array([along[1], -along[0], 0.0])  # in the palm plane, across the MCP line
        if distal[0] < 0:
            distal = -distal
        cuts.append((distal, min(float(distal @ caps[f][0]) - caps[f][1] for f in (a, b))))
    # clear of the thenar: at least its radius from its axis, on the palm's side
    p0, u = thenar_axis(layout)
    centre = np.array([0.5 * layout.palm_length_m, 0.0, 0.0])
    w = (centre - p0) - ((centre - p0) @ u) * u
    w /= np.linalg.norm(w)
    radius = layout.digits["thumb"].radii_m["metacarpal"]
    cuts.append((-w, float(-w @ p0 - radius)))
    return cuts


def _palm_piece(points: np.ndarray, cuts) -> np.ndarray:
    for normal, offset in cuts:
        points = clip_hull(points, normal, offset)
    return points


#: How a hand's palm is cut into pieces (hand_pieces): ``whole`` one convex piece, palmar and
#: dorsal sides and borders together (the partner's tissue: no seam, so no indentation at its
#: borders is resisted twice); ``quarters`` palmar / dorsal x proximal / distal (the prosthetic's
#: Palm1, Palm2, Back1, Back2 regions, each with its own sensor).
PALM_CUTS = ("whole", "quarters")


def hand_pieces(layout: HandLayout, *, palm: str) -> list[Piece]:
    """The envelope pieces of a hand (see the module docstring).

    Args:
        layout: the hand's numbers.
        palm: how the palm is cut (PALM_CUTS).
    """
    if palm not in PALM_CUTS:
        raise ValueError(f"palm = {palm!r}: allowed {', '.join(PALM_CUTS)}")
    pieces: list[Piece] = []
    base = _palm_piece(palm_hull_points(layout), _palm_cuts(layout))
    if palm == "whole":
        pieces.append(Piece("palm", "palm", "mesh", vertices=base))
    sides = {"palm": (np.array([0.0, 0.0, 1.0]), 0.0), "back": (np.array([0.0, 0.0, -1.0]), 0.0)}
    x_split = 0.5 * layout.palm_length_m
    for side, (normal, offset) in sides.items():
        if palm == "whole":
            break
        half = clip_hull(base, normal, offset)
        pieces.append(Piece(f"{side}_proximal", "palm", "mesh",
                            vertices=clip_hull(half, [1.0, 0.0, 0.0], x_split)))
        pieces.append(Piece(f"{side}_distal", "palm", "mesh",
                            vertices=clip_hull(half, [-1.0, 0.0, 0.0], -x_split)))
    for digit, d in layout.digits.items():
        for seg in d.phalanges:
            length, radius = d.lengths_m[seg], d.radii_m[seg]
            if length < 2 * radius:
                raise ValueError(f"{digit}_{seg}: length {length:.4f} m is shorter than its "
                                 f"envelope's diameter {2 * radius:.4f} m")
            pieces.append(Piece(f"{digit}_{seg}", f"{digit}_{seg}", "capsule",
                                fromto=(radius, 0.0, 0.0, length - radius, 0.0, 0.0),
                                radius=radius))
    return pieces
