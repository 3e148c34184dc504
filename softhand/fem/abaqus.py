"""Abaqus/Standard and CalculiX input decks of the 3D quarter indentation model of softhand.

A deck holds softhand's own mesh (same node and element numbers, plus one), materials and
loading, so that a run of the other solver can be compared with
`softhand.fem.solver.indent`. One core (mesh, C3D20 connectivity, node sets, sections,
materials, skin and pocket surfaces) feeds two dialects:

* ``"abaqus"`` (``fmt="inp"``): C3D20H bricks (hybrid, for nu = 0.47-0.49); the plate is an
  analytical rigid surface (TYPE=CYLINDER) on ``PLATE_RP``; frictionless hard contact; Table 3
  hyperfoam with MODULI as softhand reads them and Prony terms with k_i = g_i (the paper applies
  g(t) to the whole stress, and Abaqus requires equal shear and bulk relaxation for hyperfoam);
  *VISCO ramp and hold.
* ``"calculix"`` (``fmt="ccx"``, runs unmodified in CalculiX 2.20, ``ccx -i job``): C3D20
  bricks with full 27-point integration, like softhand's 3x3x3-point Q27 (C3D20R integrates
  8 points; 2.1 % softer at 0.5 mm on coarse solid-pu); the plate is a grid of C3D8 bricks tied to ``PLATE_RP`` by
  *RIGID BODY; frictionless face-to-face penalty contact with softhand's own linear law
  (pressure = ``penalty_N_mm3`` x overclosure); hyperfoam only with elastic *STATIC, because
  CalculiX has no Prony viscoelasticity for hyperfoam (it ignores *VISCOELASTIC there): the
  deck reproduces softhand's ``elastic_only=True`` run.

Nodes are written as they are (id = softhand index + 1). Each Lagrange Q27 hexahedron becomes a
20-node brick (the Q27 face and centre nodes stay as unconnected nodes); the C3D20 order is
derived from the element's natural coordinates (below), and each element takes the axis
assignment that gives its corner hexahedron a positive volume. The elements at the base centre
are collapsed bricks (one face collapsed to a line); both solvers accept them. Boundary: base
y = 0 fixed, x = 0 and z = 0 symmetry planes. The force on the whole phalanx is -4 x RF2 of
``PLATE_RP`` (RF2 < 0: the skin pushes the plate up).

Round indenters (``settings.indenter``, `softhand.fem.indenter`): Abaqus gets an analytical
rigid surface ``INDENTER`` on ``PLATE_RP``, a cylinder (TYPE=CYLINDER, the lower half circle swept
along the axis) or a sphere (TYPE=REVOLUTION, a quarter circle revolved about the vertical),
touching the top of the skin at travel 0. CalculiX gets a meshed rigid one
(`softhand.fem.calculix.indenter_grid`).

Plate travel: Abaqus/Standard cannot end a displacement-controlled step at a force, so the ramp
goes to a depth that is either given or softhand's own displacement at ``max_force_N`` for the
same model (`write_deck` runs `indent`); the hold keeps that depth, as softhand does.

Units: mm, N, s, MPa.
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal

import numpy as np

import softhand
from softhand.fem.geometry import Design, PhalanxGeometry, parse_design
from softhand.fem.indenter import Indenter, parse_indenter
from softhand.fem.materials import Material, material
from softhand.fem.mesh import Mesh, build_mesh
from softhand.fem.solver import IndentationSettings, Status, indent
from softhand.io import atomic_write_text

__all__ = ["C3D20_FACES", "C3D20_NATURAL", "DIALECTS", "ELEMENT_TYPES", "FORMATS", "DeckInfo",
           "c3d20_connectivity", "corner_volumes", "face_label", "inp_text", "write_deck"]

Dialect = Literal["abaqus", "calculix"]
DeckFormat = Literal["inp", "ccx"]
DIALECTS: tuple[str, ...] = ("abaqus", "calculix")
#: file format (CLI ``--format``) -> dialect
FORMATS: dict[str, str] = {"inp": "abaqus", "ccx": "calculix"}
ELEMENT_TYPES: dict[str, str] = {"abaqus": "C3D20H", "calculix": "C3D20"}
#: smallest |alpha_i| written. CalculiX's hyperfoam does not converge with sil's alpha_1 = 0.001
#: (nor 0.01; 0.03 does); in softhand 0.03 instead of 0.001 moves the coarse elastic solid-sil
#: F(0.5 mm) by -0.03 % and pocket2-sil d(2 N) by +0.02 %.
MIN_ALPHA: dict[str, float] = {"abaqus": 0.0, "calculix": 0.03}
PLATE_MARGIN_MM = 2.0  # the plate overhangs the quarter model by this much in x (and z)
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


def _comment(text: str) -> list[str]:
    """``**`` comment lines of at most 100 characters (CalculiX reads 132 per line)."""
    words, lines, line = text.split(), [], "**"
    for w in words:
        if len(line) + 1 + len(w) > 100:
            lines.append(line)
            line = "**"
        line += " " + w
    return [*lines, line]


@dataclass(frozen=True)
class DeckInfo:
    """What `write_deck` wrote.

    Attributes:
        path: the deck file.
        fmt: ``"inp"`` (Abaqus/Standard) or ``"ccx"`` (CalculiX).
        depth_mm: plate travel of the ramp step (mm, > 0).
        depth_source: ``"given"`` (``depth_mm=``) or ``"softhand"`` (softhand's displacement at
            ``max_force_N`` for the same model, or at ``max_depth_mm`` if it never got there).
    """

    path: Path
    fmt: str
    depth_mm: float
    depth_source: Literal["given", "softhand"]


@dataclass(frozen=True)
class _Core:
    """The dialect-independent model: mesh, C3D20 connectivity and the settings as used."""

    design: Design
    settings: IndentationSettings  # CalculiX: elastic_only=True
    geom: PhalanxGeometry
    mesh: Mesh
    conn: np.ndarray
    variant: np.ndarray

    @property
    def used(self) -> np.ndarray:
        return np.unique(self.conn)


def _prepare(design: str | Design, settings: IndentationSettings | None, dialect: str,
             depth_mm: float | None) -> tuple[_Core, float | None]:
    """Validate every input (no FE run, no file) and build the mesh core."""
    if isinstance(design, str):
        design = parse_design(design)
    elif not isinstance(design, Design):
        raise ValueError(f"design = {design!r}: allowed a design name or a Design")
    s = IndentationSettings() if settings is None else settings
    if not isinstance(s, IndentationSettings):
        raise ValueError(f"settings = {s!r}: allowed an IndentationSettings or None")
    if s.mode != "3d":
        raise ValueError(f"mode = {s.mode!r}: only the 3D quarter model ('3d') is exportable")
    if dialect not in DIALECTS:
        raise ValueError(f"dialect = {dialect!r}: allowed {', '.join(DIALECTS)}")
    if parse_indenter(s.indenter).full_model:
        raise ValueError(f"indenter = {s.indenter!r}: a cylinder at an angle other than 0 or 90 "
                         "deg runs on softhand's full model; the decks are the quarter model "
                         "(symmetry planes x = 0, z = 0): allowed angles 0 and 90")
    if dialect == "calculix":
        s = replace(s, elastic_only=True)
    geom = design.geometry(**s.geometry)
    depth = None
    if depth_mm is not None:
        try:
            depth = float(depth_mm)
        except (TypeError, ValueError):
            depth = float("nan")
        if not (np.isfinite(depth) and 0.0 < depth < geom.height_mm):
            raise ValueError(f"depth_mm = {depth_mm!r} is outside the allowed range "
                             f"(0, {geom.height_mm:g}) mm (finite, below the phalanx height)")
    mesh = build_mesh(geom, s.mesh_spec, dim=3)
    conn, variant = c3d20_connectivity(mesh)
    return _Core(design, s, geom, mesh, conn, variant), depth


def _travel(core: _Core, depth: float | None,
            progress: Callable[[float], None] | None) -> tuple[float, str, str]:
    """Plate travel, its source and the header sentence saying where it comes from."""
    if depth is not None:
        return depth, "given", f"plate travel {depth:.6g} mm: given"
    s = core.settings
    res = indent(core.design, replace(s, hold_s=0.0), progress=progress)
    d = float(res.displacement_mm[-1])
    if res.status is Status.REACHED_FORCE:
        note = f"plate travel {d:.6g} mm: softhand's d(F = {s.max_force_N:g} N) for this model"
    else:
        note = (f"plate travel {d:.6g} mm: softhand's max_depth_mm (F = {s.max_force_N:g} N not "
                f"reached: {float(res.force_N[-1]):.4g} N there)")
    return d, "softhand", note


def _material(name: str, s: IndentationSettings) -> Material:
    return material(name, moduli=s.moduli, elastic_only=s.elastic_only,
                    constants=s.materials.get(name))


def _raised_alphas(core: _Core, dialect: str) -> list[str]:
    """The materials whose exponents the dialect raises to MIN_ALPHA[dialect] in magnitude."""
    return [n for n in dict.fromkeys((core.design.inner, core.design.outer))
            if any(abs(a) < MIN_ALPHA[dialect] for a in _material(n, core.settings).hyperfoam.alpha)]


def _material_lines(name: str, s: IndentationSettings, min_alpha: float = 0.0) -> list[str]:
    """*MATERIAL block with the constants and moduli softhand uses for ``name``.

    Exponents below ``min_alpha`` in magnitude are written as +-``min_alpha``.
    """
    mat = _material(name, s)
    law, prony = mat.hyperfoam, mat.prony
    alpha = [a if abs(a) >= min_alpha else float(np.copysign(min_alpha, a)) for a in law.alpha]
    mu = law.mu  # instantaneous in softhand; back to the long-term values as given if so read
    head = f"*HYPERFOAM, N={len(mu)}"
    if prony is not None:
        if s.moduli == "long-term":
            mu = tuple(m * prony.g_inf for m in mu)
        head += ", MODULI=" + ("LONG TERM" if s.moduli == "long-term" else "INSTANTANEOUS")
    data = [_num(v) for pair in zip(mu, alpha, strict=True) for v in pair]
    data += [_num(law.nu)] * len(mu)
    lines = [f"*MATERIAL, NAME={name.upper()}", head, *_wrap(data, 8)]
    if prony is not None:
        lines.append("** g_i, k_i = g_i (hyperfoam: equal shear and bulk relaxation), tau_i (s)")
        lines.append("*VISCOELASTIC, TIME=PRONY")
        lines += [f"{_num(g)}, {_num(g)}, {_num(t)}"
                  for g, t in zip(prony.g, prony.tau_s, strict=True)]
    return lines


def _surface(name: str, elements: np.ndarray, label: np.ndarray | list[str]) -> list[str]:
    return [f"*SURFACE, TYPE=ELEMENT, NAME={name}",
            *(f"{e + 1}, {lab}" for e, lab in zip(elements, label, strict=True))]


def _header(core: _Core, dialect: str, note: str) -> list[str]:
    s, version = core.settings, getattr(softhand, "__version__", "0.1.0")
    solver = "Abaqus/Standard" if dialect == "abaqus" else "CalculiX 2.20 (run: ccx -i JOBNAME)"
    text = [f"{solver} deck.",
            "Quarter model: symmetry planes x = 0 and z = 0, base y = 0 fixed. Whole-phalanx "
            "force = -4 x RF2 of PLATE_RP. Node/element id = softhand index + 1.",
            f"mesh: {s.mesh}; moduli: {s.moduli}; elastic_only: {s.elastic_only}; speed: "
            f"{s.speed_mm_s:g} mm/s; hold: {s.hold_s:g} s; max_force_N: {s.max_force_N:g}.",
            "Q27 face/centre nodes are listed but unconnected (C3D20 uses 20 of the 27)."]
    if s.geometry:
        text.append("geometry overrides: " + ", ".join(f"{k} = {v:g}" for k, v in
                                                        sorted(s.geometry.items())) + ".")
    for name, constants in sorted(s.materials.items()):
        text.append(f"material constants of {name}: {constants}.")
    if dialect == "calculix":
        text.append("CalculiX has no Prony viscoelasticity for hyperfoam (it silently ignores "
                    "*VISCOELASTIC there): this deck is hyperfoam only, elastic *STATIC with the "
                    "moduli as written and no hold. It reproduces softhand's elastic_only=True "
                    "run, not the viscoelastic one.")
        for name in _raised_alphas(core, dialect):
            text.append(f"{name}: |alpha_i| < {MIN_ALPHA[dialect]:g} written as "
                        f"{MIN_ALPHA[dialect]:g} (CalculiX's hyperfoam does not converge with "
                        "alpha = 0.001; in softhand the change moves the forces by < 0.05 %).")
    ind = parse_indenter(s.indenter)
    if ind.kind != "plate":
        text.append(f"indenter: {ind.text} (radius {ind.radius_mm:g} mm"
                    + ("" if ind.angle_deg is None else
                       f", axis at {ind.angle_deg:g} deg from the phalanx axis z") + "), "
                    + ("" if dialect == "calculix" else "analytical ")
                    + "rigid surface INDENTER on PLATE_RP, touching the skin's top at travel 0"
                    + (" (CalculiX: a rigid mesh of C3D8 bricks)." if dialect == "calculix"
                       else "."))
    what = "plate" if ind.kind == "plate" else ind.text
    out = ["*HEADING",
           f"softhand {version}: {what} indentation of {core.design.name}; units mm, N, s, MPa",
           f"** {note}"]
    for t in text:
        out += _comment(t)
    return out


def _body(core: _Core, dialect: str) -> list[str]:
    """Nodes, skin elements, sets, sections, materials and surfaces: common to both dialects."""
    mesh, conn, used = core.mesh, core.conn, core.used
    Xu = mesh.X[used]
    out = ["*NODE, NSET=SKIN_NODES"]
    out += [f"{i + 1}, {_num(x)}, {_num(y)}, {_num(z)}" for i, (x, y, z) in enumerate(mesh.X)]
    out += ["*NODE, NSET=PLATE_RP", f"{mesh.X.shape[0] + 1}, 0., {_num(core.geom.height_mm)}, 0.",
            *_comment("Elements at the base centre are collapsed bricks (repeated node ids, one "
                      "face collapsed to a line, i.e. 15-node wedges); the solver accepts them."),
            f"*ELEMENT, TYPE={ELEMENT_TYPES[dialect]}, ELSET=SKIN"]
    for e, row in enumerate(conn):
        ids = [str(e + 1)] + [str(n + 1) for n in row]
        out += [", ".join(ids[:16]) + ",", ", ".join(ids[16:])]
    for set_name, lay in (("INNER", 0), ("OUTER", 1)):
        out += [f"*ELSET, ELSET={set_name}", *_ids(np.flatnonzero(mesh.layer == lay))]
    for set_name, axis in (("BASE", 1), ("XSYM", 0), ("ZSYM", 2)):
        out += [f"*NSET, NSET={set_name}", *_ids(used[np.abs(Xu[:, axis]) < _TOL])]
    d = core.design
    for set_name, mat in (("INNER", d.inner), ("OUTER", d.outer)):
        out += [f"*SOLID SECTION, ELSET={set_name}, MATERIAL={mat.upper()}", ","]
    for name in dict.fromkeys((d.inner, d.outer)):
        out += _material_lines(name, core.settings, MIN_ALPHA[dialect])
    # skin surface: xi0 = +1 faces of the outermost elements; pocket: roof underside, floor top
    labels = {v: (face_label(v, 0, 0), face_label(v, 0, 2)) for v in (0, 1)}
    outer_el = _face_elements(mesh, mesh.outer_faces, 2)
    out += _surface("SKIN", outer_el, [labels[v][1] for v in core.variant[outer_el]])
    if mesh.floor_faces.size:
        roof_el = _face_elements(mesh, mesh.roof_faces, 0)
        floor_el = _face_elements(mesh, mesh.floor_faces, 2)
        out += _surface("ROOF", roof_el, [labels[v][0] for v in core.variant[roof_el]])
        out += _surface("FLOOR", floor_el, [labels[v][1] for v in core.variant[floor_el]])
    return out


def _abaqus_step(name: str, proc: str, period: float, plate: float, *, first: bool) -> list[str]:
    inc = f"{_num(period / 100)}, {_num(period)}, {_num(period * 1e-6)}, {_num(period / 20)}"
    bc = "*BOUNDARY" if first else "*BOUNDARY, OP=MOD"
    return [f"*STEP, NAME={name}, NLGEOM=YES, INC=10000, AMPLITUDE=RAMP", proc, inc,
            bc, f"PLATE_RP, 2, 2, {_num(plate)}",
            "*OUTPUT, FIELD, VARIABLE=PRESELECT",
            "*OUTPUT, HISTORY, FREQUENCY=1", "*NODE OUTPUT, NSET=PLATE_RP", "RF2, U2",
            "*END STEP"]


def _abaqus_tail(core: _Core, depth: float) -> list[str]:
    """Analytical rigid plate, hard frictionless contact, boundary, *VISCO/*STATIC steps."""
    s, geom = core.settings, core.geom
    a, h = PLATE_MARGIN_MM, _num(geom.height_mm)
    out = [*_comment("Plate: profile in the local (x, y) plane swept along the generator (local "
                     "z = global Z); local x = global X, so local y = Z x X = global Y. The "
                     "segment runs towards -x; its normal (segment direction turned 90 deg "
                     "counterclockwise) is -Y, facing the skin. Covers x in [-margin, width/2 + "
                     "margin], all z."),
           "*SURFACE, TYPE=CYLINDER, NAME=PLATE",
           f"0., {h}, 0., 1., {h}, 0.", f"0., {h}, 1.",
           f"START, {_num(0.5 * geom.width_mm + a)}, 0.", f"LINE, {_num(-a)}, 0."]
    ind = parse_indenter(s.indenter)
    name = "PLATE"
    if ind.kind != "plate":
        out, name = _round_surface(ind, geom.height_mm), "INDENTER"
    out += [f"*RIGID BODY, ANALYTICAL SURFACE={name}, REF NODE=PLATE_RP",
            "*SURFACE INTERACTION, NAME=FRICTIONLESS", "*FRICTION", "0.",
            "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD",
            "*CONTACT PAIR, INTERACTION=FRICTIONLESS", f"SKIN, {name}"]
    if core.mesh.floor_faces.size:
        out += ["** Pocket closure: roof underside against floor.",
                "*CONTACT PAIR, INTERACTION=FRICTIONLESS", "ROOF, FLOOR"]
    out += ["*BOUNDARY", "BASE, ENCASTRE", "XSYM, XSYMM", "ZSYM, ZSYMM",
            "PLATE_RP, 1, 1", "PLATE_RP, 3, 6"]
    proc = "*STATIC" if s.elastic_only else f"*VISCO, CETOL={_num(CETOL)}"
    out += [f"** Ramp: plate down {_num(depth)} mm at {_num(s.speed_mm_s)} mm/s."]
    out += _abaqus_step("RAMP", proc, depth / s.speed_mm_s, -depth, first=True)
    if s.hold_s > 0 and not s.elastic_only:
        out += [f"** Hold: plate fixed at {_num(depth)} mm for {_num(s.hold_s)} s."]
        out += _abaqus_step("HOLD", proc, s.hold_s, -depth, first=False)
    return out


def _round_surface(ind: Indenter, height_mm: float) -> list[str]:
    """Analytical rigid cylinder or sphere of radius R whose lowest point is (0, height, 0).

    As for the plate, a segment's normal is its direction turned 90 deg counterclockwise in the
    profile plane: the arcs run clockwise, so the normal points out of the circle, at the skin.
    """
    R, c = _num(ind.radius_mm), _num(height_mm + ind.radius_mm)
    r = ind.radius_mm
    if ind.kind == "sphere":
        return [*_comment("Sphere: a quarter circle in the local (r, z) plane, z = global Y from "
                          "the centre, from the equator to the lowest point, revolved about Y."),
                "*SURFACE, TYPE=REVOLUTION, NAME=INDENTER",
                f"0., {c}, 0., 0., {_num(height_mm + r + 1.0)}, 0.",
                f"START, {R}, 0.", f"CIRCL, 0., {_num(-r)}, 0., 0."]
    if ind.angle_deg == 0.0:  # axis along z: local x = X, local y = Z x X = Y
        return [*_comment("Cylinder along the phalanx (axis global Z through the centre): the "
                          "lower half circle in the local (x, y) = (X, Y) plane, swept along Z."),
                "*SURFACE, TYPE=CYLINDER, NAME=INDENTER",
                f"0., {c}, 0., 1., {c}, 0.", f"0., {c}, 1.",
                f"START, {R}, 0.", f"CIRCL, 0., {_num(-r)}, 0., 0.",
                f"CIRCL, {_num(-r)}, 0., 0., 0."]
    # axis along x: local x = Z, local z = X, local y = X x Z = -Y
    return [*_comment("Cylinder across the phalanx (axis global X through the centre): the "
                      "lower half circle in the local (x, y) = (Z, -Y) plane, swept along X."),
            "*SURFACE, TYPE=CYLINDER, NAME=INDENTER",
            f"0., {c}, 0., 0., {c}, 1.", f"1., {c}, 0.",
            f"START, {_num(-r)}, 0.", f"CIRCL, 0., {R}, 0., 0.", f"CIRCL, {R}, 0., 0., 0."]


def _render(core: _Core, dialect: str, depth: float, note: str) -> str:
    if dialect == "abaqus":
        tail = _abaqus_tail
    else:  # imported here: softhand.fem.calculix builds on this module's core
        from softhand.fem.calculix import calculix_tail as tail
    lines = [*_header(core, dialect, note), *_body(core, dialect), *tail(core, depth)]
    return "\n".join(lines) + "\n"


def inp_text(design: str | Design, settings: IndentationSettings | None = None, *,
             depth_mm: float | None = None, dialect: Dialect = "abaqus",
             progress: Callable[[float], None] | None = None) -> str:
    """The deck of one design's 3D quarter indentation model.

    Args:
        design: a design name such as ``"pocket2-sil"`` or a `Design`.
        settings: run settings; ``mode`` must be ``"3d"``. Mesh, geometry overrides, material
            constants, moduli, elastic_only, speed, hold, max_force_N and penalty (CalculiX) are
            taken from it. CalculiX decks are always elastic (``elastic_only=True``).
        depth_mm: plate travel of the ramp, in (0, height). None: softhand's displacement at
            ``max_force_N`` for the same model (runs `indent` without hold).
        dialect: ``"abaqus"`` or ``"calculix"``.
        progress: passed to `indent` when it runs.

    Raises:
        ValueError: unknown design, 2D mode, bad geometry, depth or dialect (before any FE run).
        ConvergenceError: softhand's run for the plate travel failed.
    """
    core, depth = _prepare(design, settings, dialect, depth_mm)
    depth, _, note = _travel(core, depth, progress)
    return _render(core, dialect, depth, note)


def write_deck(design: str | Design, path: str | os.PathLike,
               settings: IndentationSettings | None = None, *, fmt: DeckFormat = "inp",
               depth_mm: float | None = None,
               progress: Callable[[float], None] | None = None) -> DeckInfo:
    """Write the Abaqus (``fmt="inp"``) or CalculiX (``fmt="ccx"``) deck atomically.

    Every input is validated and the mesh is built before softhand's run (when ``depth_mm`` is
    None) and before the file is opened: on error no file is written.

    Args:
        design, settings, depth_mm, progress: as `inp_text`.
        path: the deck file (its folder is created); not an existing folder.
        fmt: ``"inp"`` (Abaqus/Standard) or ``"ccx"`` (CalculiX 2.20).

    Returns:
        The path, format, plate travel and where the travel comes from.

    Raises:
        ValueError: bad fmt or path, or as `inp_text`.
        ConvergenceError: softhand's run for the plate travel failed.
    """
    if fmt not in FORMATS:
        raise ValueError(f"fmt = {fmt!r}: allowed {', '.join(FORMATS)}")
    target = Path(path)
    if target.is_dir():
        raise ValueError(f"path = {str(path)!r} is a folder: allowed a file path")
    core, depth = _prepare(design, settings, FORMATS[fmt], depth_mm)
    depth, source, note = _travel(core, depth, progress)
    atomic_write_text(target, _render(core, FORMATS[fmt], depth, note))
    return DeckInfo(target, fmt, depth, source)  # type: ignore[arg-type]
