r"""Total-Lagrangian finite-strain assembly of internal force and tangent stiffness.

Weak form (reference configuration :math:`\Omega_0`, Green strain :math:`E`, PK2 stress :math:`S`):

.. math::

    r(u) = \int_{\Omega_0} B(u)^T S\,dV, \qquad
    K = \int_{\Omega_0} B^T \mathbb{C} B\,dV + \int_{\Omega_0} \nabla_0 N\,S\,\nabla_0 N^T \otimes I\,dV,

with :math:`B` the strain-displacement matrix at the current deformation gradient
:math:`F = I + \nabla_0 u`. Plane strain keeps :math:`F_{33} = 1` and integrates per unit length.
The sparse pattern is computed once; each assembly scatters element matrices with one
``bincount`` into CSR data.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from softhand.fem.materials import Material, ViscoState, voigt_to_tensor
from softhand.fem.mesh import Mesh

__all__ = ["Assembler", "ElementState"]

_VOIGT = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))


class ElementError(FloatingPointError):
    """An element inverted (det F <= 0) during an iteration."""


@dataclass
class ElementState:
    """Viscoelastic history per material group (one entry per material in the assembler)."""

    groups: list[ViscoState | None]

    def copy(self) -> ElementState:
        return ElementState([None if g is None else g.copy() for g in self.groups])


class Assembler:
    """Internal force and tangent for a mesh with per-element materials.

    Args:
        mesh: the mesh.
        materials: one material per layer id (index 0: inner part, 1: outer layer).
    """

    def __init__(self, mesh: Mesh, materials: list[Material]) -> None:
        self.mesh = mesh
        self.materials = materials
        dim, ref = mesh.dim, mesh.ref
        Xe = mesh.X[mesh.elements]  # (ne, nn, dim)
        J = np.einsum("enk,qnj->eqkj", Xe, ref.dN)  # dX/dxi
        det = np.linalg.det(J)
        if np.any(det <= 0):
            raise ValueError(f"mesh has {int((det <= 0).sum())} Gauss points with det J <= 0")
        self.dNdX = np.einsum("qnj,eqjk->eqnk", ref.dN, np.linalg.inv(J))
        self.wdet = det * ref.weights[None, :]
        ne, nn = mesh.elements.shape
        self.edofs = (mesh.elements[:, :, None] * dim + np.arange(dim)).reshape(ne, nn * dim)
        nd = nn * dim
        rows = np.repeat(self.edofs, nd, axis=1).ravel()
        cols = np.tile(self.edofs, (1, nd)).ravel()
        n = mesh.n_dofs
        keys, self._scatter = np.unique(rows * n + cols, return_inverse=True)
        rows_u = keys // n
        self._cols = (keys % n).astype(np.int32)
        self._indptr = np.searchsorted(rows_u, np.arange(n + 1)).astype(np.int32)
        self._nnz = keys.size
        self.groups = [np.flatnonzero(mesh.layer == k) for k in range(len(materials))]
        self.n_qp = ref.weights.size

    def initial_state(self) -> ElementState:
        return ElementState([
            None if m.prony is None else ViscoState.zeros(len(g) * self.n_qp, m.n_terms)
            for m, g in zip(self.materials, self.groups, strict=True)
        ])

    def deformation_gradient(self, u: np.ndarray) -> np.ndarray:
        """F at every Gauss point, (ne, nq, 3, 3)."""
        dim = self.mesh.dim
        ue = u.reshape(-1, dim)[self.mesh.elements]
        grad = np.einsum("enk,eqnj->eqkj", ue, self.dNdX)
        F = np.broadcast_to(np.eye(3), grad.shape[:2] + (3, 3)).copy()
        F[..., :dim, :dim] += grad
        return F

    def assemble(self, u: np.ndarray, state: ElementState, dt: float, *, tangent: bool = True):
        """Internal force vector, tangent (CSR) and the history for the end of the step.

        Raises:
            ElementError: an element is inverted at this displacement.
        """
        mesh, dim = self.mesh, self.mesh.dim
        ne, nn = mesh.elements.shape
        nq = self.n_qp
        F = self.deformation_gradient(u)
        with np.errstate(over="ignore", invalid="ignore"):  # a wild Newton iterate is rejected
            detF = np.linalg.det(F)
        if not np.all(detF > 0):
            raise ElementError(f"{int((detF <= 0).sum())} Gauss points have det F <= 0")
        S = np.empty((ne, nq, 6))
        D = np.empty((ne, nq, 6, 6))
        new_groups: list[ViscoState | None] = []
        for mat, idx, hist in zip(self.materials, self.groups, state.groups, strict=True):
            if idx.size == 0:
                new_groups.append(hist)
                continue
            Fg = F[idx].reshape(-1, 3, 3)
            C = np.einsum("nki,nkj->nij", Fg, Fg)
            with np.errstate(over="ignore", invalid="ignore"):  # checked below, not warned
                Sg, Dg, h = mat.update(C, hist, dt)
            S[idx] = Sg.reshape(idx.size, nq, 6)
            D[idx] = Dg.reshape(idx.size, nq, 6, 6)
            new_groups.append(h)
        G = np.zeros((ne, nq, nn, 3))
        G[..., :dim] = self.dNdX
        Fd = F[..., :dim, :]  # rows i < dim: displacement components
        B = np.empty((ne, nq, 6, nn, dim))
        for v, (a, b) in enumerate(_VOIGT):
            np.multiply(Fd[:, :, None, :, a], G[:, :, :, b, None], out=B[:, :, v])
            if a != b:
                B[:, :, v] += Fd[:, :, None, :, b] * G[:, :, :, a, None]
        B = B.reshape(ne, nq, 6, nn * dim)
        w = self.wdet
        fe = np.einsum("eqvk,eqv->ek", B, S * w[..., None])
        f = np.bincount(self.edofs.ravel(), weights=fe.ravel(), minlength=mesh.n_dofs)
        if not tangent:
            return f, None, ElementState(new_groups)
        DB = np.matmul(D * w[..., None, None], B)  # (ne, nq, 6, nd)
        nd = nn * dim
        Bt = B.transpose(0, 3, 1, 2).reshape(ne, nd, nq * 6)
        Km = np.matmul(Bt, DB.reshape(ne, nq * 6, nd))
        St = voigt_to_tensor(S) * w[..., None, None]
        GS = np.einsum("eqna,eqab->eqnb", G, St)
        Kg = np.matmul(GS.transpose(0, 2, 1, 3).reshape(ne, nn, nq * 3),
                       G.transpose(0, 1, 3, 2).reshape(ne, nq * 3, nn))
        Kv = Km.reshape(ne, nn, dim, nn, dim)
        for i in range(dim):  # geometric stiffness: the same node block on every component
            Kv[:, :, i, :, i] += Kg
        data = np.bincount(self._scatter, weights=Km.ravel(), minlength=self._nnz)
        K = sp.csr_matrix((data, self._cols, self._indptr), shape=(mesh.n_dofs, mesh.n_dofs))
        return f, K, ElementState(new_groups)
