"""The design space of the search: what varies, its bounds, and what a mould can make.

A candidate is a pocketed phalanx on the paper's envelope (16 x 9 x 10 mm, half-ellipse profile;
`softhand.fem.geometry.PhalanxGeometry`) with:

| variable | field | default bounds |
|---|---|---|
| outer layer thickness | ``outer_layer_mm`` | [0.5, 1.5] mm |
| pocket roof (skin over the pocket, outer layer included) | ``pocket_roof_mm`` | [1.0, 2.3] mm |
| pocket height | ``pocket_height_mm`` | [0.5, 3.5] mm |
| pocket half-width (the arc's span) | ``pocket_half_width_mm`` | [2.0, 6.0] mm |
| inner and outer material | ``inner``, ``outer`` | the library (`softhand.fem.library`) |

Derived, not free: the floor (material between the pocket and the bone at the apex,
``height - roof - pocket height``; the envelope fixes the height) and the embedded sensor's depth
(the FE reads patches on the bone, under the outer layer and on the pocket floor,
`softhand.fem.sensors`: the sensor under the outer layer sits ``outer_layer_mm`` deep, so the
outer layer sets it).

Manufacturability, stated and checked (`Candidate.check`): every wall at least ``MIN_WALL_MM`` =
0.5 mm (the outer layer, the inner material in the roof ``roof - outer``, and the side wall beside
the pocket, which `PhalanxGeometry` keeps at 0.5 mm); a floor of at least 2 mm (PhalanxGeometry's
1 mm floor band and 1 mm core); demouldable: the pocket is a prism of constant section running the
full length, open at both ends (the paper's), so a straight core pulls out along the finger. The
geometry type can express no other pocket, so this holds by construction; the STL test checks that
the pocket runs through (genus 1). Every relation `PhalanxGeometry` checks (bands under the
profile's curvature, the core) applies as well: the search never builds a geometry it would
refuse.

Dependent ranges: a deep roof leaves less room for the pocket, so the sampler draws each
geometric variable as a fraction in [0, 1] of its range *given the variables before it*
(outer -> roof -> height -> half-width), found from PhalanxGeometry's own checks by bisection
(`DesignSpace.candidate`). Every sample is then feasible, and the sampler's space is fixed.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from softhand.fem.geometry import GEOMETRY_RANGES, MIN_POCKET_MM, PhalanxGeometry
from softhand.fem.library import check_library_names, library
from softhand.validate import show

__all__ = ["DEFAULT_BOUNDS", "MIN_WALL_MM", "VARIABLES", "Candidate", "DesignSpace",
           "parse_bound"]

MIN_WALL_MM = 0.5
MIN_FLOOR_MM = 2.0  # PhalanxGeometry's floor band (1 mm) and core (1 mm) under the pocket
VARIABLES = ("outer_layer_mm", "pocket_roof_mm", "pocket_height_mm", "pocket_half_width_mm")
DEFAULT_BOUNDS: dict[str, tuple[float, float]] = {
    "outer_layer_mm": (0.5, 1.5),
    "pocket_roof_mm": (1.0, 2.3),  # PhalanxGeometry: roof + 2 mm band + 1 mm floor band within
    # 0.75 x the half-ellipse's 7.11 mm radius of curvature at the apex: roof <= 2.33 mm
    "pocket_height_mm": (0.5, 3.5),
    "pocket_half_width_mm": (2.0, 6.0),
}
#: the lowest value each bound may take: walls of MIN_WALL_MM, pockets of MIN_POCKET_MM
_LOWEST = {"outer_layer_mm": MIN_WALL_MM, "pocket_roof_mm": 2 * MIN_WALL_MM,
           "pocket_height_mm": MIN_POCKET_MM, "pocket_half_width_mm": 0.5}


def parse_bound(text: str) -> tuple[str, tuple[float, float]]:
    """``NAME=LO:HI`` as (name, (lo, hi)), checked (`DesignSpace` checks the range)."""
    name, sep, rng = str(text).partition("=")
    lo_text, sep2, hi_text = rng.partition(":")
    name = name.strip()
    if not sep or not sep2 or name not in VARIABLES:
        raise ValueError(f"bound {text!r}: expected NAME=LO:HI with NAME one of "
                         f"{', '.join(VARIABLES)}, e.g. pocket_height_mm=0.5:3")
    try:
        lo, hi = float(lo_text), float(hi_text)
    except ValueError:
        raise ValueError(f"bound {text!r}: {rng!r} is not two numbers LO:HI") from None
    return name, (lo, hi)


@dataclass(frozen=True)
class Candidate:
    """One design of the search: the geometric variables (mm) and the two materials."""

    outer_layer_mm: float
    pocket_roof_mm: float
    pocket_height_mm: float
    pocket_half_width_mm: float
    inner: str
    outer: str

    def overrides(self) -> dict[str, float]:
        """The `PhalanxGeometry` fields this candidate sets (the rest: the paper's defaults)."""
        return {k: float(getattr(self, k)) for k in VARIABLES}

    def geometry(self) -> PhalanxGeometry:
        """The checked geometry (`check`)."""
        self.check()
        return PhalanxGeometry(**self.overrides())

    @property
    def floor_mm(self) -> float:
        """Material between the pocket and the bone at the apex (mm)."""
        g = PhalanxGeometry(**self.overrides())
        return g.height_mm - self.pocket_roof_mm - self.pocket_height_mm

    @property
    def label(self) -> str:
        mats = self.inner if self.inner == self.outer else f"{self.inner}/{self.outer}"
        return (f"{mats} h{self.pocket_height_mm:.2f} w{self.pocket_half_width_mm:.2f} "
                f"r{self.pocket_roof_mm:.2f} o{self.outer_layer_mm:.2f}")

    def check(self) -> None:
        """Manufacturability and geometry (module docstring).

        Raises:
            ValueError: the first violation, naming the field, its value and the allowed range.
        """
        check_library_names([self.inner, self.outer], key="candidate materials")
        if self.outer_layer_mm < MIN_WALL_MM:
            raise ValueError(f"outer_layer_mm = {show(self.outer_layer_mm)}: allowed range >= "
                             f"{MIN_WALL_MM:g} mm (the minimum wall a mould fills)")
        inner_roof = self.pocket_roof_mm - self.outer_layer_mm
        if inner_roof < MIN_WALL_MM - 1e-12:
            raise ValueError(
                f"pocket_roof_mm = {show(self.pocket_roof_mm)}: allowed range >= "
                f"{self.outer_layer_mm + MIN_WALL_MM:g} mm at outer_layer_mm = "
                f"{self.outer_layer_mm:g} (the inner material in the roof is a wall of at least "
                f"{MIN_WALL_MM:g} mm)")
        if not self.pocket_height_mm >= MIN_POCKET_MM:
            raise ValueError(f"pocket_height_mm = {show(self.pocket_height_mm)}: allowed range >= "
                             f"{MIN_POCKET_MM:g} mm (the search designs pocketed phalanges)")
        PhalanxGeometry(**self.overrides())  # its own ranges and relations, named

    def to_dict(self) -> dict:
        return {**self.overrides(), "inner": self.inner, "outer": self.outer,
                "floor_mm": self.floor_mm, "sensor_depth_mm": self.outer_layer_mm}


def _largest(field_name: str, lo: float, hi: float, fixed: dict[str, float]) -> float | None:
    """The largest value in [lo, hi] of ``field_name`` that PhalanxGeometry accepts with
    ``fixed`` (bisection: each check is monotone in these fields); None when lo is refused."""
    def ok(v: float) -> bool:
        try:
            PhalanxGeometry(**{**fixed, field_name: v})
        except ValueError:
            return False
        return True

    if ok(hi):
        return hi
    if not ok(lo):
        return None
    a, b = lo, hi
    for _ in range(50):
        mid = 0.5 * (a + b)
        a, b = (mid, b) if ok(mid) else (a, mid)
    return a


@dataclass(frozen=True)
class DesignSpace:
    """Bounds of the geometric variables and the materials to combine.

    Attributes:
        bounds: per variable (`VARIABLES`) its (lo, hi), mm, lo < hi; missing: `DEFAULT_BOUNDS`.
        materials: library names the inner and outer parts are drawn from.

    Raises:
        ValueError: an unknown variable or material, inverted or out-of-range bounds, or bounds
            whose corner designs no geometry fits, naming the bound and the allowed range.
    """

    bounds: dict[str, tuple[float, float]] = field(default_factory=dict)
    materials: tuple[str, ...] = ("ecoflex-00-30", "dragon-skin-10", "dragon-skin-20")

    def __post_init__(self) -> None:
        unknown = [k for k in self.bounds if k not in VARIABLES]
        if unknown:
            raise ValueError(f"bound {unknown[0]} is unknown; allowed: {', '.join(VARIABLES)}")
        merged = {**DEFAULT_BOUNDS, **{k: tuple(map(float, v)) for k, v in self.bounds.items()}}
        for name, (lo, hi) in merged.items():
            lowest, highest = _LOWEST[name], GEOMETRY_RANGES[name][1]
            if not lo < hi:
                raise ValueError(f"bound {name}={lo:g}:{hi:g}: the low bound {lo:g} is not below "
                                 f"the high bound {hi:g}; allowed LO < HI within "
                                 f"[{lowest:g}, {highest:g}] mm")
            if lo < lowest or hi > highest:
                raise ValueError(f"bound {name}={lo:g}:{hi:g}: allowed range [{lowest:g}, "
                                 f"{highest:g}] mm")
        object.__setattr__(self, "bounds", merged)
        if not self.materials:
            raise ValueError("materials = (): allowed one or more of " + ", ".join(library()))
        mats = tuple(check_library_names(self.materials, key="materials"))
        object.__setattr__(self, "materials", tuple(dict.fromkeys(mats)))
        # the worst corner still leaves room for every variable
        (_, o_hi), (r_lo, r_hi) = merged["outer_layer_mm"], merged["pocket_roof_mm"]
        if o_hi + MIN_WALL_MM > r_hi:
            raise ValueError(f"bound pocket_roof_mm={r_lo:g}:{r_hi:g}: the roof must reach "
                             f"outer_layer_mm's high bound {o_hi:g} + {MIN_WALL_MM:g} mm of wall; "
                             f"allowed high bound >= {o_hi + MIN_WALL_MM:g} mm")
        corner = {**self._lowest(), "outer_layer_mm": o_hi, "pocket_roof_mm": r_hi}
        try:
            PhalanxGeometry(**corner)
        except ValueError as exc:
            where = ", ".join(f"{k} = {v:g}" for k, v in corner.items())
            raise ValueError(f"bounds: their deepest corner ({where}) makes no phalanx: "
                             f"{exc}") from None

    def _lowest(self) -> dict[str, float]:
        """Every variable at its low bound."""
        return {k: self.bounds[k][0] for k in VARIABLES}

    def _range(self, name: str, fixed: dict[str, float]) -> tuple[float, float] | None:
        lo, hi = self.bounds[name]
        top = _largest(name, lo, hi, {k: v for k, v in fixed.items() if k != name})
        return None if top is None else (lo, top)

    def candidate(self, fractions: dict[str, float], inner: str, outer: str) -> Candidate:
        """The candidate at ``fractions`` (each in [0, 1]) of each variable's feasible range
        given the variables before it (module docstring)."""
        chosen: dict[str, float] = {}
        for name in VARIABLES:
            f = min(max(float(fractions[name]), 0.0), 1.0)
            lo, hi = self.bounds[name]
            if name == "pocket_roof_mm":
                lo = max(lo, chosen["outer_layer_mm"] + MIN_WALL_MM)
            if name in ("pocket_height_mm", "pocket_half_width_mm"):
                rng = self._range(name, {**self._lowest(), **chosen})
                lo, hi = rng if rng is not None else (lo, lo)
            chosen[name] = lo + f * (hi - lo)
        cand = Candidate(**chosen, inner=inner, outer=outer)
        cand.check()
        return cand

    def with_materials(self, materials: tuple[str, ...]) -> DesignSpace:
        return replace(self, materials=materials)
