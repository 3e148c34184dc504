"""The phalanx family of the paper (Fig. 3) and the 12 design names.

Cross-section (x across the width, y up from the bone, z along the finger):

* The outer profile is the superellipse ``|x/a|^n + (y/b)^n = 1``, ``y >= 0``, with ``a = width/2``
  and ``b = height``: a flat base (the bone, fixed) under a rounded top. The paper gives width,
  height and length but no drawing; ``profile_exponent`` n is the unstated shape parameter
  (n = 2: a half ellipse; larger n: a boxier section).
* The outer layer is the band between the outer profile and its inward normal offset by
  ``outer_layer_mm``; it is tied (shares nodes) to the inner part.
* An arc-shaped pocket is a band of constant height ``pocket_height_mm`` that follows the top,
  starting ``pocket_roof_mm`` below the outer surface and spanning ``|x| <= pocket_half_width_mm``
  (measured on the roof's underside). It runs the full length, open at both ends.

Every dimension the paper does not state is a named field here with its default and the reason for
it. Units: mm.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace

import numpy as np

from softhand.fem.materials import MATERIAL_NAMES
from softhand.paper import paper
from softhand.validate import check_number, show

__all__ = ["DESIGNS", "GEOMETRY_RANGES", "PLATE_LENGTH_MM", "PLATE_WIDTH_MM", "POCKET_FIELDS", "TOPOLOGIES", "Design",
           "PhalanxGeometry", "check_section_length", "parse_design"]

TOPOLOGIES = ("solid", "pocket1", "pocket2")
_POCKET_HEIGHT = {"solid": 0.0, "pocket1": 1.0, "pocket2": 2.0}
_MIN_CORE_MM = 1.0  # material kept between the deepest offset band and the base at the top
_FLOOR_BAND_MM = 1.0  # offset band meshed under the pocket before the core begins


def _geometry_defaults() -> dict[str, float]:
    g = paper()["geometry"]
    return {"width": g["width_mm"], "height": g["height_mm"], "length": g["length_mm"],
            "outer": g["outer_layer_mm"]}


_D = _geometry_defaults()


#: Allowed range [low, high] of each field (mm; the exponent has no unit). Each is a physically
#: sensible phalanx around the paper's (16 x 9 x 10 mm, 0.8 mm outer layer, 1 and 2 mm pockets)
#: that the structured mesh can build; the relations between fields are checked as well (see
#: `PhalanxGeometry`).
GEOMETRY_RANGES: dict[str, tuple[float, float]] = {
    "width_mm": (12.0, 20.0),  # finger phalanges; at most the indenter's 20 mm width
    "height_mm": (6.0, 12.0),  # the paper's 9 mm +- 3 mm; >= 6 leaves the bands and a core
    # the paper's 10 mm and shorter; longer (a palm's rounded border, `softhand.skin.
    # contact_classes`) for curved indenters, or under the plate's central 10 mm (`PLATE_LENGTH_MM`)
    "length_mm": (5.0, 60.0),
    "outer_layer_mm": (0.2, 2.0),  # a coating (0.2 mm) to a thick layer; < pocket_roof_mm
    "profile_exponent": (2.0, 3.0),  # half ellipse to boxy; see PhalanxGeometry
    "pocket_height_mm": (0.0, 6.0),  # 0: no pocket; else >= MIN_POCKET_MM and under the roof
    "pocket_roof_mm": (0.5, 3.0),  # skin above the pocket (and the top band of a solid design)
    "pocket_half_width_mm": (0.5, 9.5),  # inside the side walls (relation below)
}
#: The paper's plate (mm; 20 x 10): it covers a phalanx up to this wide and this long
PLATE_WIDTH_MM = 20.0
PLATE_LENGTH_MM = 10.0


def check_section_length(length_mm: float, mode: str) -> None:
    """Refuse a part longer than the plate in 2D (mode ``"2d"``): a plane-strain section's
    force per unit length is multiplied by the part's length, which only the plate's covers.

    Raises:
        ValueError: naming the length, the allowed bound and the way out.
    """
    if mode == "2d" and length_mm > PLATE_LENGTH_MM:
        raise ValueError(f"length_mm = {length_mm:g}: a 2D section is as long as the plate, at "
                         f"most {PLATE_LENGTH_MM:g} mm; use mode 3d")
MIN_POCKET_MM = 0.25  # thinnest pocket: thinner is a slit that closes before the ramp starts
_TOP_BAND_MM = 2.0  # band meshed under the roof of a solid design (or a pocket under 2 mm)
_CURVATURE_FRACTION = 0.75  # deepest band / smallest radius of curvature (mesh-scan limit)
_SIDE_WALL_MM = 0.5  # material kept between the pocket's edge and the side of the roof


@dataclass(frozen=True)
class PhalanxGeometry:
    """Dimensions of one synthetic phalanx (mm).

    Each field has an allowed range (`GEOMETRY_RANGES`, given below) and the fields must
    fit together: ``outer_layer_mm < pocket_roof_mm``; the bands meshed under the surface
    (roof, pocket or a 2 mm top band, 1 mm floor) plus a 1 mm core fit under ``height_mm``; the
    pocket's edge keeps 0.5 mm of side wall; the bands stay shallower than 0.75 times the outer
    profile's smallest radius of curvature (deeper, the offset curves fold and the mesh inverts;
    0.9 still inverted coarse and fine meshes of boxy sections in a scan of the range corners).
    Every geometry that passes these checks meshes with det J > 0 at every mesh level (the
    corners of the ranges are tested in 2D and 3D).

    Attributes:
        width_mm: across the finger (paper: 16), in [12, 20] (at most the indenter's 20 mm).
        height_mm: base (bone) to the top of the skin (paper: 9), in [6, 12].
        length_mm: along the finger (paper: 10), in [5, 60]. Up to `PLATE_LENGTH_MM` the paper's
            20 x 10 mm plate covers the part; a longer part (a stand-in for a long rounded edge,
            such as a palm's border pressed by a finger crossing it at an angle) is meshed
            finer over its central `PLATE_LENGTH_MM` than beyond (`softhand.fem.mesh`), and a
            plate presses only that central length. 3D only: a 2D section is as long as the plate.
        outer_layer_mm: outer layer thickness (paper: 0.8), in [0.2, 2] and < pocket_roof_mm.
        profile_exponent: superellipse exponent n of the outer profile, in [2, 3] (unstated;
            default 2, a half ellipse, the simplest rounded section with the paper's width and
            height). Below 2 the profile has corners (zero radius of curvature) at the base and the
            top that no skin band can follow; at 3 the corners of a boxy section are already about
            as tight as the 3.5 mm or deeper bands allow.
        pocket_height_mm: 0 for the solid design, 1 or 2 for the paper's pockets; a pocket is in
            [0.25, height_mm - pocket_roof_mm - 2] (1 mm floor band and 1 mm core below it), and
            the bands' curvature limit (above) may lower that bound.
        pocket_roof_mm: skin thickness above the pocket, in [0.5, 3] and at most
            height_mm - 4 (for a solid design: the band above a 2 mm top band of the mesh)
            (unstated; default 1.4 mm: the 0.8 mm
            outer layer plus 0.6 mm of inner material, chosen so that pocket2-sil gives the
            paper's 0.39 N at 2 mm on the default 3D mesh (1.35 mm: 0.376 N, 1.4 mm: 0.391 N;
            2.0 mm: ~0.67 N). It is the one paper number used to choose geometry; every other
            number is a prediction).
        pocket_half_width_mm: half the pocket's span across the finger, in
            [0.5, width_mm / 2 - pocket_roof_mm - 0.5] (unstated; default 5.0 mm). For a solid
            design it only places the mesh's contact-zone edge.

    Raises:
        ValueError: a non-number, non-finite or out-of-range field, or fields that do not fit
            together, naming the field, its value and the allowed range.
    """

    width_mm: float = _D["width"]
    height_mm: float = _D["height"]
    length_mm: float = _D["length"]
    outer_layer_mm: float = _D["outer"]
    profile_exponent: float = 2.0
    pocket_height_mm: float = 0.0
    pocket_roof_mm: float = 1.4
    pocket_half_width_mm: float = 5.0

    def __post_init__(self) -> None:
        for name, (lo, hi) in GEOMETRY_RANGES.items():
            object.__setattr__(self, name, check_number(name, getattr(self, name), lo=lo, hi=hi))
        roof, outer, h = self.pocket_roof_mm, self.outer_layer_mm, self.pocket_height_mm
        if outer >= roof:
            raise ValueError(
                f"outer_layer_mm = {outer!r}: must be thinner than pocket_roof_mm = {roof:g} "
                f"(allowed range [{GEOMETRY_RANGES['outer_layer_mm'][0]:g}, {roof:g}))"
            )
        below = _FLOOR_BAND_MM + _MIN_CORE_MM
        if 0.0 < h < MIN_POCKET_MM:
            raise ValueError(f"pocket_height_mm = {h!r}: expected 0 (no pocket) or a pocket of "
                             f"at least {MIN_POCKET_MM:g} mm")
        # the bands under the surface (roof, pocket or a 2 mm top band, floor) must fit over a
        # core and stay shallower than _CURVATURE_FRACTION x the profile's smallest radius of
        # curvature
        r_min = self.min_curvature_radius_mm()
        limit = _CURVATURE_FRACTION * r_min
        shape = (f"width_mm = {self.width_mm:g}, height_mm = {self.height_mm:g}, "
                 f"profile_exponent = {self.profile_exponent:g}")
        shallowest = GEOMETRY_RANGES["pocket_roof_mm"][0] + _TOP_BAND_MM + _FLOOR_BAND_MM
        curvature = (f"shallower than {_CURVATURE_FRACTION:g} x the profile's smallest radius of "
                     f"curvature, {r_min:.3g} mm")
        if shallowest >= limit:
            raise ValueError(
                f"{shape}: the profile's smallest radius of curvature is {r_min:.3g} mm; the skin "
                f"bands under the surface (at least {shallowest:g} mm deep) need more than "
                f"{shallowest / _CURVATURE_FRACTION:.3g} mm (a wider or flatter section, or a "
                "smaller profile_exponent)"
            )
        top_band = max(h, _TOP_BAND_MM)
        roof_max = min(self.height_mm - top_band - below, limit - top_band - _FLOOR_BAND_MM)
        if top_band == _TOP_BAND_MM and roof > roof_max:
            raise ValueError(
                f"pocket_roof_mm = {roof!r}: allowed range ({outer:g}, {roof_max:.3g}) at {shape} "
                f"(roof, a {top_band:g} mm pocket or top band and a {_FLOOR_BAND_MM:g} mm floor "
                f"band fit over a {_MIN_CORE_MM:g} mm core, {curvature})"
            )
        h_max = min(self.height_mm - roof - below, limit - roof - _FLOOR_BAND_MM)
        if h > h_max:
            raise ValueError(
                f"pocket_height_mm = {h!r}: allowed range [{MIN_POCKET_MM:g}, {h_max:.3g}) at "
                f"pocket_roof_mm = {roof:g}, {shape} (the pocket and a {_FLOOR_BAND_MM:g} mm floor "
                f"band fit over a {_MIN_CORE_MM:g} mm core, {curvature})"
            )
        x_max = 0.5 * self.width_mm - roof - _SIDE_WALL_MM
        if not 0.5 <= self.pocket_half_width_mm <= x_max:
            raise ValueError(
                f"pocket_half_width_mm = {self.pocket_half_width_mm!r}: allowed range "
                f"[0.5, {x_max:g}] at width_mm = {self.width_mm:g} and pocket_roof_mm = {roof:g} "
                f"(the pocket, or a solid design's contact zone, keeps {_SIDE_WALL_MM:g} mm of side "
                "wall)"
            )

    @property
    def semi_axes(self) -> tuple[float, float]:
        return 0.5 * self.width_mm, self.height_mm

    @property
    def band_depth_mm(self) -> float:
        """Depth of the offset-band region meshed under the surface (outer, roof, pocket, floor)."""
        return self.pocket_roof_mm + max(self.pocket_height_mm, _TOP_BAND_MM) + _FLOOR_BAND_MM

    @property
    def has_pocket(self) -> bool:
        return self.pocket_height_mm > 0.0

    # --- profile ---------------------------------------------------------------------------
    def profile(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Outer profile point and unit outward normal at angle parameter theta in [0, pi/2]."""
        a, b = self.semi_axes
        p = 2.0 / self.profile_exponent
        c, s = np.clip(np.cos(theta), 0, 1), np.clip(np.sin(theta), 0, 1)
        point = np.stack([a * c**p, b * s**p], axis=-1)
        normal = np.stack([b * c ** (2 - p), a * s ** (2 - p)], axis=-1)
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        return point, normal

    def offset(self, theta: np.ndarray, depth: float | np.ndarray) -> np.ndarray:
        """Point at inward normal distance ``depth`` below the outer profile."""
        point, normal = self.profile(theta)
        return point - np.asarray(depth)[..., None] * normal

    def min_curvature_radius_mm(self) -> float:
        """Smallest radius of curvature of the outer profile (numerical, over 2001 samples)."""
        theta = np.linspace(1e-4, 0.5 * np.pi - 1e-4, 2001)
        pts, _ = self.profile(theta)
        d1 = np.gradient(pts, theta, axis=0)
        d2 = np.gradient(d1, theta, axis=0)
        num = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
        kappa = num / np.linalg.norm(d1, axis=1) ** 3
        return float(1.0 / kappa[5:-5].max())

    def pocket_edge_theta(self) -> float:
        """Angle parameter where the pocket roof's underside reaches x = pocket_half_width_mm."""
        lo, hi = 0.0, 0.5 * np.pi
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            x = self.offset(np.array(mid), self.pocket_roof_mm)[0]
            lo, hi = (mid, hi) if x > self.pocket_half_width_mm else (lo, mid)
        return 0.5 * (lo + hi)


@dataclass(frozen=True)
class Design:
    """A named skin design: topology plus inner and outer material.

    Names are ``{solid|pocket1|pocket2}-{inner}[-{outer}]`` with materials ``sil`` and ``pu``;
    ``solid-pu-sil`` is a PU inner part under a SIL outer layer. A name without an outer material
    is homogeneous.
    """

    topology: str
    inner: str
    outer: str

    @property
    def name(self) -> str:
        base = f"{self.topology}-{self.inner}"
        return base if self.outer == self.inner else f"{base}-{self.outer}"

    @property
    def homogeneous(self) -> bool:
        return self.inner == self.outer

    def geometry(self, **overrides: float) -> PhalanxGeometry:
        """The default geometry of this design, with optional field overrides.

        A solid design has no pocket: `POCKET_FIELDS` other than their solid defaults are
        rejected (the run would be labelled with the solid design's name). For a solid design
        whose width or roof leaves no room for the default 5 mm contact-zone edge
        (``pocket_half_width_mm``), the edge moves inwards to the largest allowed value.

        Raises:
            ValueError: an unknown field, a pocket field for a solid design, or a value that
                `PhalanxGeometry` rejects.
        """
        unknown = [k for k in overrides if k not in GEOMETRY_RANGES]
        if unknown:
            raise ValueError(f"geometry field {unknown[0]} = {show(overrides[unknown[0]])} is "
                             f"unknown; allowed: {', '.join(GEOMETRY_RANGES)}")
        base = PhalanxGeometry(pocket_height_mm=_POCKET_HEIGHT[self.topology])
        if self.topology == "solid":
            for name in POCKET_FIELDS:
                if name in overrides and overrides[name] != getattr(base, name):
                    pocketed = ", ".join(d for d in DESIGNS if not d.startswith("solid"))
                    raise ValueError(
                        f"{name} = {show(overrides[name])}: design {self.name} has no pocket; "
                        f"{' and '.join(POCKET_FIELDS)} apply to the pocket designs ({pocketed})"
                    )
            width = overrides.get("width_mm", base.width_mm)
            roof = overrides.get("pocket_roof_mm", base.pocket_roof_mm)
            try:
                edge = float(width) / 2 - float(roof) - _SIDE_WALL_MM
            except (TypeError, ValueError):
                edge = base.pocket_half_width_mm  # a bad value: PhalanxGeometry names it
            if edge < base.pocket_half_width_mm:
                overrides = {**overrides, "pocket_half_width_mm": max(edge, 0.5)}
        return replace(base, **overrides) if overrides else base


#: Fields that describe the pocket: only the pocket designs may change them.
POCKET_FIELDS = ("pocket_height_mm", "pocket_half_width_mm")


_NAME = re.compile(r"^(solid|pocket1|pocket2)-(sil|pu)(?:-(sil|pu))?$")


def parse_design(name: str) -> Design:
    """Parse a design name, raising ValueError that lists the allowed names."""
    m = _NAME.match(name.strip()) if isinstance(name, str) else None
    if m is None or (m.group(3) is not None and m.group(3) == m.group(2)):
        raise ValueError(f"design {name!r} is unknown; allowed: {', '.join(DESIGNS)}")
    topo, inner, outer = m.group(1), m.group(2), m.group(3) or m.group(2)
    return Design(topo, inner, outer)


DESIGNS: tuple[str, ...] = tuple(
    Design(t, i, o).name for t in TOPOLOGIES for i in MATERIAL_NAMES for o in MATERIAL_NAMES
)
