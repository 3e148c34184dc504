"""A graded rectangular block: the half-space stand-in of the indenter checks against Hertz.

Quarter of a block ``|x| <= width/2, 0 <= y <= height, |z| <= length/2`` in 3D (half,
``|x| <= width/2``, in 2D plane strain, per mm of length), quadratic elements graded towards the
indenter's first contact at the top centre (x = z = 0, y = height). Same conventions as the
phalanx mesh (`softhand.fem.mesh`): base y = 0 fixed, symmetry planes x = 0 and z = 0, the
top face is the outer (contact) surface, all elements in layer 0 (the inner material).
"""

from __future__ import annotations

import numpy as np

from softhand.fem.elements import reference_element
from softhand.fem.mesh import Mesh, MeshSpec, _graded, _with_midpoints

__all__ = ["block_mesh"]


def _lines(size: float, n: int, ratio: float, dense_at_end: bool) -> np.ndarray:
    """2n + 1 ascending node lines on [0, size], the smallest element ``ratio`` times the largest
    at 0 (or at ``size`` if ``dense_at_end``)."""
    g = size * _graded(n, ratio)
    if dense_at_end:
        g = size - g[::-1]
    return _with_midpoints(g)


def block_mesh(*, width_mm: float, height_mm: float, length_mm: float | None = None,
               n: int = 8, ratio: float = 0.1, dim: int = 3) -> Mesh:
    """Build the graded block.

    Args:
        width_mm, height_mm, length_mm: full block size (mm; length only in 3D), each > 0.
        n: elements along each modelled edge, >= 1.
        ratio: smallest / largest element along each edge, in (0, 1] (the smallest at the
            top centre).
        dim: 3 (quarter) or 2 (half section, plane strain, force per mm of length).
    """
    if dim not in (2, 3):
        raise ValueError(f"dim = {dim!r}: allowed 2 (plane strain) or 3")
    sizes = {"width_mm": width_mm, "height_mm": height_mm}
    if dim == 3:
        sizes["length_mm"] = length_mm
    for name, v in sizes.items():
        if v is None or not np.isfinite(v) or v <= 0:
            raise ValueError(f"{name} = {v!r}: expected a finite number > 0")
    if not isinstance(n, int) or n < 1:
        raise ValueError(f"n = {n!r}: expected an integer >= 1")
    if not 0 < ratio <= 1:
        raise ValueError(f"ratio = {ratio!r}: expected a number in (0, 1]")
    y = _lines(height_mm, n, ratio, dense_at_end=True)
    x = _lines(0.5 * width_mm, n, ratio, dense_at_end=False)
    if dim == 3:
        # local axes (xi0, xi1, xi2) = (y, z, x): right-handed, xi0 = +1 is the top face
        z = _lines(0.5 * length_mm, n, ratio, dense_at_end=False)
        Y, Z, Xc = np.meshgrid(y, z, x, indexing="ij")
        coords = np.stack([Xc, Y, Z], axis=-1)
        shape = (len(y), len(z), len(x))
    else:
        # local axes (xi0, xi1) = (y, -x): right-handed, xi0 = +1 is the top face
        Y, Xc = np.meshgrid(y, x[::-1], indexing="ij")
        coords = np.stack([Xc, Y], axis=-1)
        shape = (len(y), len(x))
    gid = np.arange(int(np.prod(shape))).reshape(shape)
    local = [(p0, p1, p2) for p2 in range(3 if dim == 3 else 1) for p1 in range(3)
             for p0 in range(3)]
    elems, outer_rows = [], []
    ranges = [range(n)] * dim
    for k in np.ndindex(*(len(r) for r in ranges)):
        idx = [gid[tuple(2 * k[j] + p[j] for j in range(dim))] for p in local]
        if k[0] == n - 1:
            outer_rows.append(len(elems))
        elems.append(idx)
    conn = np.array(elems)
    X = coords.reshape(-1, dim)
    face_hi = [a for a, p in enumerate(local) if p[0] == 2]
    outer_faces = conn[outer_rows][:, face_hi]
    tol = 1e-9
    fixed = [np.flatnonzero(np.abs(X[:, 1]) < tol) * dim + c for c in range(dim)]
    fixed.append(np.flatnonzero(np.abs(X[:, 0]) < tol) * dim + 0)
    if dim == 3:
        fixed.append(np.flatnonzero(np.abs(X[:, 2]) < tol) * dim + 2)
    npf = 3 ** (dim - 1)
    return Mesh(
        dim=dim, X=X, elements=conn, layer=np.zeros(len(conn), dtype=int),
        ref=reference_element(dim, 3), fixed=np.unique(np.concatenate(fixed)),
        outer_faces=outer_faces, roof_faces=np.zeros((0, npf), dtype=int),
        floor_faces=np.zeros((0, npf), dtype=int),
        symmetry_factor=4.0 if dim == 3 else 2.0, length_mm=1.0, spec=MeshSpec(),
    )
