"""A phalanx as a watertight STL for a mould (mm): the cross-section with its pocket, extruded.

The section is the FE's own (`softhand.fem.mesh.build_mesh`, 2D, the ``fine`` level): each
quadratic element is split at its mid-side nodes into four quadrilaterals, two triangles each,
mirrored about x = 0 and merged there; the pocket is the elements the mesh leaves out, so it is a
hole through the section. `trimesh.creation.extrude_triangulation` extrudes it along the length
(z from 0 to ``length_mm``): one solid with a tunnel, the open pocket a straight core pulls out of
(Euler number 0). Base (bone side) on y = 0, apex at y = height.

The curved edges become chords, so the volume is slightly below the exact one
(`exact_volume_mm3`: the superellipse's area minus the pocket's, times the length; the pocket,
a band of constant thickness h under the profile, has area h times the length of its mid-depth
offset curve).
"""

from __future__ import annotations

from math import gamma
from pathlib import Path

import numpy as np

from softhand.fem.geometry import PhalanxGeometry
from softhand.fem.mesh import MESH_LEVELS, build_mesh

__all__ = ["exact_volume_mm3", "phalanx_mesh", "write_stl"]

_SUB_QUADS = [((0, 0), (1, 0), (1, 1), (0, 1)), ((1, 0), (2, 0), (2, 1), (1, 1)),
              ((0, 1), (1, 1), (1, 2), (0, 2)), ((1, 1), (2, 1), (2, 2), (1, 2))]


def _section_triangles(geom: PhalanxGeometry, level: str) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (n, 2), CCW triangles (m, 3)) of the whole cross-section."""
    mesh = build_mesh(geom, MESH_LEVELS[level], dim=2)
    tris = []
    for e in mesh.elements:  # Q9, local node p0 + 3 p1
        for quad in _SUB_QUADS:
            a, b, c, d = (e[p0 + 3 * p1] for p0, p1 in quad)
            tris += [(a, b, c), (a, c, d)]
    tris = np.array(tris)
    X = mesh.X
    # mirror about x = 0 and merge the nodes on it
    n = len(X)
    on_axis = np.abs(X[:, 0]) < 1e-9
    mirror_id = np.where(on_axis, np.arange(n), n + np.arange(n))
    verts = np.vstack([X, X * [-1.0, 1.0]])
    tris = np.vstack([tris, mirror_id[tris]])
    used, inverse = np.unique(tris, return_inverse=True)
    verts, tris = verts[used], inverse.reshape(tris.shape)
    p = verts[tris]
    area2 = ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
             - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    keep = np.abs(area2) > 1e-12  # the collapsed base centre makes degenerate triangles
    tris = tris[keep]
    flip = area2[keep] < 0
    tris[flip] = tris[flip][:, ::-1]
    return verts, tris


def phalanx_mesh(geom: PhalanxGeometry, *, level: str = "fine"):
    """The phalanx as a watertight `trimesh.Trimesh` in mm (module docstring)."""
    import trimesh

    verts, tris = _section_triangles(geom, level)
    solid = trimesh.creation.extrude_triangulation(verts, tris, geom.length_mm)
    solid.merge_vertices()
    solid.fix_normals()
    return solid


def exact_volume_mm3(geom: PhalanxGeometry) -> float:
    """The phalanx's exact volume (mm^3): section area times length (module docstring)."""
    a, b = geom.semi_axes
    n = geom.profile_exponent
    half = 2.0 * a * b * gamma(1 + 1 / n) ** 2 / gamma(1 + 2 / n)  # y >= 0 half superellipse
    pocket = 0.0
    if geom.has_pocket:
        theta = np.linspace(geom.pocket_edge_theta(), 0.5 * np.pi, 20001)
        mid = geom.offset(theta, geom.pocket_roof_mm + 0.5 * geom.pocket_height_mm)
        length = float(np.sum(np.linalg.norm(np.diff(mid, axis=0), axis=1)))
        pocket = 2.0 * geom.pocket_height_mm * length  # both halves
    return (half - pocket) * geom.length_mm


def write_stl(geom: PhalanxGeometry, path: str | Path, *, level: str = "fine") -> dict:
    """Write the phalanx's STL (binary, mm) atomically; return its checks.

    Returns:
        ``{"path", "watertight", "volume_mm3", "exact_volume_mm3", "volume_error_pct",
        "euler_number", "bounds_mm"}``.

    Raises:
        ValueError: the mesh is not watertight (a bug: it would not cast).
    """
    from softhand.io import atomic_open

    solid = phalanx_mesh(geom, level=level)
    if not solid.is_watertight:
        raise ValueError(f"{path}: the phalanx mesh is not watertight")
    exact = exact_volume_mm3(geom)
    with atomic_open(path, "wb") as fh:
        fh.write(solid.export(file_type="stl"))
    return {"path": str(path), "watertight": bool(solid.is_watertight),
            "volume_mm3": float(solid.volume), "exact_volume_mm3": exact,
            "volume_error_pct": float(100 * (solid.volume - exact) / exact),
            "euler_number": int(solid.euler_number),
            "bounds_mm": np.asarray(solid.bounds).tolist()}
