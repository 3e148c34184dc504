r"""Frictionless penalty contact, integrated at surface Gauss points.

Each contact set is a linear gap `g = g_0 + G u` evaluated at Gauss points of a surface,
with weights `w` (reference area). The penalty energy
`\Pi_c=\tfrac12\,\varepsilon\sum_q w_q\langle -g_q\rangle^2` gives

    r_c = -G^T (\varepsilon\, w \langle -g\rangle), \qquad K_c = G^T\,\mathrm{diag}(\varepsilon w\,[g<0])\,G,

and the contact force `\sum_q \varepsilon w_q\langle -g_q\rangle`. Integrating at Gauss points
(not nodes) lets the contact zone grow inside an element, which keeps the force curve smooth.

* Plate: a rigid plane ``y = top - d`` (d the plate displacement). Frictionless: only the vertical
  component enters the gap. Exact for a flat plate, any sliding. A plate smaller than the body
  (``Mesh.plate_half_mm``, the palm) acts on the surface points under its face only.
* Cylinder or sphere (`RoundGaps`): the gap to a rigid cylinder or sphere of radius R is
  nonlinear in u, `g = |P(x - c)| - R` with `x` the current point, `c` the
  centre (on the axis) and `P` the projection off the cylinder's axis (the identity for a
  sphere); it is linearised at every Newton iterate, `G = n^T N` with the unit normal
  `n = P(x-c)/|P(x-c)|`, into a `GapSet`. The tangent drops the curvature term
  `\varepsilon w\, g\,(P - nn^T)/|P(x-c)|` (relative size penetration / R, about 1e-4):
  Newton converges slightly less than quadratically, and the residual is exact.
* Pocket: roof underside against floor, paired at the same surface coordinates (small sliding),
  gap measured along the floor's reference normal. Adequate while the roof closes onto the floor
  without sliding far along it, which is how the pocket closes under a flat plate.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from softhand.fem.mesh import Mesh, face_element

__all__ = ["GapSet", "RoundGaps", "plate_gaps", "pocket_gaps"]


@dataclass(frozen=True)
class GapSet:
    """A linear gap function at surface Gauss points: g = g0 + G u (mm).

    ``weight`` is each point's share of the undeformed surface (mm^2; mm in plane strain),
    ``points`` its undeformed position (mm), where known.
    """

    g0: np.ndarray
    G: sp.csr_matrix
    weight: np.ndarray
    points: np.ndarray | None = None

    @property
    def size(self) -> int:
        return self.g0.size

    def gaps(self, u: np.ndarray, shift: float = 0.0) -> np.ndarray:
        return self.g0 + shift + self.G @ u

    def force(self, u: np.ndarray, penalty: float, shift: float = 0.0) -> float:
        """Contact force on the modelled part (N; N/mm in plane strain) of this set."""
        return float(penalty * (self.weight * np.maximum(-self.gaps(u, shift), 0.0)).sum())

    def pressure(self, u: np.ndarray, penalty: float, shift: float = 0.0) -> np.ndarray:
        """Contact pressure at each point (MPa = N/mm^2): the penalty times the overlap."""
        return penalty * np.maximum(-self.gaps(u, shift), 0.0)

    def contact_area(self, u: np.ndarray, shift: float = 0.0) -> float:
        """Undeformed surface in contact (mm^2 of the modelled part; mm in plane strain): the
        weights of the points whose gap is closed. Resolution: one Gauss point's weight."""
        return float(self.weight[self.gaps(u, shift) < 0.0].sum())

    def penalty_forces(self, u: np.ndarray, penalty: float, shift: float = 0.0):
        """Residual contribution, each point's penalty stiffness ``eps w [g < 0]`` (the
        diagonal of the tangent `stiffness`) and the number of closed points."""
        g = self.gaps(u, shift)
        closed = g < 0.0
        lam = penalty * self.weight * np.where(closed, -g, 0.0)
        r = -(self.transposed @ lam)
        return r, penalty * self.weight * closed, int(closed.sum())

    @cached_property
    def transposed(self) -> sp.csr_matrix:
        """The gap matrix ``G`` transposed, in CSR (dofs x points), formed once: `penalty_forces` runs at every
        Newton iteration, and transposing there took 0.06 s of a 0.87 s 2D run."""
        return self.G.T.tocsr()

    def stiffness(self, kw: np.ndarray) -> sp.csr_matrix:
        """The tangent ``G^T diag(kw) G`` for the point stiffnesses of `penalty_forces`."""
        return self.G.T @ sp.diags(kw) @ self.G


def _face_geometry(mesh: Mesh, faces: np.ndarray, n_gauss: int):
    """Shape values, positions, unit normals and area weights at face Gauss points."""
    fref = face_element(mesh.dim, n_gauss)
    Xf = mesh.X[faces]  # (nf, npf, dim)
    pos = np.einsum("qn,fnd->fqd", fref.N, Xf)
    tang = np.einsum("qnj,fnd->fqdj", fref.dN, Xf)  # (nf, nq, dim, dim-1)
    if mesh.dim == 2:
        t = tang[..., 0]
        normal = np.stack([t[..., 1], -t[..., 0]], axis=-1)
    else:
        normal = np.cross(tang[..., 0], tang[..., 1])
    area = np.linalg.norm(normal, axis=-1)
    normal = normal / area[..., None]
    weight = area * fref.weights[None, :]
    return fref.N, pos, normal, weight


