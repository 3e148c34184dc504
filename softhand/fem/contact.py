r"""Frictionless penalty contact, integrated at surface Gauss points.

Each contact set is a linear gap :math:`g = g_0 + G u` evaluated at Gauss points of a surface,
with weights :math:`w` (reference area). The penalty energy
:math:`\Pi_c=\tfrac12\,\varepsilon\sum_q w_q\langle -g_q\rangle^2` gives

.. math::

    r_c = -G^T (\varepsilon\, w \langle -g\rangle), \qquad K_c = G^T\,\mathrm{diag}(\varepsilon w\,[g<0])\,G,

and the contact force :math:`\sum_q \varepsilon w_q\langle -g_q\rangle`. Integrating at Gauss points
(not nodes) lets the contact zone grow inside an element, which keeps the force curve smooth.

* Plate: a rigid plane ``y = top - d`` (d the plate displacement). Frictionless: only the vertical
  component enters the gap. Exact for a flat plate, any sliding.
* Pocket: roof underside against floor, paired at the same surface coordinates (small sliding),
  gap measured along the floor's reference normal. Adequate while the roof closes onto the floor
  without sliding far along it, which is how the pocket closes under a flat plate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from softhand.fem.mesh import Mesh, face_element

__all__ = ["GapSet", "plate_gaps", "pocket_gaps"]


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

    def add(self, u: np.ndarray, penalty: float, shift: float = 0.0):
        """Residual vector and tangent matrix contributions, and the number of closed points."""
        g = self.gaps(u, shift)
        closed = g < 0.0
        lam = penalty * self.weight * np.where(closed, -g, 0.0)
        r = -(self.G.T @ lam)
        K = self.G.T @ sp.diags(penalty * self.weight * closed) @ self.G
        return r, K, int(closed.sum())


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
    """Gap between the outer surface and the plate ``y = top_mm - shift`` (shift = -d)."""
    N, pos, _, weight = _face_geometry(mesh, mesh.outer_faces, n_gauss)
    down = np.zeros(pos.shape)
    down[..., 1] = 1.0
    G = _gap_matrix(mesh, mesh.outer_faces, N, down, -1.0)
    return GapSet((top_mm - pos[..., 1]).ravel(), G, weight.ravel(),
                  pos.reshape(-1, mesh.dim))


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
