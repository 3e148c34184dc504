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

__all__ = ["DESIGNS", "TOPOLOGIES", "Design", "PhalanxGeometry", "parse_design"]

TOPOLOGIES = ("solid", "pocket1", "pocket2")
_POCKET_HEIGHT = {"solid": 0.0, "pocket1": 1.0, "pocket2": 2.0}
_MIN_CORE_MM = 1.0  # material kept between the deepest offset band and the base at the top
_FLOOR_BAND_MM = 1.0  # offset band meshed under the pocket before the core begins


def _geometry_defaults() -> dict[str, float]:
    g = paper()["geometry"]
    return {"width": g["width_mm"], "height": g["height_mm"], "length": g["length_mm"],
            "outer": g["outer_layer_mm"]}


_D = _geometry_defaults()


@dataclass(frozen=True)
class PhalanxGeometry:
    """Dimensions of one synthetic phalanx (mm).

    Attributes:
        width_mm: across the finger (paper: 16).
        height_mm: base (bone) to the top of the skin (paper: 9).
        length_mm: along the finger (paper: 10); the indenter (20 x 10) covers it.
        outer_layer_mm: outer layer thickness (paper: 0.8), in (0, pocket_roof_mm).
        profile_exponent: superellipse exponent n of the outer profile (unstated; default 2, a
            half ellipse, the simplest rounded section with the paper's width and height).
        pocket_height_mm: 0 for the solid design, 1 or 2 for the paper's pockets.
        pocket_roof_mm: skin thickness above the pocket (unstated; default 1.4 mm: the 0.8 mm
            outer layer plus 0.6 mm of inner material, chosen so that pocket2-sil gives the
            paper's 0.39 N at 2 mm on the default 3D mesh (1.35 mm: 0.376 N, 1.4 mm: 0.391 N;
            2.0 mm: ~0.67 N). It is the one paper number used to choose geometry; every other
            number is a prediction).
        pocket_half_width_mm: half the pocket's span across the finger (unstated; default 5.0 mm).
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
        for name in ("width_mm", "height_mm", "length_mm", "outer_layer_mm", "pocket_roof_mm",
                     "pocket_half_width_mm"):
            v = getattr(self, name)
            if not np.isfinite(v) or v <= 0:
                raise ValueError(f"{name} = {v!r} must be finite and > 0")
        if not 1.5 <= self.profile_exponent <= 4.0:
            raise ValueError(
                f"profile_exponent = {self.profile_exponent!r} is outside the allowed range [1.5, 4]"
            )
        part = min(0.5 * self.width_mm, self.height_mm)
        if self.outer_layer_mm >= part:
            raise ValueError(
                f"outer_layer_mm = {self.outer_layer_mm!r} is thicker than the part: allowed range "
                f"(0, {part:g}) (half width and height bound it)"
            )
        if self.outer_layer_mm >= self.pocket_roof_mm:
            raise ValueError(
                f"outer_layer_mm = {self.outer_layer_mm!r} must be thinner than the pocket roof / "
                f"top band: allowed range (0, pocket_roof_mm = {self.pocket_roof_mm:g})"
            )
        h_max = self.height_mm - self.pocket_roof_mm - _FLOOR_BAND_MM - _MIN_CORE_MM
        if not 0.0 <= self.pocket_height_mm <= h_max:
            raise ValueError(
                f"pocket_height_mm = {self.pocket_height_mm!r} is taller than the space above the "
                f"base: allowed range [0, {h_max:g}] (height {self.height_mm:g} - roof "
                f"{self.pocket_roof_mm:g} - {_FLOOR_BAND_MM + _MIN_CORE_MM:g} mm floor and core)"
            )
        depth = self.band_depth_mm
        r_min = self.min_curvature_radius_mm()
        if depth >= 0.9 * r_min:
            raise ValueError(
                f"the meshed skin band is {depth:g} mm deep but the profile's smallest radius of "
                f"curvature is {r_min:.3g} mm: lower profile_exponent = {self.profile_exponent!r} "
                f"or pocket_roof_mm = {self.pocket_roof_mm!r} (band depth must stay < "
                f"{0.9 * r_min:.3g} mm)"
            )
        if self.pocket_height_mm > 0:
            x_max = 0.5 * self.width_mm - self.pocket_roof_mm - 0.5
            if not 0.5 <= self.pocket_half_width_mm <= x_max:
                raise ValueError(
                    f"pocket_half_width_mm = {self.pocket_half_width_mm!r} is outside the allowed "
                    f"range [0.5, {x_max:g}] (the pocket must stay inside the side walls)"
                )

    @property
    def semi_axes(self) -> tuple[float, float]:
        return 0.5 * self.width_mm, self.height_mm

    @property
    def band_depth_mm(self) -> float:
        """Depth of the offset-band region meshed under the surface (outer, roof, pocket, floor)."""
        return self.pocket_roof_mm + max(self.pocket_height_mm, 2.0) + _FLOOR_BAND_MM

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
        """The default geometry of this design, with optional field overrides."""
        base = PhalanxGeometry(pocket_height_mm=_POCKET_HEIGHT[self.topology])
        return replace(base, **overrides) if overrides else base


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
