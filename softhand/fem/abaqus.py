"""Abaqus/Standard input deck of the 3D quarter indentation model that softhand solves.

The deck holds softhand's own mesh (same node and element numbers, plus one), materials and
loading, so that an Abaqus run can be compared with :func:`softhand.fem.solver.indent`:

* Nodes are written as they are (Abaqus id = softhand index + 1). Each Lagrange Q27 hexahedron
  becomes a C3D20H brick (hybrid serendipity; the Q27 face and centre nodes stay as unconnected
  nodes). The C3D20 order is derived from the element's natural coordinates (below), and each
  element takes the axis assignment that gives its corner hexahedron a positive volume.
* Boundary: base y = 0 encastre, x = 0 XSYMM, z = 0 ZSYMM. The force on the whole phalanx is
  4 x RF2 of ``PLATE_RP``.
* The plate is an analytical rigid surface (TYPE=CYLINDER) at y = height; frictionless hard
  contact with the outer skin surface and, for pocket designs, between pocket roof and floor.
* Materials: Table 3 hyperfoam with MODULI as softhand reads them; Prony terms with k_i = g_i
  (the paper applies g(t) to the whole stress, and Abaqus requires equal shear and bulk
  relaxation data for hyperfoam).

Units: mm, N, s, MPa.
"""

from __future__ import annotations

import itertools
import os
from pathlib import Path

import numpy as np

import softhand
from softhand.fem.geometry import Design, parse_design
from softhand.fem.materials import material
from softhand.fem.mesh import Mesh, build_mesh
from softhand.fem.solver import IndentationSettings
from softhand.io import atomic_write_text

__all__ = ["C3D20_FACES", "C3D20_NATURAL", "DEFAULT_DEPTH_MM", "ELEMENT_TYPE",
           "c3d20_connectivity", "corner_volumes", "face_label", "inp_text", "write_inp"]

ELEMENT_TYPE = "C3D20H"
DEFAULT_DEPTH_MM = 3.0  # beyond the 2 N point of every design
PLATE_MARGIN_MM = 2.0  # the plate overhangs the quarter model by this much in x
CETOL = 2e-3  # *VISCO creep-strain tolerance (automatic incrementation), about 1% of the strains
_TOL = 1e-9

#: Natural coordinates (xi, eta, zeta) of C3D20 nodes 1..20: corners 1-4 (zeta = -1) and 5-8
#: (zeta = +1) counterclockwise about +zeta, midside nodes 9-12 and 13-16 on the edges 1-2, 2-3,
#: 3-4, 4-1 (then 5-6, ...), 17-20 on the edges 1-5, 2-6, 3-7, 4-8.
C3D20_NATURAL: tuple[tuple[int, int, int], ...] = (
    (-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1),
    (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1),
    (0, -1, -1), (1, 0, -1), (0, 1, -1), (-1, 0, -1),
    (0, -1, 1), (1, 0, 1), (0, 1, 1), (-1, 0, 1),
    (-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0),
)
#: Abaqus face labels of 3D bricks and their corner nodes (1-based).
C3D20_FACES: dict[str, tuple[int, int, int, int]] = {
    "S1": (1, 2, 3, 4), "S2": (5, 8, 7, 6), "S3": (1, 5, 6, 2),
    "S4": (2, 6, 7, 3), "S5": (3, 7, 8, 4), "S6": (4, 8, 5, 1),
}
# softhand local axis k <- Abaqus natural axis _AXES[v][k]; variant 1 swaps two axes (mirror)
_AXES = ((0, 1, 2), (1, 0, 2))


def _order(variant: int) -> np.ndarray:
    """Softhand Q27 local index (p0 + 3 p1 + 9 p2) of each C3D20 node for one axis variant."""
    axes = _AXES[variant]
    return np.array([sum((nat[axes[k]] + 1) * 3**k for k in range(3)) for nat in C3D20_NATURAL])


_ORDERS = (_order(0), _order(1))


