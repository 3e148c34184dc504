"""Structured quadratic meshes of a phalanx: 2D half cross-section or 3D quarter.

The cross-section is mapped from a (level, theta) grid. Levels run from the base centre outward:
first a core filled by scaling the deepest offset curve towards the base centre, then bands of
constant normal depth under the outer profile (floor, pocket, roof, outer layer), so that the
outer layer and the pocket have exactly their thickness everywhere. The 3D mesh extrudes the
half section over half the length. Symmetry: x = 0 (both) and z = 0 (3D); the base y = 0 is fixed.

Element counts per band are set by `MeshSpec`; ``fine`` doubles every count of ``default``.
``default`` is graded towards the pocket ends: once closed, the pocket is a crack-like slit whose
tips make uniform refinement (``uniform``) converge only about linearly.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from softhand.fem.elements import ReferenceElement, reference_element
from softhand.fem.geometry import (
    PLATE_LENGTH_MM,
    PLATE_WIDTH_MM,
    PhalanxGeometry,
    check_section_length,
)

__all__ = ["MESH_LEVELS", "Mesh", "MeshSpec", "build_mesh", "face_element", "full_model"]


@dataclass(frozen=True)
class MeshSpec:
    """Element counts of the structured mesh (quadratic elements).

    Attributes:
        n_side: elements along the profile from the base to the pocket edge.
        n_top: elements from the pocket edge to the top centre (the contact zone).
        n_outer, n_roof, n_pocket, n_floor, n_core: elements through each band, outside in.
        n_length: elements along the half length (3D only).
        top_grading: size ratio of the first (pocket edge) to the last (top centre) element
            along ``n_top``; < 1 refines towards the pocket edge.
        side_grading: size ratio of the first (base) to the last (pocket edge) element along
            ``n_side``; > 1 refines towards the pocket edge.
        top_cosine: cosine spacing along ``n_top`` (small elements at the pocket edge and at the
            top centre, where the plate contact starts); replaces ``top_grading``.
    """

    n_side: int = 2
    n_top: int = 5
    n_outer: int = 1
    n_roof: int = 1
    n_pocket: int = 1
    n_floor: int = 1
    n_core: int = 2
    n_length: int = 3
    top_grading: float = 1.0
    side_grading: float = 1.0
    top_cosine: bool = False

    def __post_init__(self) -> None:
        for name in ("n_side", "n_top", "n_outer", "n_roof", "n_pocket", "n_floor", "n_core",
                     "n_length"):
            v = getattr(self, name)
            if not isinstance(v, int | np.integer) or v < 1:
                raise ValueError(f"{name} = {v!r} must be an integer >= 1")

    def refined(self, factor: int = 2) -> MeshSpec:
        """Every element count multiplied by ``factor``."""
        return MeshSpec(*(getattr(self, n) * factor for n in (
            "n_side", "n_top", "n_outer", "n_roof", "n_pocket", "n_floor", "n_core",
            "n_length")), top_grading=self.top_grading, side_grading=self.side_grading,
            top_cosine=self.top_cosine)


MESH_LEVELS: dict[str, MeshSpec] = {
    "coarse": MeshSpec(n_side=1, n_top=3, n_core=1, n_floor=1, n_length=2),
    # graded towards the pocket ends, where the closed pocket behaves like a crack tip, and towards
    # the top centre, where the plate contact starts; two elements through the pocket band and
    # through the roof (the roof bends over the pocket: one quadratic element through it is too
    # stiff, 2D pocket2-sil -0.9 % against 4x refinement vs -1.3 % with one); two along the half
    # length, where the indentation hardly varies (3D pocket2-sil: 0.06 % against three)
    "default": MeshSpec(n_side=4, n_top=7, n_roof=2, n_pocket=2, n_floor=2, n_length=2,
                        top_cosine=True, side_grading=5.0),
    # the uniform mesh of softhand <= 0.1.0 runs (1.7 % from its refinement for pocket2-sil)
    "uniform": MeshSpec(),
}
MESH_LEVELS["fine"] = MESH_LEVELS["default"].refined(2)


@dataclass
class Mesh:
    """A quadratic Lagrange mesh with its boundary sets.

    Attributes:
        dim: 2 (plane strain, per unit length) or 3.
        X: reference node coordinates (n_nodes, dim), mm.
        elements: node indices (n_elements, 3**dim).
        layer: 0 for the inner part, 1 for the outer layer, per element.
        ref: reference element with its Gauss rule.
        fixed: DOF indices held at zero (base and symmetry planes).
        outer_faces: node indices of the faces on the outer surface (n, 3**(dim-1)).
        roof_faces, floor_faces: facing pocket surfaces, paired row by row.
        wall_faces: the pocket's side wall (the faces of the pocket band's solid side facing
            the void), None where the mesh does not record it; `softhand.fem.contact.
            PocketContact` presses it on the roof with the floor.
        symmetry_factor: multiplier from the modelled part to the whole phalanx force.
        length_mm: length the 2D force per unit length is multiplied by.
        spec: the element counts it was built from (`MeshSpec` for the phalanx; the palm's
            `softhand.fem.palm.PalmMeshSpec`).
        plate_half_mm: half sizes (across x, along z) of the plate's face, centred over x = z = 0,
            where the plate is smaller than the body: `softhand.fem.contact.plate_gaps`
            then presses only the outer-surface points under it (2D: ``|x| <= `` the first).
            None: the plate covers the whole modelled surface (the phalanx, 16 x 10 mm under
            the paper's 20 x 10 mm plate).
    """

    dim: int
    X: np.ndarray
    elements: np.ndarray
    layer: np.ndarray
    ref: ReferenceElement
    fixed: np.ndarray
    outer_faces: np.ndarray
    roof_faces: np.ndarray
    floor_faces: np.ndarray
    symmetry_factor: float
    length_mm: float
    spec: object = field(default_factory=MeshSpec)
    plate_half_mm: tuple[float, float] | None = None
    wall_faces: np.ndarray | None = None

    @property
    def n_dofs(self) -> int:
        return self.X.shape[0] * self.dim

    @property
    def n_elements(self) -> int:
        return self.elements.shape[0]


def face_element(dim: int, n_gauss: int) -> ReferenceElement:
    """Reference element of a face (dimension dim - 1) with its own Gauss rule."""
    return reference_element(dim - 1, n_gauss)


def _graded(n: int, ratio: float) -> np.ndarray:
    """n + 1 points on [0, 1] whose first/last spacing ratio is ``ratio``."""
    if n == 1 or ratio == 1.0:
        return np.linspace(0.0, 1.0, n + 1)
    q = ratio ** (-1.0 / (n - 1))
    steps = q ** np.arange(n)
    return np.concatenate([[0.0], np.cumsum(steps) / steps.sum()])


def _with_midpoints(edges: np.ndarray) -> np.ndarray:
    """Element edges (n+1) to the 2n+1 node lines of a quadratic mesh."""
    out = np.empty(2 * len(edges) - 1)
    out[0::2] = edges
    out[1::2] = 0.5 * (edges[:-1] + edges[1:])
    return out


def _level_lines(geom: PhalanxGeometry, spec: MeshSpec):
    """Node lines through the depth: ('core', s) or ('depth', d), with band ids per element."""
    roof = geom.pocket_roof_mm
    pocket = geom.pocket_height_mm if geom.has_pocket else 2.0
    deep = geom.band_depth_mm
    bands = [  # name, depth from, depth to (inward = larger depth), elements; inside out
        ("floor", deep, roof + pocket, spec.n_floor),
        ("pocket", roof + pocket, roof, spec.n_pocket),
        ("roof", roof, geom.outer_layer_mm, spec.n_roof),
        ("outer", geom.outer_layer_mm, 0.0, spec.n_outer),
    ]
    kinds, values, band_of_element = [], [], []
    s = _with_midpoints(np.linspace(0.0, 1.0, spec.n_core + 1))
    kinds += ["core"] * len(s)
    values += list(s)
    band_of_element += ["core"] * spec.n_core
    for name, d0, d1, n in bands:
        d = _with_midpoints(np.linspace(d0, d1, n + 1))[1:]
        kinds += ["depth"] * len(d)
        values += list(d)
        band_of_element += [name] * n
    return kinds, np.array(values), band_of_element


def _section(geom: PhalanxGeometry, spec: MeshSpec):
    """Node coordinates of the half section on the (level, theta) grid and element bands."""
    th_p = geom.pocket_edge_theta()
    side = th_p * _graded(spec.n_side, spec.side_grading)
    if spec.top_cosine:
        frac = 0.5 * (1.0 - np.cos(np.pi * np.arange(spec.n_top + 1) / spec.n_top))
    else:
        frac = _graded(spec.n_top, spec.top_grading)
    top = th_p + (0.5 * np.pi - th_p) * frac
    theta = _with_midpoints(np.concatenate([side, top[1:]]))
    kinds, values, bands = _level_lines(geom, spec)
    deep = geom.offset(theta, geom.band_depth_mm)
    grid = np.empty((len(values), len(theta), 2))
    for k, (kind, v) in enumerate(zip(kinds, values, strict=True)):
        grid[k] = v * deep if kind == "core" else geom.offset(theta, v)
    grid[:, 0, 1] = 0.0  # theta = 0 line lies on the base exactly
    grid[:, -1, 0] = 0.0  # theta = pi/2 line lies on the symmetry plane exactly
    return grid, bands, spec.n_side


def build_mesh(geom: PhalanxGeometry, spec: MeshSpec, dim: int = 3) -> Mesh:
    """Build the structured quadratic mesh of one phalanx design geometry.

    Args:
        geom: phalanx dimensions and pocket.
        spec: element counts.
        dim: 3 for the quarter model, 2 for the plane-strain half cross-section.
    """
    if dim not in (2, 3):
        raise ValueError(f"dim = {dim!r}: allowed 2 (plane strain) or 3")
    grid, bands, n_side = _section(geom, spec)
    nk, ni = grid.shape[:2]
    ek, ei = (nk - 1) // 2, (ni - 1) // 2
    if dim == 3:
        edges = _length_edges(0.5 * geom.length_mm, spec.n_length)
        z = _with_midpoints(edges)
        ez = len(edges) - 1
    else:
        check_section_length(geom.length_mm, "2d")
        z = np.zeros(1)
        ez = 1
    nz = len(z)
    # global grid index -> node id, collapsing the base centre (core s = 0) per z line
    gid = np.arange(nk * ni * nz).reshape(nk, ni, nz)
    gid[0] = gid[0, :1]
    coords = np.empty((nk, ni, nz, dim))
    coords[..., 0] = grid[:, :, None, 0]
    coords[..., 1] = grid[:, :, None, 1]
    if dim == 3:
        coords[..., 2] = z[None, None, :]

    local = [(p0, p1, p2) for p2 in range(3 if dim == 3 else 1) for p1 in range(3)
             for p0 in range(3)]
    elems, layer, void = [], [], []
    roof_rows, floor_rows, outer_rows, wall_rows = [], [], [], []
    for kz in range(ez):
        for ki in range(ei):
            for kk in range(ek):
                idx = [gid[2 * kk + p0, 2 * ki + p1, (2 * kz + p2) if dim == 3 else 0]
                       for (p0, p1, p2) in local]
                band = bands[kk]
                in_pocket = geom.has_pocket and band == "pocket" and ki >= n_side
                void.append(in_pocket)
                elems.append(idx)
                layer.append(1 if band == "outer" else 0)
                e = len(elems) - 1
                if kk == ek - 1:
                    outer_rows.append(e)
                if geom.has_pocket and band == "pocket" and ki == n_side - 1:
                    wall_rows.append(e)
                if geom.has_pocket and ki >= n_side:
                    if band == "roof" and kk > 0 and bands[kk - 1] == "pocket":
                        roof_rows.append(e)
                    if band == "floor" and kk + 1 < ek and bands[kk + 1] == "pocket":
                        floor_rows.append(e)
    elems = np.array(elems)
    keep = ~np.array(void)
    X, conn_all, _ = compact_nodes(coords.reshape(-1, dim), elems, keep)

    npf = 3 ** (dim - 1)
    face_hi = [a for a, p in enumerate(local) if p[0] == 2]  # xi0 = +1
    face_lo = [a for a, p in enumerate(local) if p[0] == 0]  # xi0 = -1
    outer_faces = conn_all[outer_rows][:, face_hi]
    roof_faces = conn_all[roof_rows][:, face_lo].reshape(-1, npf)
    floor_faces = conn_all[floor_rows][:, face_hi].reshape(-1, npf)
    face_side = [a for a, p in enumerate(local) if p[1] == 2]  # xi1 = +1: towards the void
    wall_faces = conn_all[wall_rows][:, face_side].reshape(-1, npf)
    conn = conn_all[keep]
    layer = np.array(layer)[keep]

    tol = 1e-9
    fixed_nodes_y0 = np.flatnonzero(np.abs(X[:, 1]) < tol)
    fixed = [fixed_nodes_y0 * dim + c for c in range(dim)]
    fixed.append(np.flatnonzero(np.abs(X[:, 0]) < tol) * dim + 0)
    if dim == 3:
        fixed.append(np.flatnonzero(np.abs(X[:, 2]) < tol) * dim + 2)
    fixed = np.unique(np.concatenate(fixed))

    ref = reference_element(dim, 3)
    return Mesh(
        dim=dim, X=X, elements=conn, layer=layer, ref=ref, fixed=fixed,
        outer_faces=outer_faces, roof_faces=roof_faces, floor_faces=floor_faces,
        wall_faces=wall_faces,
        symmetry_factor=2.0 if dim == 2 else 4.0,
        length_mm=geom.length_mm if dim == 2 else 1.0, spec=spec,
        plate_half_mm=(0.5 * PLATE_WIDTH_MM, 0.5 * PLATE_LENGTH_MM)
        if geom.length_mm > PLATE_LENGTH_MM else None,
    )


#: Growth of the elements along a part longer than the plate, beyond its central PLATE_LENGTH_MM
LENGTH_GROWTH = 1.5


def _length_edges(half_mm: float, n: int) -> np.ndarray:
    """Element edges along the half length: ``n`` equal elements, as on the paper's 10 mm
    phalanx; on a longer part, ``n`` equal elements over the central half plate length (a mesh
    line where a plate's face ends), then elements growing by `LENGTH_GROWTH` to the end (the
    last ones scaled to land on it)."""
    core = 0.5 * PLATE_LENGTH_MM
    if half_mm <= core + 1e-9:
        return np.linspace(0.0, half_mm, n + 1)
    h = core / n
    steps: list[float] = []
    while core + sum(steps) < half_mm - 1e-9:
        steps.append(h * LENGTH_GROWTH ** (len(steps) + 1))
    # scale the growing elements so that they end at the part's end (a last one under half its
    # predecessor's planned size is merged into it)
    if len(steps) > 1 and core + sum(steps[:-1]) + 0.5 * steps[-1] >= half_mm:
        steps.pop()
    tail = np.cumsum(steps) * (half_mm - core) / sum(steps)
    return np.concatenate([np.linspace(0.0, core, n + 1), core + tail])


def compact_nodes(coords: np.ndarray, elems: np.ndarray, keep: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Renumber a structured grid to the nodes the kept elements use: their coordinates, every
    element's connectivity in the new numbering, and the new number of each old node (-1 for a
    node no kept element uses)."""
    used = np.unique(elems[keep])
    new_id = -np.ones(coords.shape[0], dtype=np.int64)
    new_id[used] = np.arange(len(used))
    return coords[used], new_id[elems], new_id


def full_model(mesh: Mesh) -> Mesh:
    """The whole 3D phalanx from its quarter mesh: mirrored across x = 0 and z = 0.

    For loads without the quarter's symmetry (a cylinder crossing the phalanx at an angle other
    than 0 or 90 deg). Nodes on the symmetry planes are shared; an element mirrored once has its
    local xi2 axis reversed so that it stays right-handed; faces keep their pairing (roof row k
    against floor row k). Only the base y = 0 is fixed; ``symmetry_factor`` is 1.
    """
    if mesh.dim != 3:
        raise ValueError(f"mesh.dim = {mesh.dim!r}: the full model mirrors a 3D quarter mesh")
    tol = 1e-9
    on_x = np.abs(mesh.X[:, 0]) < tol
    on_z = np.abs(mesh.X[:, 2]) < tol
    n = mesh.X.shape[0]
    copies = [(1, 1), (-1, 1), (1, -1), (-1, -1)]
    keys, maps = {}, []
    for sx, sz in copies:
        ex = np.where(on_x, 1, sx)
        ez = np.where(on_z, 1, sz)
        ids = np.empty(n, dtype=np.int64)
        for a in range(n):
            ids[a] = keys.setdefault((a, int(ex[a]), int(ez[a])), len(keys))
        maps.append(ids)
    X = np.empty((len(keys), 3))
    for (a, sx, sz), i in keys.items():
        X[i] = mesh.X[a] * (sx, 1.0, sz)
    flip = np.arange(27).reshape(3, 3, 3)[::-1].ravel()  # reverse xi2 (the slowest index)
    elements, faces = [], {"outer": [], "roof": [], "floor": []}
    for (sx, sz), ids in zip(copies, maps, strict=True):
        conn = ids[mesh.elements]
        elements.append(conn[:, flip] if sx * sz < 0 else conn)
        for name in faces:
            faces[name].append(ids[getattr(mesh, f"{name}_faces")])
    fixed = np.flatnonzero(np.abs(X[:, 1]) < tol)
    return Mesh(
        dim=3, X=X, elements=np.concatenate(elements), layer=np.tile(mesh.layer, 4),
        ref=mesh.ref, fixed=np.unique(np.concatenate([fixed * 3 + c for c in range(3)])),
        outer_faces=np.concatenate(faces["outer"]), roof_faces=np.concatenate(faces["roof"]),
        floor_faces=np.concatenate(faces["floor"]), symmetry_factor=1.0, length_mm=1.0,
        spec=mesh.spec, plate_half_mm=mesh.plate_half_mm,
    )
