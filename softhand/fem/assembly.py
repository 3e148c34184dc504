r"""Total-Lagrangian finite-strain assembly of internal force and tangent stiffness.

Weak form (reference configuration `\Omega_0`, Green strain `E`, PK2 stress `S`):

    r(u) = \int_{\Omega_0} B(u)^T S\,dV, \qquad
    K = \int_{\Omega_0} B^T \mathbb{C} B\,dV + \int_{\Omega_0} \nabla_0 N\,S\,\nabla_0 N^T \otimes I\,dV,

with `B` the strain-displacement matrix at the current deformation gradient
`F = I + \nabla_0 u`. Plane strain keeps `F_{33} = 1` and integrates per unit length.
The sparse pattern is computed once; each assembly scatters element matrices with one
``bincount`` into CSR data.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import scipy.sparse as sp

from softhand.fem.materials import Material, ViscoState, voigt_to_tensor
from softhand.fem.mesh import Mesh
from softhand.parallel import check_threads

__all__ = ["ENGINES", "Assembler", "ElementState"]

#: element engines: ``"compiled"`` (numba kernels, `softhand.fem.kernels`) and ``"numpy"``
#: (the batched NumPy reference of this module); the same arithmetic, equal to rounding
ENGINES = ("compiled", "numpy")

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
        threads: element blocks evaluated at once (NumPy releases the GIL in the batched
            kernels, so the blocks run in parallel; the times with 1 and 2 threads are
            measured by ``softhand bench fe``, ``reports/bench-fe.md``); default:
            `softhand.parallel.default_threads`. The caller keeps BLAS single-threaded
            (`softhand.parallel.single_threaded_blas`): these threads own the cores.
        engine: one of `ENGINES`.
    """

    def __init__(self, mesh: Mesh, materials: list[Material], threads: int | None = None,
                 engine: str = "compiled") -> None:
        threads = check_threads(threads)
        if engine not in ENGINES:
            raise ValueError(f"engine = {engine!r}: allowed {', '.join(ENGINES)}")
        self.engine = engine
        self.threads = threads
        self._pool = ThreadPoolExecutor(threads) if threads > 1 else None
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
        #: (free dofs, their block's pattern) of the last `_free_pattern` call
        self._free_cache: tuple[np.ndarray, tuple] | None = None
        if engine == "compiled":
            nd_ = nn * dim
            #: the scatter in the compiled tangent's entry order (n, i, j, m) per element
            self._scatter_nijm = (self._scatter.reshape(ne, nn, dim, nn, dim)
                                  .transpose(0, 1, 2, 4, 3).reshape(ne, nd_ * nd_))
            #: the shape-function gradients as (element, (q, d), m) for the compiled tangent
            self._G_qdm = np.ascontiguousarray(
                self.dNdX.transpose(0, 1, 3, 2).reshape(ne, self.n_qp * dim, nn))

    def close(self) -> None:
        """Stop the element threads (the assembler stays usable, single-threaded)."""
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    def initial_state(self) -> ElementState:
        return ElementState([
            None if m.prony is None else ViscoState.zeros(len(g) * self.n_qp, m.n_terms)
            for m, g in zip(self.materials, self.groups, strict=True)
        ])

    def deformation_gradient(self, u: np.ndarray) -> np.ndarray:
        """F at every Gauss point, (ne, nq, 3, 3)."""
        dim = self.mesh.dim
        ue = u.reshape(-1, dim)[self.mesh.elements]
        grad = np.matmul(ue.transpose(0, 2, 1)[:, None], self.dNdX)
        F = np.broadcast_to(np.eye(3), grad.shape[:2] + (3, 3)).copy()
        F[..., :dim, :dim] += grad
        return F

    def assemble(self, u: np.ndarray, state: ElementState, dt: float, *, tangent: bool = True):
        """Internal force vector, tangent (CSR) and the history for the end of the step.

        Raises:
            ElementError: an element is inverted at this displacement.
        """
        f, tangent_of, new_state = self.evaluate(u, state, dt)
        return f, tangent_of() if tangent else None, new_state

    def evaluate(self, u: np.ndarray, state: ElementState, dt: float):
        """Internal force, a function that assembles the tangent at ``u``, and the new history.

        The function takes an optional sorted array of free DOFs and then returns only the
        free-free block, in CSC (scattered straight into its pattern: no slicing of the whole
        matrix). The tangent is built only when asked for, so a converged Newton iteration skips it. The
        internal force is ``sum_q w G_a P`` with the first Piola-Kirchhoff stress ``P = F S``
        (no strain matrix); the strain matrix is built only inside the tangent, block by
        block, so the converged iteration of each step never builds it.

        Raises:
            ElementError: an element is inverted at this displacement.
        """
        if self.engine == "compiled":
            return self._evaluate_compiled(u, state, dt)
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
            C = np.matmul(Fg.transpose(0, 2, 1), Fg)

            def update(a: int, b: int, mat=mat, C=C, hist=hist):
                part = None if hist is None else ViscoState(hist.S0[a:b], hist.H[:, a:b])
                with np.errstate(over="ignore", invalid="ignore"):  # checked below, not warned
                    return mat.update(C[a:b], part, dt)

            parts = self._blocks(update, C.shape[0])
            S[idx] = np.concatenate([p[0] for p in parts]).reshape(idx.size, nq, 6)
            D[idx] = np.concatenate([p[1] for p in parts]).reshape(idx.size, nq, 6, 6)
            new_groups.append(None if hist is None else ViscoState(
                np.concatenate([p[2].S0 for p in parts]),
                np.concatenate([p[2].H for p in parts], axis=1)))
        fe = np.empty((ne, nn * dim))

        def force(a: int, b: int) -> None:
            St = voigt_to_tensor(S[a:b])[..., :dim, :dim] * self.wdet[a:b, :, None, None]
            P = np.matmul(F[a:b, :, :dim, :dim], St)  # (m, nq, dim, dim): w F S, in-plane
            fe[a:b] = np.einsum("eqnb,eqib->eni", self.dNdX[a:b], P).reshape(b - a, nn * dim)

        self._blocks(force, ne)
        self._element_forces = fe  # of the last evaluation, for force_of()
        f = np.bincount(self.edofs.ravel(), weights=fe.ravel(), minlength=mesh.n_dofs)
        return f, lambda free=None: self._tangent(F, D, S, free), ElementState(new_groups)

    def _kernels(self):
        """The compiled kernels' module, its numba threads set to this assembler's."""
        import numba

        from softhand.fem import kernels

        numba.set_num_threads(min(self.threads, numba.config.NUMBA_NUM_THREADS))
        return kernels

    def _evaluate_compiled(self, u: np.ndarray, state: ElementState, dt: float):
        """`evaluate` on the compiled kernels (`softhand.fem.kernels`)."""
        kernels = self._kernels()
        mesh, dim = self.mesh, self.mesh.dim
        ne, nn = mesh.elements.shape
        nq = self.n_qp
        u = np.ascontiguousarray(u, dtype=float)
        fe = np.empty((ne, nn * dim))
        F = np.empty((ne, nq, 3, 3))
        S = np.empty((ne, nq, 6))
        D = np.empty((ne, nq, 6, 6))
        new_groups: list[ViscoState | None] = []
        bad = 0
        for mat, idx, hist in zip(self.materials, self.groups, state.groups, strict=True):
            if idx.size == 0:
                new_groups.append(hist)
                continue
            hf = mat.hyperfoam
            visco = mat.prony is not None and hist is not None
            if visco:
                if not dt >= 0.0:
                    raise ValueError(f"dt = {dt!r} must be >= 0")
                decay, ramp = mat.prony.step_factors(dt)
                g = np.asarray(mat.prony.g, dtype=float)
                S0_old, H_old = hist.S0, hist.H
                new = ViscoState(np.empty_like(S0_old), np.empty_like(H_old))
            else:
                decay = ramp = g = np.zeros(0)
                S0_old = np.zeros((0, 6))
                H_old = np.zeros((0, 0, 6))
                new = None
            bad += kernels.evaluate_group(
                u, mesh.elements, dim, idx, self.dNdX, self.wdet,
                np.asarray(hf.mu, dtype=float), np.asarray(hf.alpha, dtype=float),
                float(hf.beta), g, np.ascontiguousarray(decay, dtype=float),
                np.ascontiguousarray(ramp, dtype=float), S0_old, H_old, visco, fe, F, S, D,
                np.zeros((0, 6)) if new is None else new.S0,
                np.zeros((0, 0, 6)) if new is None else new.H)
            new_groups.append(new)
        if bad:
            raise ElementError(f"{bad} Gauss points have det F <= 0 or an indefinite C")
        self._element_forces = fe
        f = np.bincount(self.edofs.ravel(), weights=fe.ravel(), minlength=mesh.n_dofs)
        return (f, lambda free=None, raw=False: self._tangent_compiled(F, D, S, free, raw),
                ElementState(new_groups))

    def pattern(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The tangent's pattern, row and column of each stored value, and for each entry of
        the compiled element tangents (``tangent_of(raw=True)``, compiled engine) the index
        of the value it adds to (entries of one value are summed in their order; None on the
        NumPy engine)."""
        rows = np.repeat(np.arange(self.mesh.n_dofs), np.diff(self._indptr))
        entries = self._scatter_nijm.ravel() if self.engine == "compiled" else None
        return rows, self._cols.astype(np.int64), entries

    def inverted(self, u: np.ndarray) -> int:
        """The number of Gauss points with det F <= 0 (or not finite) at ``u``."""
        if self.engine == "compiled":
            return self._kernels().inverted_points(np.ascontiguousarray(u, dtype=float),
                                                   self.mesh.elements, self.mesh.dim,
                                                   self.dNdX)
        with np.errstate(over="ignore", invalid="ignore"):
            detF = np.linalg.det(self.deformation_gradient(u))
        return int((~(detF > 0)).sum())

    def _tangent_compiled(self, F: np.ndarray, D: np.ndarray, S: np.ndarray,
                          free: np.ndarray | None = None, raw: bool = False):
        """`_tangent` from the compiled element tangents (`kernels.element_tangents`);
        ``raw``: those element tangents' entries, unassembled (`pattern` says where each
        goes), instead of a matrix."""
        kernels = self._kernels()
        mesh, dim = self.mesh, self.mesh.dim
        ne, nn = mesh.elements.shape
        K = np.empty((ne, nn * dim * dim, nn))
        kernels.element_tangents(F, S, D, self.dNdX, self.wdet, self._G_qdm, K)
        if raw:
            return K.ravel()
        data = np.bincount(self._scatter_nijm.ravel(), weights=K.ravel(), minlength=self._nnz)
        return self._assembled(data, free)

    def _assembled(self, data: np.ndarray, free: np.ndarray | None) -> sp.spmatrix:
        """The tangent from its pattern's data: whole (CSR), or its free-free block (CSC)."""
        n = self.mesh.n_dofs
        if free is None:
            return sp.csr_matrix((data, self._cols, self._indptr), shape=(n, n))
        sel, cols, indptr = self._free_pattern(free)
        # the pattern is symmetric, so its CSR arrays are the CSC arrays of the transpose: the
        # tangent's own transpose (symmetric to rounding)
        return sp.csc_matrix((data[sel], cols, indptr), shape=(free.size, free.size))

    def force_of(self, elements: np.ndarray) -> np.ndarray:
        """Internal force vector of ``elements`` alone, at the last `evaluate`."""
        fe = self._element_forces[elements]
        return np.bincount(self.edofs[elements].ravel(), weights=fe.ravel(),
                           minlength=self.mesh.n_dofs)

    def _blocks(self, fn, n: int) -> list:
        """``fn(start, stop)`` over ``self.threads`` contiguous blocks of ``range(n)``, in order."""
        cuts = np.linspace(0, n, self.threads + 1).astype(int)
        spans = [(int(a), int(b)) for a, b in pairwise(cuts) if b > a]
        if self._pool is None or len(spans) == 1:
            return [fn(a, b) for a, b in spans]
        return list(self._pool.map(lambda ab: fn(*ab), spans))

    def _strain_matrix(self, F: np.ndarray, G: np.ndarray) -> np.ndarray:
        """B such that dE (Voigt, engineering shear) = B du_e, shape (ne, nq, 6, nn * dim).

        ``F`` and ``G`` (shape-function gradients) are those of the same elements.
        """
        dim = self.mesh.dim
        ne, nq, nn = G.shape[:3]
        Fd = F[..., :dim, :]  # rows i < dim: displacement components
        B = np.zeros((ne, nq, 6, nn, dim))
        for v, (a, b) in enumerate(_VOIGT):
            if b < dim:
                np.multiply(Fd[:, :, None, :, a], G[:, :, :, b, None], out=B[:, :, v])
            if a != b and a < dim:
                B[:, :, v] += Fd[:, :, None, :, b] * G[:, :, :, a, None]
        return B.reshape(ne, nq, 6, nn * dim)

    def _free_pattern(self, free: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Which entries of the full pattern lie in the free-free block, and that block's CSR
        column indices and row pointers (cached for the last ``free``)."""
        cached = self._free_cache
        if cached is not None and np.array_equal(cached[0], free):
            return cached[1]
        n = self.mesh.n_dofs
        fmap = np.full(n, -1, dtype=np.int64)
        fmap[free] = np.arange(free.size)
        rows = np.repeat(np.arange(n), np.diff(self._indptr))
        sel = (fmap[rows] >= 0) & (fmap[self._cols] >= 0)
        cols = fmap[self._cols[sel]].astype(np.int32)
        indptr = np.searchsorted(fmap[rows[sel]], np.arange(free.size + 1)).astype(np.int32)
        self._free_cache = (free.copy(), (np.flatnonzero(sel), cols, indptr))
        return self._free_cache[1]

    def _tangent(self, F: np.ndarray, D: np.ndarray, S: np.ndarray,
                 free: np.ndarray | None = None) -> sp.spmatrix:
        """Material plus geometric stiffness from the Gauss-point arrays of `evaluate`
        (the strain matrix is built block by block here, never for the whole mesh)."""
        mesh, dim = self.mesh, self.mesh.dim
        ne, nn = mesh.elements.shape
        nq = self.n_qp
        nd = nn * dim
        G = self.dNdX  # (ne, nq, nn, dim): only the in-plane stresses enter in plane strain
        per_element = self._scatter.size // ne
        parts: list[np.ndarray] = []

        def block(a: int, b: int) -> np.ndarray:
            w = self.wdet[a:b]
            m = b - a
            B = self._strain_matrix(F[a:b], G[a:b])
            DB = np.matmul(D[a:b] * w[..., None, None], B)  # (m, nq, 6, nd)
            Bt = B.transpose(0, 3, 1, 2).reshape(m, nd, nq * 6)
            Km = np.matmul(Bt, DB.reshape(m, nq * 6, nd))
            St = voigt_to_tensor(S[a:b])[..., :dim, :dim] * w[..., None, None]
            GS = np.matmul(G[a:b], St)  # (m, nq, nn, dim)
            Kg = np.matmul(GS.transpose(0, 2, 1, 3).reshape(m, nn, nq * dim),
                           G[a:b].transpose(0, 1, 3, 2).reshape(m, nq * dim, nn))
            Kv = Km.reshape(m, nn, dim, nn, dim)
            for i in range(dim):  # geometric stiffness: the same node block on every component
                Kv[:, :, i, :, i] += Kg
            return np.bincount(self._scatter[a * per_element:b * per_element],
                               weights=Km.ravel(), minlength=self._nnz)

        parts = self._blocks(block, ne)
        data = parts[0] if len(parts) == 1 else np.sum(parts, axis=0)
        return self._assembled(data, free)
