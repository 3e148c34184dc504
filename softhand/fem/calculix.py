"""CalculiX 2.20 dialect of the indentation deck, and the reader of its ``.dat`` output.

`softhand.fem.abaqus.write_deck` with ``fmt="ccx"`` writes the deck: the common core of
`softhand.fem.abaqus` (nodes, C3D20 bricks, sets, hyperfoam, skin and pocket surfaces)
followed by `calculix_tail`. What differs from the Abaqus deck and why:

* C3D20 (27-point integration, like softhand's 3x3x3-point Q27; CalculiX has no hybrid C3D20H).
  Coarse solid-pu, 0.015 mm increments, force against softhand at 0.25 / 0.5 mm: C3D20
  +1.2 / -0.6 %, C3D20R (8 points) +0.2 / -2.1 %; C3D20 at the 0.01 mm default: +0.7 / -0.7 %.
* No analytical rigid surface in CalculiX: the plate is a grid of C3D8 bricks whose nodes are
  tied to ``PLATE_RP`` (translation) and ``PLATE_ROT`` (rotation, held) by *RIGID BODY.
  A cylinder or sphere (``settings.indenter``) is a curved grid of such bricks, 1 mm (at most
  R/2) thick towards its axis or centre, whose faces facing the skin have their corners on the
  round surface. Faces span at most ``ROUND_ELEMENT_MM`` of arc (a sphere's cube map up to 4 %
  more off its central lines): chord sag (0.25 mm)^2 / 8R = 1.1e-3 mm at R = 7.4 mm. The grid
  spans the plate's area (the quarter model plus 2 mm), at most 80 deg of arc from the lowest
  line (a sphere: 55 deg each way from the lowest point).
* Frictionless face-to-face contact (``TYPE=SURFACE TO SURFACE``, no *FRICTION card) with
  ``PRESSURE-OVERCLOSURE=LINEAR`` at softhand's penalty: the same contact law as softhand.
* Boundary conditions by DOF numbers (no ENCASTRE/XSYMM/ZSYMM); load by the reference node.
* Hyperfoam only, *STATIC: CalculiX ignores *VISCOELASTIC for hyperfoam, so the deck is
  softhand's ``elastic_only=True`` model.
* |alpha_i| below ``MIN_ALPHA["calculix"]`` (0.03) is written as 0.03: CalculiX's hyperfoam
  does not converge with sil's alpha_1 = 0.001; in softhand the change is < 0.05 % in force.
* *CONTROLS: the residual test uses a fixed reference force (softhand's ``tol_N``) instead of
  the running average force, which is tiny at first contact (pocket2-sil: no convergence
  otherwise).
* ``*NODE PRINT`` of U and RF of ``PLATE_RP`` puts the force history into ``JOBNAME.dat``
  (`read_ccx_dat`).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from softhand.fem.abaqus import PLATE_MARGIN_MM, _comment, _Core, _num, _surface
from softhand.fem.indenter import Indenter, parse_indenter

__all__ = ["CCX_STEP_MM", "PLATE_GRID", "ROUND_ELEMENT_MM", "calculix_tail", "indenter_grid",
           "read_ccx_dat"]

PLATE_GRID = (4, 3)  # plate: C3D8 bricks across x and along z, 1 mm thick
ROUND_ELEMENT_MM = 0.25  # largest brick face along a round indenter's arc
#: largest (and first) increment in plate travel (mm). CalculiX freezes the face-to-face contact
#: match within an increment, which stiffens the response by about the increment: coarse solid-pu
#: F(0.25 mm) is 1.8 / 1.2 / 0.7 % above softhand's with 0.029 / 0.015 / 0.0075 mm increments
#: (-> +0.35 % extrapolated to zero).
CCX_STEP_MM = 0.01
R_N = 0.005  # CalculiX's default residual ratio R_n (*CONTROLS, FIELD=DISPLACEMENT)


def _arc(lo_mm: float, hi_mm: float, radius: float, max_deg: float) -> np.ndarray:
    """Angles (rad) covering the arc whose sine-projections reach lo and hi (capped at max_deg),
    in elements of at most ROUND_ELEMENT_MM of arc."""
    cap = np.radians(max_deg)
    lo = -min(np.arcsin(min(-lo_mm / radius, 1.0)), cap)
    hi = min(np.arcsin(min(hi_mm / radius, 1.0)), cap)
    n = max(2, int(np.ceil(radius * (hi - lo) / ROUND_ELEMENT_MM)))
    return np.linspace(lo, hi, n + 1)


def indenter_grid(ind: Indenter, height_mm: float, width_mm: float,
                  length_mm: float) -> np.ndarray:
    """Node positions (2, nz + 1, nx + 1, 3) of the indenter's bricks: ``[0]`` on the face
    that meets the skin, ``[1]`` away from it; i runs with +x and k with +z."""
    a = PLATE_MARGIN_MM
    x_hi, z_hi = 0.5 * width_mm + a, 0.5 * length_mm + a
    if ind.kind == "plate":
        nx, nz = PLATE_GRID
        xs, zs = np.linspace(-a, x_hi, nx + 1), np.linspace(-a, z_hi, nz + 1)
        P = np.empty((2, nz + 1, nx + 1, 3))
        P[..., 0], P[..., 2] = xs[None, None, :], zs[None, :, None]
        P[0, ..., 1], P[1, ..., 1] = height_mm, height_mm + 1.0
        return P
    R = ind.radius_mm
    centre = np.array([0.0, height_mm + R, 0.0])
    radii = np.array([R, R - min(1.0, 0.5 * R)])[:, None, None, None]  # the far side: inwards
    if ind.kind == "sphere":  # cube map: direction (tan al, -1, tan be), normalised
        al = _arc(-a, x_hi, R, 55.0)
        be = _arc(-a, z_hi, R, 55.0)
        d = np.stack(np.broadcast_arrays(np.tan(al)[None, :], -1.0, np.tan(be)[:, None]), -1)
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        return centre + radii * d[None]
    if ind.angle_deg == 0.0:  # axis along z: i along the arc (x = R sin phi), k along z
        phi = _arc(-a, x_hi, R, 80.0)
        zs = np.linspace(-a, z_hi, PLATE_GRID[1] + 1)
        d = np.stack(np.broadcast_arrays(np.sin(phi)[None, :], -np.cos(phi)[None, :],
                                         0.0 * zs[:, None]), -1)
        P = centre + radii * d[None]
        P[..., 2] = zs[None, :, None]
        return P
    psi = _arc(-a, z_hi, R, 80.0)  # axis along x: i along x, k along the arc (z = R sin psi)
    xs = np.linspace(-a, x_hi, PLATE_GRID[0] + 1)
    d = np.stack(np.broadcast_arrays(0.0 * xs[None, :], -np.cos(psi)[:, None],
                                     np.sin(psi)[:, None]), -1)
    P = centre + radii * d[None]
    P[..., 0] = xs[None, None, :]
    return P


def calculix_tail(core: _Core, depth: float) -> list[str]:
    """Rigid C3D8 indenter on *RIGID BODY, linear-penalty face-to-face contact, boundary,
    *STATIC."""
    s, geom, n_skin = core.settings, core.geom, core.mesh.X.shape[0]
    rp, rot = n_skin + 1, n_skin + 2  # 1-based ids; PLATE_RP is written by _body
    ind = parse_indenter(s.indenter)
    P = indenter_grid(ind, geom.height_mm, geom.width_mm, geom.length_mm)
    nz, nx = P.shape[1] - 1, P.shape[2] - 1
    first = rot + 1

    def nid(i: int, j: int, k: int) -> int:  # i along x, k along z, j = 0 bottom / 1 top
        return first + (j * (nz + 1) + k) * (nx + 1) + i

    out = ["*NODE, NSET=PLATE_ROT", f"{rot}, 0., {_num(geom.height_mm)}, 0.",
           "*NODE, NSET=PLATE_NODES"]
    out += [f"{nid(i, j, k)}, {', '.join(_num(v) for v in P[j, k, i])}"
            for j in range(2) for k in range(nz + 1) for i in range(nx + 1)]
    # natural (xi, eta, zeta) = (z, x, y): right-handed (z x x = y); face S1 (zeta = -1) is the
    # plate's underside y = height, outward normal -y, facing the skin
    e0 = core.conn.shape[0] + 1
    out += ["*ELEMENT, TYPE=C3D8, ELSET=PLATE"]
    plate_el = []
    for k in range(nz):
        for i in range(nx):
            corners = [nid(i + di, j, k + dk) for j in range(2)
                       for dk, di in ((0, 0), (1, 0), (1, 1), (0, 1))]
            plate_el.append(e0 + len(plate_el))
            out.append(", ".join(map(str, [plate_el[-1], *corners])))
    name = "PLATE" if ind.kind == "plate" else "INDENTER"
    out += ["*MATERIAL, NAME=PLATE_STIFF", "*ELASTIC", "210000., 0.3",
            "*SOLID SECTION, ELSET=PLATE, MATERIAL=PLATE_STIFF", ",",
            *_comment(f"The {'plate' if ind.kind == 'plate' else 'indenter ' + ind.text} is "
                      "rigid: its nodes follow PLATE_RP (translation) and PLATE_ROT (rotation, "
                      "held at zero)."),
            f"*RIGID BODY, NSET=PLATE_NODES, REF NODE={rp}, ROT NODE={rot}",
            *_surface(name, np.array(plate_el) - 1, ["S1"] * len(plate_el)),
            *_comment(f"Frictionless (no *FRICTION) face-to-face penalty contact with "
                      f"softhand's law: pressure = {_num(s.penalty_N_mm3)} N/mm^3 x overclosure."),
            "*SURFACE INTERACTION, NAME=PENALTY",
            "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", _num(s.penalty_N_mm3),
            "*CONTACT PAIR, INTERACTION=PENALTY, TYPE=SURFACE TO SURFACE", f"SKIN, {name}"]
    if core.mesh.floor_faces.size:
        out += ["** Pocket closure: roof underside against floor.",
                "*CONTACT PAIR, INTERACTION=PENALTY, TYPE=SURFACE TO SURFACE", "ROOF, FLOOR"]
    period = depth / s.speed_mm_s
    dt = period / max(1, int(np.ceil(depth / CCX_STEP_MM - 1e-9)))
    inc = f"{_num(dt)}, {_num(period)}, {_num(period * 1e-6)}, {_num(dt)}"
    out += ["*BOUNDARY", "BASE, 1, 3", "XSYM, 1, 1", "ZSYM, 3, 3",
            "PLATE_RP, 1, 1", "PLATE_RP, 3, 3", "PLATE_ROT, 1, 3",
            f"** Ramp: plate down {_num(depth)} mm (time = travel / {_num(s.speed_mm_s)} mm/s).",
            "*STEP, NLGEOM, INC=10000", "*STATIC", inc,
            *_comment(f"Residual force test against a fixed reference force (q_u) instead of "
                      f"the running average, which is ~1e-5 N at the first contact of the "
                      f"soft skins: largest residual <= {_num(R_N)} x q_u = softhand's tol_N "
                      f"= {_num(s.tol_N)} N on the whole phalanx."),
            "*CONTROLS, PARAMETERS=FIELD, FIELD=DISPLACEMENT",
            f"{_num(R_N)}, 0.01, 0., {_num(s.tol_N / 4.0 / R_N)}, 0.02, 1e-05, 0.001, 1e-08",
            "*BOUNDARY", f"PLATE_RP, 2, 2, {_num(-depth)}",
            "*NODE PRINT, NSET=PLATE_RP", "U, RF", "*NODE FILE", "U", "*END STEP"]
    return out


_DAT_HEAD = re.compile(r"^\s*(displacements|forces)\s+\(.*?\)\s+for set\s+(\S+)\s+and time\s+"
                       r"(\S+)", re.IGNORECASE)


def read_ccx_dat(path: str | os.PathLike, node_set: str = "PLATE_RP"
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Plate curve from the .dat file of a CalculiX run of a ``fmt="ccx"`` deck.

    Args:
        path: the ``JOBNAME.dat`` file (``*NODE PRINT`` of U and RF of ``node_set``).
        node_set: the node set printed (one node: the plate reference node).

    Returns:
        ``(displacement_mm, force_N)`` per converged increment, starting at (0, 0): plate
        displacement -U2 (> 0 down) and whole-phalanx force -4 x RF2 (quarter model).

    Raises:
        ValueError: the file holds no U and RF of ``node_set``.
    """
    rows: dict[str, dict[float, float]] = {"displacements": {}, "forces": {}}
    kind = None
    for line in Path(path).read_text(encoding="utf-8", errors="replace").splitlines():
        m = _DAT_HEAD.match(line)
        if m:
            ok = m.group(2).upper() == node_set.upper()
            kind, time = (m.group(1).lower(), float(m.group(3))) if ok else (None, 0.0)
            continue
        fields = line.split()
        if kind and len(fields) == 4:
            rows[kind][time] = float(fields[2])
            kind = None
    times = sorted(set(rows["displacements"]) & set(rows["forces"]))
    if not times:
        raise ValueError(f"{str(path)!r} has no U and RF of node set {node_set!r}")
    d = [0.0] + [-rows["displacements"][t] for t in times]
    f = [0.0] + [-4.0 * rows["forces"][t] for t in times]
    return np.array(d), np.array(f)