def _gap_matrix(mesh: Mesh, faces: np.ndarray, N: np.ndarray, direction: np.ndarray, sign: float):
    """Sparse rows (one per face Gauss point) of sign * sum_a N_a (u_a . direction)."""
    nf, npf = faces.shape
    nq = N.shape[0]
    dim = mesh.dim
    rows = np.broadcast_to(np.arange(nf * nq).reshape(nf, nq, 1, 1), (nf, nq, npf, dim))
    cols = faces[:, None, :, None] * dim + np.arange(dim)
    cols = np.broadcast_to(cols, (nf, nq, npf, dim))
    vals = sign * N[None, :, :, None] * direction[:, :, None, :]
    return sp.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())),
                         shape=(nf * nq, mesh.n_dofs))


def plate_gaps(mesh: Mesh, top_mm: float, n_gauss: int = 4) -> GapSet:
    """Gap between the outer surface and the plate ``y = top_mm - shift`` (shift = -d).

    A finite plate (``mesh.plate_half_mm`` = (hx, hz), a body wider than the plate) presses only
    the points under its face, ``|x| <= hx`` and ``|z| <= hz`` in the undeformed state (2D:
    ``|x| <= hx``): frictionless points hardly slide, so the set is fixed for the run. The face's
    edge falls between Gauss points unless a mesh line lies on it (the palm mesh puts one at
    ``z = hz``). Without ``plate_half_mm`` (the phalanx) every point of the outer surface is in
    the set, as before.
    """
    N, pos, _, weight = _face_geometry(mesh, mesh.outer_faces, n_gauss)
    down = np.zeros(pos.shape)
    down[..., 1] = 1.0
    G = _gap_matrix(mesh, mesh.outer_faces, N, down, -1.0)
    gaps = GapSet((top_mm - pos[..., 1]).ravel(), G, weight.ravel(), pos.reshape(-1, mesh.dim))
    if mesh.plate_half_mm is None:
        return gaps
    hx, hz = mesh.plate_half_mm
    tol = 1e-9
    under = np.abs(gaps.points[:, 0]) <= hx + tol
    if mesh.dim == 3:
        under &= np.abs(gaps.points[:, 2]) <= hz + tol
    return GapSet(gaps.g0[under], gaps.G[under], gaps.weight[under], gaps.points[under])


class RoundGaps:
    """Gap between the outer surface and a rigid cylinder or sphere moving down (-y).

    The centre is at ``(0, top_mm + radius_mm - d, 0)`` for indenter travel ``d``: at ``d = 0``
    the indenter touches the top of the skin. ``axis`` is the cylinder's unit axis in model
    coordinates (3D), or None for a sphere (3D) and for a cylinder normal to a 2D section.
    """

    def __init__(self, mesh: Mesh, top_mm: float, radius_mm: float,
                 axis: np.ndarray | None, n_gauss: int = 4) -> None:
        N, pos, _, weight = _face_geometry(mesh, mesh.outer_faces, n_gauss)
        self.mesh, self.N, self.top_mm, self.radius_mm = mesh, N, top_mm, radius_mm
        self.axis = None if axis is None else np.asarray(axis, dtype=float)[:mesh.dim]
        self.points = pos.reshape(-1, mesh.dim)
        self.weight = weight.ravel()
        self._shape = pos.shape  # (faces, points per face, dim)

    def centre(self, d: float) -> np.ndarray:
        c = np.zeros(self.mesh.dim)
        c[1] = self.top_mm + self.radius_mm - d
        return c

    def _normal(self, u: np.ndarray, d: float) -> tuple[np.ndarray, np.ndarray]:
        """Gap and unit normal (away from the axis or centre) at each point for state u."""
        un = u.reshape(-1, self.mesh.dim)[self.mesh.outer_faces]
        x = self.points + np.einsum("qn,fnd->fqd", self.N, un).reshape(self.points.shape)
        r = x - self.centre(d)
        if self.axis is not None:
            r = r - np.outer(r @ self.axis, self.axis)
        rho = np.linalg.norm(r, axis=1)
        return rho - self.radius_mm, r / rho[:, None]

    def linearised(self, u: np.ndarray, d: float) -> GapSet:
        """The gap linearised at state u (exact gap at u), for indenter travel d."""
        g, n = self._normal(u, d)
        G = _gap_matrix(self.mesh, self.mesh.outer_faces, self.N, n.reshape(self._shape), 1.0)
        return GapSet(g - G @ u, G, self.weight, self.points)

    def force(self, u: np.ndarray, d: float, penalty: float) -> float:
        """Reaction on the indenter along its travel (+ = the skin pushes it up), modelled part."""
        g, n = self._normal(u, d)
        return float(penalty * (self.weight * np.maximum(-g, 0.0) * -n[:, 1]).sum())


def pocket_gaps(mesh: Mesh, n_gauss: int = 4) -> GapSet | None:
    """Gap between the pocket roof and floor along the floor's reference normal, or None."""
    if mesh.floor_faces.size == 0:
        return None
    N, pos_f, normal, weight = _face_geometry(mesh, mesh.floor_faces, n_gauss)
    pos_r = np.einsum("qn,fnd->fqd", N, mesh.X[mesh.roof_faces])
    gap0 = np.einsum("fqd,fqd->fq", pos_r - pos_f, normal)
    flip = np.where(gap0 < 0, -1.0, 1.0)
    normal = normal * flip[..., None]
    gap0 = gap0 * flip
    G = (_gap_matrix(mesh, mesh.roof_faces, N, normal, 1.0)
         + _gap_matrix(mesh, mesh.floor_faces, N, normal, -1.0))
    return GapSet(gap0.ravel(), G.tocsr(), weight.ravel())