def face_label(variant: int, axis: int, side: int) -> str:
    """Abaqus face label of the softhand element face ``p_axis == side``.

    Computed from the node orders, not assumed: the face whose four corners all lie on it.

    Args:
        variant: axis variant of the element (0: identity, 1: xi0 and xi1 swapped).
        axis: softhand local axis 0, 1 or 2.
        side: 0 for the face xi = -1, 2 for xi = +1.
    """
    for label, corners in C3D20_FACES.items():
        local = _ORDERS[variant][np.array(corners) - 1]
        if all((a // 3**axis) % 3 == side for a in local):
            return label
    raise ValueError(f"no C3D20 face at axis {axis}, side {side}")  # pragma: no cover


def corner_volumes(corners: np.ndarray) -> np.ndarray:
    """Signed volumes of trilinear hexahedra (n, 8, 3) in C3D20 corner order.

    Exact: det J of a trilinear map is quadratic per direction, integrated with 2x2x2 Gauss.
    """
    nat = np.array(C3D20_NATURAL[:8], dtype=float)
    g = 1.0 / np.sqrt(3.0)
    vol = np.zeros(corners.shape[0])
    for q in itertools.product((-g, g), repeat=3):
        f = 1.0 + nat * np.array(q)
        dN = np.stack([nat[:, j] / 8.0 * np.prod(np.delete(f, j, axis=1), axis=1)
                       for j in range(3)], axis=1)
        vol += np.linalg.det(np.einsum("nai,aj->nij", corners, dN))
    return vol


def c3d20_connectivity(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """C3D20 connectivity (0-based node indices, (n, 20)) and the axis variant of each element.

    Raises:
        ValueError: an element's corner hexahedron has (near) zero volume.
    """
    vol = corner_volumes(mesh.X[mesh.elements[:, _ORDERS[0][:8]]])
    bad = np.flatnonzero(np.abs(vol) <= 1e-12 * np.abs(vol).max())
    if bad.size:
        raise ValueError(f"elements {(bad + 1).tolist()} have a zero-volume corner hexahedron")
    variant = (vol < 0).astype(int)  # swapping two axes flips the sign
    conn = np.where(variant[:, None] == 1, mesh.elements[:, _ORDERS[1]],
                    mesh.elements[:, _ORDERS[0]])
    return conn, variant


def _face_elements(mesh: Mesh, faces: np.ndarray, side: int) -> np.ndarray:
    """Indices of the elements whose xi0 face on ``side`` (0 or 2) has the given node rows."""
    local = [a for a in range(27) if a % 3 == side]
    lookup = {}
    for e, row in enumerate(mesh.elements[:, local]):
        if len(set(row.tolist())) == len(local):  # skip collapsed faces
            lookup[tuple(sorted(row.tolist()))] = e
    out = []
    for row in faces:
        key = tuple(sorted(row.tolist()))
        if key not in lookup:
            raise ValueError(f"face {row.tolist()} matches no element face")
        out.append(lookup[key])
    return np.array(out, dtype=int)


def _num(v: float) -> str:
    s = f"{float(v):.12g}"
    return s if any(c in s for c in ".eEn") else s + "."


def _wrap(items: list[str], per_line: int) -> list[str]:
    return [", ".join(items[i:i + per_line]) for i in range(0, len(items), per_line)]


def _ids(ids: np.ndarray) -> list[str]:
    return _wrap([str(int(i) + 1) for i in ids], 16)


def _material_lines(name: str, s: IndentationSettings) -> list[str]:
    """*MATERIAL block with the moduli softhand uses for ``name``."""
    mat = material(name, moduli=s.moduli, elastic_only=s.elastic_only)
    law, prony = mat.hyperfoam, mat.prony
    mu = law.mu  # instantaneous in softhand; back to Table 3's long-term values if so read
    head = f"*HYPERFOAM, N={len(mu)}"
    if prony is not None:
        if s.moduli == "long-term":
            mu = tuple(m * prony.long_term_ratio for m in mu)
        head += ", MODULI=" + ("LONG TERM" if s.moduli == "long-term" else "INSTANTANEOUS")
    data = [_num(v) for pair in zip(mu, law.alpha, strict=True) for v in pair]
    data += [_num(law.nu)] * len(mu)
    lines = [f"*MATERIAL, NAME={name.upper()}", head, *_wrap(data, 8)]
    if prony is not None:
        lines.append("** g_i, k_i = g_i (hyperfoam: equal shear and bulk relaxation), tau_i (s)")
        lines.append("*VISCOELASTIC, TIME=PRONY")
        lines += [f"{_num(g)}, {_num(g)}, {_num(t)}"
                  for g, t in zip(prony.g, prony.tau, strict=True)]
    return lines


def _surface(name: str, elements: np.ndarray, label: np.ndarray) -> list[str]:
    return [f"*SURFACE, TYPE=ELEMENT, NAME={name}",
            *(f"{e + 1}, {lab}" for e, lab in zip(elements, label, strict=True))]


def _step(name: str, proc: str, period: float, plate: float, *, first: bool) -> list[str]:
    inc = f"{_num(period / 100)}, {_num(period)}, {_num(period * 1e-6)}, {_num(period / 20)}"
    bc = "*BOUNDARY" if first else "*BOUNDARY, OP=MOD"
    return [f"*STEP, NAME={name}, NLGEOM=YES, INC=10000, AMPLITUDE=RAMP", proc, inc,
            bc, f"PLATE_RP, 2, 2, {_num(plate)}",
            "*OUTPUT, FIELD, VARIABLE=PRESELECT",
            "*OUTPUT, HISTORY, FREQUENCY=1", "*NODE OUTPUT, NSET=PLATE_RP", "RF2, U2",
            "*END STEP"]


def inp_text(design: str | Design, settings: IndentationSettings | None = None, *,
             depth_mm: float | None = None) -> str:
    """The Abaqus/Standard deck of one design's 3D quarter indentation model.

    Args:
        design: a design name such as ``"pocket2-sil"`` or a :class:`Design`.
        settings: run settings; ``mode`` must be ``"3d"``. Mesh, moduli, elastic_only, speed,
            hold and geometry overrides are taken from it.
        depth_mm: plate travel of the ramp step (default :data:`DEFAULT_DEPTH_MM`), > 0.

    Raises:
        ValueError: unknown design, 2D mode, or a depth that is not finite and > 0.
    """
    design = parse_design(design) if isinstance(design, str) else design
    s = settings or IndentationSettings()
    if s.mode != "3d":
        raise ValueError(f"mode = {s.mode!r}: the Abaqus export needs the 3D model ('3d')")
    try:
        depth = float(DEFAULT_DEPTH_MM if depth_mm is None else depth_mm)
    except (TypeError, ValueError):
        depth = float("nan")
    if not (np.isfinite(depth) and depth > 0):
        raise ValueError(f"depth_mm = {depth_mm!r} must be finite and > 0")
    geom = design.geometry(**s.geometry)
    mesh = build_mesh(geom, s.mesh_spec, dim=3)
    conn, variant = c3d20_connectivity(mesh)
    used = np.unique(conn)
    Xu = mesh.X[used]
    rp = mesh.X.shape[0]  # 0-based index of the plate reference node
    version = getattr(softhand, "__version__", "0.1.0")
    t_ramp = depth / s.speed_mm_s

    out = ["*HEADING",
           f"softhand {version}: plate indentation of {design.name}; units mm, N, s, MPa",
           "** Quarter model: symmetry planes x = 0 (XSYMM) and z = 0 (ZSYMM), base y = 0 "
           "encastre.",
           "** Whole-phalanx force = 4 x RF2 of PLATE_RP. Abaqus node/element id = softhand "
           "index + 1.",
           f"** mesh: {s.mesh}; moduli: {s.moduli}; elastic_only: {s.elastic_only}",
           "** Q27 face/centre nodes are listed but unconnected (C3D20 uses 20 of the 27).",
           "*NODE, NSET=SKIN_NODES"]
    out += [f"{i + 1}, {_num(x)}, {_num(y)}, {_num(z)}" for i, (x, y, z) in enumerate(mesh.X)]
    out += ["*NODE, NSET=PLATE_RP", f"{rp + 1}, 0., {_num(geom.height_mm)}, 0.",
            "** Elements at the base centre are collapsed bricks (repeated node ids, one face",
            "** collapsed to a line, i.e. 15-node wedges); Abaqus accepts collapsed C3D20 bricks.",
            f"*ELEMENT, TYPE={ELEMENT_TYPE}, ELSET=SKIN"]
    for e, row in enumerate(conn):
        ids = [str(e + 1)] + [str(n + 1) for n in row]
        out += [", ".join(ids[:16]) + ",", ", ".join(ids[16:])]
    for set_name, lay in (("INNER", 0), ("OUTER", 1)):
        out += [f"*ELSET, ELSET={set_name}", *_ids(np.flatnonzero(mesh.layer == lay))]
    for set_name, axis in (("BASE", 1), ("XSYM", 0), ("ZSYM", 2)):
        out += [f"*NSET, NSET={set_name}", *_ids(used[np.abs(Xu[:, axis]) < _TOL])]
    for set_name, mat in (("INNER", design.inner), ("OUTER", design.outer)):
        out += [f"*SOLID SECTION, ELSET={set_name}, MATERIAL={mat.upper()}", ","]
    for name in dict.fromkeys((design.inner, design.outer)):
        out += _material_lines(name, s)

    # skin surface: xi0 = +1 faces of the outermost elements
    outer_el = _face_elements(mesh, mesh.outer_faces, 2)
    labels = {v: (face_label(v, 0, 0), face_label(v, 0, 2)) for v in (0, 1)}
    out += _surface("SKIN", outer_el, np.array([labels[v][1] for v in variant[outer_el]]))
    a = PLATE_MARGIN_MM
    h = _num(geom.height_mm)
    out += ["** Plate: profile in the local (x, y) plane swept along the generator (local z =",
            "** global Z); local x = global X, so local y = Z x X = global Y. The segment runs",
            "** towards -x; its normal (segment direction turned 90 deg counterclockwise) is",
            "** -Y, facing the skin. Covers x in [-margin, width/2 + margin], all z.",
            "*SURFACE, TYPE=CYLINDER, NAME=PLATE",
            f"0., {h}, 0., 1., {h}, 0.", f"0., {h}, 1.",
            f"START, {_num(0.5 * geom.width_mm + a)}, 0.", f"LINE, {_num(-a)}, 0.",
            "*RIGID BODY, ANALYTICAL SURFACE=PLATE, REF NODE=PLATE_RP",
            "*SURFACE INTERACTION, NAME=FRICTIONLESS", "*FRICTION", "0.",
            "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD",
            "*CONTACT PAIR, INTERACTION=FRICTIONLESS", "SKIN, PLATE"]
    if mesh.floor_faces.size:
        roof_el = _face_elements(mesh, mesh.roof_faces, 0)
        floor_el = _face_elements(mesh, mesh.floor_faces, 2)
        out += _surface("ROOF", roof_el, np.array([labels[v][0] for v in variant[roof_el]]))
        out += _surface("FLOOR", floor_el, np.array([labels[v][1] for v in variant[floor_el]]))
        out += ["** Pocket closure: roof underside against floor.",
                "*CONTACT PAIR, INTERACTION=FRICTIONLESS", "ROOF, FLOOR"]
    out += ["*BOUNDARY", "BASE, ENCASTRE", "XSYM, XSYMM", "ZSYM, ZSYMM",
            "PLATE_RP, 1, 1", "PLATE_RP, 3, 6"]
    proc = "*STATIC" if s.elastic_only else f"*VISCO, CETOL={_num(CETOL)}"
    out += [f"** Ramp: plate down {_num(depth)} mm at {_num(s.speed_mm_s)} mm/s."]
    out += _step("RAMP", proc, t_ramp, -depth, first=True)
    if s.hold_s > 0 and not s.elastic_only:
        out += [f"** Hold: plate fixed for {_num(s.hold_s)} s."]
        out += _step("HOLD", proc, s.hold_s, -depth, first=False)
    return "\n".join(out) + "\n"


def write_inp(design: str | Design, path: str | os.PathLike,
              settings: IndentationSettings | None = None, *,
              depth_mm: float | None = None) -> Path:
    """Write the Abaqus deck of :func:`inp_text` to ``path`` atomically and return the path.

    Everything is validated and built before the file is opened: on error no file is written.

    Raises:
        ValueError: as :func:`inp_text`.
    """
    text = inp_text(design, settings, depth_mm=depth_mm)
    target = Path(path)
    atomic_write_text(target, text)
    return target
