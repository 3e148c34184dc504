"""The palm (and the back of the hand): a slab of a design's skin layers over a metacarpal.

Cross-section of one cell (x across the metacarpals, y up from the floor between them, z along
the metacarpal; the cells repeat across the hand):

    y = rise + skin  ─────────────────────────────  flat top: outer surface, the indenter's face
                     outer layer, roof, pocket (|x| <= the design's pocket_half_width_mm), floor:
                     bands at constant depth under the top, as on the phalanx
                     core: skin material down to the bone
    y = y_b(x)       ╭──╮
                  ──╯    ╰──  bone (the metacarpal shaft's crest over a floor), fixed
                 x = 0     x = spacing / 2 (the next cell, mirrored, beyond)

The bone surface is the cosine bump ``y_b(x) = rise cos^2(pi x / (4 b))`` for ``|x| <= 2 b`` and 0
beyond (b = ``bone_half_width_mm``: the bump is 2 b wide at half its rise, the shaft's width,
and meets the floor with zero slope; its slope is at most ``pi rise / (4 b)``, so it has no
vertical tangent and every column of the mesh below is a function of x).

The mesh is a quarter cell, the same conventions as the phalanx's (`softhand.fem.mesh`):
quadratic Q27 (Q9 in 2D) elements on a structured grid mapped column by column (each column's
nodes lie between ``y_b(x)`` and the flat top), local axes (level up, -x, z), the top row's upper
faces the outer surface, pocket roof and floor faces paired row by row. Its boundary conditions:

* the bone surface ``y = y_b(x)`` is fixed (all dofs);
* x = 0 (the plane through the metacarpal's axis) and the model's side are symmetry planes,
  ``u_x = 0``. By default (``side_cells = 0``) the side is x = spacing/2, the midplane between two
  metacarpals: the cells repeat across the hand, so the model is exact for a load that repeats
  with them (a plate or a palm as wide as the hand, a finger across the metacarpals at 90 deg)
  and stands for a load over every metacarpal when the load is local in x. ``side_cells = k``
  models k unloaded neighbouring cells beside the loaded one (the side at x = (k + 1/2) spacing),
  for a load local in x: measured (2026-12, default mesh unless said), one side cell lowers the
  force at 0.5 mm by 8 % for the 20 x 10 mm plate (3D coarse, solid-sil) and by 20 % for a
  cylinder R = 8 mm along the metacarpal (2D, solid-sil); a second cell changes that by 0.6 %.
* z = 0 is a symmetry plane and the far end z = half_length is one too (``u_z = 0``, a roller):
  the palm continues past the modelled part, so its tissue there is held in z, not free; a load
  that is uniform along z (the cylinder at 0 deg) is then exactly plane strain and the 3D force is
  the 2D section's force per mm times the modelled length 2 x half_length.

The 2D model (``dim=2``) is that plane-strain section, x >= 0 (force per mm times
2 x half_length): exact for the cylinder at 0 deg, and the plate as infinitely long along z.
The paper's 20 x 10 mm plate lies with its 20 mm across the metacarpals (as across the phalanx)
and its 10 mm along them; over the palm it is smaller than the body, so the mesh carries its
half sizes (``Mesh.plate_half_mm``) and the plate presses only the points under it
(`softhand.fem.contact.plate_gaps`).

Units: mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from softhand.fem.elements import reference_element
from softhand.fem.geometry import Design, PhalanxGeometry, parse_design
from softhand.fem.mesh import Mesh, _graded, _level_lines, _with_midpoints, compact_nodes
from softhand.paper import paper
from softhand.validate import check_number

__all__ = ["PALM_MESH_LEVELS", "PALM_RANGES", "PalmGeometry", "PalmMeshSpec", "bone_height",
           "palm_mesh"]

#: Allowed range [low, high] of each `PalmGeometry` field (mm); see its docstring.
PALM_RANGES: dict[str, tuple[float, float]] = {
    "spacing_mm": (14.0, 26.0),
    "bone_half_width_mm": (2.5, 6.5),
    "bone_rise_mm": (0.0, 8.0),
    "skin_mm": (4.5, 20.0),
    "half_length_mm": (10.0, 50.0),
}
_MIN_CORE_MM = 1.0  # skin material kept between the deepest band and the crest (as the phalanx)
_SIDE_WALL_MM = 0.5  # material kept between the pocket's edge and the neighbouring cell's pocket


def _paper_spacing() -> float:
    """The paper's experimenter's hand width (Table 1, 88 mm) over 4.4 cells."""
    return paper()["anthropometry"]["experimenter_hand_width_mm"] / 4.4


@dataclass(frozen=True)
class PalmGeometry:
    """Dimensions of the palm model (mm): a cell of skin over one metacarpal.

    Each field has an allowed range (`PALM_RANGES`); the bump must fit in its cell
    (``2 bone_half_width_mm <= spacing_mm / 2``). The design's layers must fit under the skin:
    `palm_mesh` checks that against the design.

    Attributes:
        spacing_mm: cell width, centre to centre of adjacent metacarpals, in [14, 26]. Default
            20 mm = 88 mm / 4.4, the paper's experimenter's hand width (Table 1; ANSUR II's male
            mean breadth, 88.3 mm, gives the same) shared by four metacarpal cells plus a fifth
            of a cell of border tissue on each side (named assumption: the hand breadth is
            measured over the metacarpal heads, with the skin and the hypothenar/first
            web's soft border beyond the index and little metacarpals). The range covers
            breadths of about 62 to 114 mm.
        bone_half_width_mm: half the metacarpal shaft's width, measured at half the bump's rise,
            in [2.5, 6.5] and at most spacing_mm / 4 (the bump's foot, 2 x this, stays in the
            cell). Default 4.5 mm: a third metacarpal shaft taken as about 9 mm wide (named
            assumption, no measured source at hand; the hand model's 10 mm shaft,
            ``softhand.hands.constants.METACARPAL_BONE_RADIUS_OVER_THICKNESS``, is of the same
            order).
        bone_rise_mm: how far the crest stands above the floor between the bones, in [0, 8]
            (0: a flat bone, the confined-layer check). Default 4 mm: half of a shaft about
            8 mm deep (named assumption), i.e. the floor lies at the shafts' mid-depth, where
            the interosseous muscles fill the space between them; everything below the floor
            is taken as rigid, everything above it as the design's inner material.
        skin_mm: skin thickness over the crest, in [4.5, 20] and at least the design's bands
            plus a 1 mm core (5.4 mm for the default layers; 4.5 for the thinnest roof the
            phalanx allows, 0.5 mm, over a 2 mm top band and a 1 mm floor band). Default 9 mm, the phalanx's height
            (paper Fig. 3), so that the palm differs from the phalanx only in its geometry
            (a flat, wide top over a ridged bone instead of a rounded 16 mm section); the back
            of a human hand has thinner tissue over its metacarpals, so Back1/Back2 may want
            less (a prosthetic skin has the thickness its design gives it).
        half_length_mm: modelled half length along the metacarpal, in [10, 50]: a numerical
            length (the real palm's tissue continues past it, over the carpus and into the
            fingers, which the roller at the far end stands for). Default 35 mm, half a middle
            metacarpal (0.373 x 190 mm hand length, Buchholz et al. 1992, as in
            ``softhand.hands.constants``), chosen by a run (3D, HEAD solver of 2026-12, mesh
            with 8 columns, silicone, 0.5 mm/s): from 35 to 50 mm the 90 deg cylinder's force
            (R = 8 mm, solid-sil) changes by -0.3 % at 0.5 mm and -0.35 % at 1 mm, the plate's
            (pocket2-sil) by +0.5 %, the size of the far elements' own effect (+-0.6 %); at
            25 mm the cylinder was 2.5 % stiffer than at 50 mm. The contact does not feel the
            end at 35 mm.
        side_cells: unloaded neighbouring cells modelled beside the loaded one, an integer in
            [0, 3]. Default 0: the midplane between two metacarpals is a symmetry plane (cells
            repeat with the load); see the module docstring for when one more cell matters.

    Raises:
        ValueError: a non-number, non-finite or out-of-range field, or a bump wider than its
            cell, naming the field, its value and the allowed range.
    """

    spacing_mm: float = _paper_spacing()
    bone_half_width_mm: float = 4.5
    bone_rise_mm: float = 4.0
    skin_mm: float = 9.0
    half_length_mm: float = 35.0
    side_cells: int = 0

    def __post_init__(self) -> None:
        for name, (lo, hi) in PALM_RANGES.items():
            object.__setattr__(self, name, check_number(name, getattr(self, name), lo=lo, hi=hi))
        check_number("side_cells", self.side_cells, lo=0, hi=3, integer=True)
        object.__setattr__(self, "side_cells", int(self.side_cells))
        b_max = 0.25 * self.spacing_mm
        if self.bone_half_width_mm > b_max:
            raise ValueError(
                f"bone_half_width_mm = {self.bone_half_width_mm!r}: allowed range "
                f"[{PALM_RANGES['bone_half_width_mm'][0]:g}, {b_max:g}] at spacing_mm = "
                f"{self.spacing_mm:g} (the bone's foot, twice its half-width, stays inside "
                "the half cell)")

    @property
    def width_mm(self) -> float:
        """Modelled width across x >= 0: the loaded half cell and the side cells."""
        return (self.side_cells + 0.5) * self.spacing_mm

    @property
    def top_mm(self) -> float:
        """Height of the flat top above the floor between the bones."""
        return self.bone_rise_mm + self.skin_mm

    @property
    def max_slope(self) -> float:
        """Steepest slope of the bone surface, pi rise / (4 b)."""
        return np.pi * self.bone_rise_mm / (4.0 * self.bone_half_width_mm)


def bone_height(geom: PalmGeometry, x: np.ndarray) -> np.ndarray:
    """The bone surface ``y_b(x)``: rise cos^2(pi x / 4b) for |x| <= 2b, else 0 (mm), with x
    measured from the nearest metacarpal's axis (the bones repeat every ``spacing_mm``)."""
    x = _to_bone(geom, x)
    b = geom.bone_half_width_mm
    return np.where(x < 2 * b, geom.bone_rise_mm * np.cos(np.pi * x / (4 * b)) ** 2, 0.0)


@dataclass(frozen=True)
class PalmMeshSpec:
    """Element counts of the palm mesh (quadratic elements).

    Attributes:
        n_top: across the pocket span (the contact zone) 0 <= x <= pocket_half_width_mm, cosine
            spaced (small at x = 0, where a cylinder along the metacarpal first touches, and at
            the pocket's edge, where the closed pocket behaves like a crack tip).
        n_side: from the pocket's edge to the cell's midplane, graded by ``side_grading``.
        n_outer, n_roof, n_pocket, n_floor, n_core: through each band, outside in (as the
            phalanx's `softhand.fem.mesh.MeshSpec`; a solid design meshes a 2 mm top
            band in place of the pocket).
        n_plate: along z under the plate's half length (uniform), 3D only.
        n_far: along z from the plate's edge to the far end, 3D only, graded by ``far_grading``.
        side_grading: first (at the pocket edge) / last element size along ``n_side``, in (0, 1].
        far_grading: first (at the plate's edge) / last element size along ``n_far``, in (0, 1].
    """

    n_top: int = 6
    n_side: int = 4
    n_outer: int = 1
    n_roof: int = 2
    n_pocket: int = 2
    n_floor: int = 1
    n_core: int = 2
    n_plate: int = 4
    n_far: int = 4
    side_grading: float = 0.1
    far_grading: float = 0.25

    def __post_init__(self) -> None:
        for name in ("n_top", "n_side", "n_outer", "n_roof", "n_pocket", "n_floor", "n_core",
                     "n_plate", "n_far"):
            check_number(name, getattr(self, name), lo=1, hi=64, integer=True)
        for name in ("side_grading", "far_grading"):
            check_number(name, getattr(self, name), lo=0.0, hi=1.0, lo_open=True)

    def refined(self, factor: int = 2) -> PalmMeshSpec:
        """Every element count multiplied by ``factor`` (same gradings)."""
        counts = ("n_top", "n_side", "n_outer", "n_roof", "n_pocket", "n_floor", "n_core",
                  "n_plate", "n_far")
        return PalmMeshSpec(**{n: getattr(self, n) * factor for n in counts},
                            side_grading=self.side_grading, far_grading=self.far_grading)


#: Element counts by level. ``default`` against refinement (HEAD solver of 2026-12, silicone,
#: 0.5 mm/s, R = 8 mm cylinder): in the 2D section (the cylinder along the metacarpal) solid-sil
#: is +0.9 % at 0.5 mm against 4x the elements; pocket2-sil is +4.3, +5.3 and +7.6 % at 0.5, 1
#: and 2 mm against 4x, itself still falling by about 2 % per refinement (the closed pocket's
#: edges are crack tips and converge slowly; grading towards them, side_grading 0.1 and cosine
#: spacing over the span, halved the 2 mm error of a first default with n_top 5, n_side 3,
#: side_grading 0.4: +16 %). Along z (3D, solid-sil, the cylinder across at 90 deg) twice the
#: elements change the force by -0.1 % at 0.5 mm and -0.5 % at 1 mm. The 3D default has 16,000
#: to 18,000 dofs (the phalanx's: 5,600 to 6,200).
PALM_MESH_LEVELS: dict[str, PalmMeshSpec] = {
    "coarse": PalmMeshSpec(n_top=3, n_side=2, n_roof=1, n_pocket=1, n_core=1, n_plate=2,
                           n_far=2),
    "default": PalmMeshSpec(),
}
PALM_MESH_LEVELS["fine"] = PALM_MESH_LEVELS["default"].refined(2)


def _cosine(n: int) -> np.ndarray:
    """n + 1 points on [0, 1], cosine spaced (small elements at both ends)."""
    return 0.5 * (1.0 - np.cos(np.pi * np.arange(n + 1) / n))


def _x_lines(geom: PalmGeometry, layers: PhalanxGeometry, spec: PalmMeshSpec) -> np.ndarray:
    """Node columns from the model's side x = (side_cells + 1/2) spacing down to x = 0 (the
    grid's -x direction): each half cell has the same columns, mirrored about its bone."""
    s, pw = geom.spacing_mm, layers.pocket_half_width_mm
    top = pw * _cosine(spec.n_top)
    side = pw + (0.5 * s - pw) * _graded(spec.n_side, spec.side_grading)
    half = np.concatenate([top, side[1:]])
    half[-1] = 0.5 * s  # the midplane's nodes lie on it exactly
    edges = [half]
    for j in range(1, geom.side_cells + 1):
        edges += [j * s - half[::-1][1:], j * s + half[1:]]
    return _with_midpoints(np.concatenate(edges))[::-1]


def _to_bone(geom: PalmGeometry, x: np.ndarray) -> np.ndarray:
    """Distance across from the nearest metacarpal's axis (the bones at x = j spacing)."""
    x = np.asarray(x, dtype=float)
    return np.abs(x - geom.spacing_mm * np.round(x / geom.spacing_mm))


def _z_lines(geom: PalmGeometry, half_plate_z: float, spec: PalmMeshSpec) -> np.ndarray:
    """Node lines along z: uniform under the plate, graded beyond its edge to the far end."""
    L = geom.half_length_mm
    if half_plate_z >= L:
        edges = L * np.linspace(0.0, 1.0, spec.n_plate + spec.n_far + 1)
    else:
        under = half_plate_z * np.linspace(0.0, 1.0, spec.n_plate + 1)
        far = half_plate_z + (L - half_plate_z) * _graded(spec.n_far, spec.far_grading)
        edges = np.concatenate([under, far[1:]])
    edges[-1] = L  # the far end's nodes lie on it exactly
    return _with_midpoints(edges)


def _check_fit(geom: PalmGeometry, layers: PhalanxGeometry) -> None:
    """The design's bands fit under the skin over the crest, its pocket inside the cell."""
    deep = layers.band_depth_mm
    if geom.skin_mm < deep + _MIN_CORE_MM:
        raise ValueError(
            f"skin_mm = {geom.skin_mm!r}: allowed range [{deep + _MIN_CORE_MM:g}, "
            f"{PALM_RANGES['skin_mm'][1]:g}] for these layers (outer layer, roof, pocket or 2 mm "
            f"top band and 1 mm floor band, {deep:g} mm deep, over a {_MIN_CORE_MM:g} mm core)")
    pw_max = 0.5 * geom.spacing_mm - _SIDE_WALL_MM
    if layers.pocket_half_width_mm > pw_max:
        raise ValueError(
            f"pocket_half_width_mm = {layers.pocket_half_width_mm!r}: allowed range [0.5, "
            f"{pw_max:g}] at spacing_mm = {geom.spacing_mm:g} (the pocket keeps "
            f"{_SIDE_WALL_MM:g} mm of wall from the neighbouring cell's pocket)")


def palm_mesh(design: str | Design, geometry: PalmGeometry | None = None,
              spec: PalmMeshSpec | str = "default", dim: int = 3, *,
              layers: PhalanxGeometry | None = None,
              plate_mm: tuple[float, float] | None = None) -> Mesh:
    """Build the quarter-cell palm mesh of a design (module docstring: conventions).

    Args:
        design: a design name or `Design`; its layers (outer layer, roof, pocket height
            and half width) come from ``design.geometry()``, the phalanx's defaults.
        geometry: the palm's dimensions (default `PalmGeometry`).
        spec: element counts, or a level of `PALM_MESH_LEVELS`.
        dim: 3 (quarter cell) or 2 (plane-strain half section, force per mm times the
            modelled length 2 x half_length_mm).
        layers: a phalanx geometry whose layer fields replace the design's defaults.
        plate_mm: full sizes of the plate's face (across, along the metacarpals), mm; default the
            paper's 20 x 10 mm indenter. Sizes at least the modelled cell's cover it whole.

    Raises:
        ValueError: a bad ``dim``, spec level or plate size, or layers that do not fit the palm.
    """
    design = parse_design(design) if isinstance(design, str) else design
    geom = geometry if geometry is not None else PalmGeometry()
    layers = layers if layers is not None else design.geometry()
    if dim not in (2, 3):
        raise ValueError(f"dim = {dim!r}: allowed 2 (plane strain) or 3")
    if isinstance(spec, str):
        if spec not in PALM_MESH_LEVELS:
            raise ValueError(f"spec = {spec!r}: allowed {', '.join(PALM_MESH_LEVELS)} or a "
                             "PalmMeshSpec")
        spec = PALM_MESH_LEVELS[spec]
    plate = tuple(paper()["loading"]["indenter_mm"]) if plate_mm is None else plate_mm
    if not (isinstance(plate, tuple | list) and len(plate) == 2):
        raise ValueError(f"plate_mm = {plate_mm!r}: expected (across, along) in mm")
    hx, hz = (0.5 * check_number(f"plate_mm[{k}]", v, lo=0.0, lo_open=True, hi=1000.0)
              for k, v in enumerate(plate))
    _check_fit(geom, layers)

    x = _x_lines(geom, layers, spec)
    kinds, values, bands = _level_lines(layers, spec)
    top, deep = geom.top_mm, layers.band_depth_mm
    yb = bone_height(geom, x)
    grid = np.empty((len(values), len(x)))  # (level, column) -> y
    for k, (kind, v) in enumerate(zip(kinds, values, strict=True)):
        grid[k] = yb + v * (top - deep - yb) if kind == "core" else top - v
    z = _z_lines(geom, hz, spec) if dim == 3 else np.zeros(1)
    nk, ni, nz = len(values), len(x), len(z)
    ek, ei, ez = (nk - 1) // 2, (ni - 1) // 2, max((nz - 1) // 2, 1)
    # element columns over a pocket: their middle node within the pocket's half width of a bone
    in_span = _to_bone(geom, x[1::2]) < layers.pocket_half_width_mm
    coords = np.empty((nk, ni, nz, dim))
    coords[..., 0] = x[None, :, None]
    coords[..., 1] = grid[:, :, None]
    if dim == 3:
        coords[..., 2] = z[None, None, :]
    gid = np.arange(nk * ni * nz).reshape(nk, ni, nz)

    local = [(p0, p1, p2) for p2 in range(3 if dim == 3 else 1) for p1 in range(3)
             for p0 in range(3)]
    pocket = layers.has_pocket
    elems, layer, void, outer_rows, roof_rows, floor_rows = [], [], [], [], [], []
    for kz in range(ez):
        for ki in range(ei):
            for kk in range(ek):
                elems.append([gid[2 * kk + p0, 2 * ki + p1, 2 * kz + p2 if dim == 3 else 0]
                              for (p0, p1, p2) in local])
                band, e = bands[kk], len(elems) - 1
                span = pocket and in_span[ki]
                void.append(span and band == "pocket")
                layer.append(1 if band == "outer" else 0)
                if kk == ek - 1:
                    outer_rows.append(e)
                if span and band == "roof" and bands[kk - 1] == "pocket":
                    roof_rows.append(e)
                if span and band == "floor" and bands[kk + 1] == "pocket":
                    floor_rows.append(e)
    elems = np.array(elems)
    keep = ~np.array(void)
    X, conn_all, new_id = compact_nodes(coords.reshape(-1, dim), elems, keep)
    npf = 3 ** (dim - 1)
    face_hi = [a for a, p in enumerate(local) if p[0] == 2]
    face_lo = [a for a, p in enumerate(local) if p[0] == 0]

    bone = new_id[gid[0].ravel()]
    tol = 1e-9
    fixed = [bone * dim + c for c in range(dim)]
    fixed.append(np.flatnonzero(np.abs(X[:, 0]) < tol) * dim)
    fixed.append(np.flatnonzero(np.abs(X[:, 0] - geom.width_mm) < tol) * dim)
    if dim == 3:
        on_end = (np.abs(X[:, 2]) < tol) | (np.abs(X[:, 2] - geom.half_length_mm) < tol)
        fixed.append(np.flatnonzero(on_end) * dim + 2)
    covers = hx >= geom.width_mm - tol and (dim == 2 or hz >= geom.half_length_mm - tol)
    return Mesh(
        dim=dim, X=X, elements=conn_all[keep], layer=np.array(layer)[keep],
        ref=reference_element(dim, 3), fixed=np.unique(np.concatenate(fixed)),
        outer_faces=conn_all[outer_rows][:, face_hi],
        roof_faces=conn_all[roof_rows][:, face_lo].reshape(-1, npf),
        floor_faces=conn_all[floor_rows][:, face_hi].reshape(-1, npf),
        symmetry_factor=4.0 if dim == 3 else 2.0,
        length_mm=1.0 if dim == 3 else 2.0 * geom.half_length_mm, spec=spec,
        plate_half_mm=None if covers else (hx, hz),
    )
