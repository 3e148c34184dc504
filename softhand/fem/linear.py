"""The Newton tangent of one run in one fixed sparse pattern, factorized by sparse Cholesky.

Every tangent of a run is the free-free block of the elements' stiffness plus the penalty
stiffness of the contact points that are closed, `G^T \\operatorname{diag}(\\varepsilon w
[g<0])\\, G` (`softhand.fem.contact`). So every tangent's pattern lies in one union known
before the first step: the elements' pattern and, for each contact set, the couplings of each
point's degrees of freedom. `TangentSystem` builds that union's lower triangle once,
analyses it once (the symbolic factorization: fill-reducing ordering and supernodes), and
then each Newton iteration only scatters numbers into it and runs the numeric factorization.

Two factorizations serve, the same arithmetic to rounding (``softhand bench fe`` times both):

- MKL PARDISO (Schenk and Gaertner, Future Generation Computer Systems 20, 2004; as shipped in
  Intel's MKL wheels, loaded by pypardiso; the ``softhand[mkl]`` extra, x86-64 Linux and
  Windows): nested-dissection ordering (METIS) and threaded supernodal factorization, on the
  GNU OpenMP runtime that numba's kernels use (`_Pardiso.library`). Chosen where it is
  installed: on the 3D tangents of ``pocket2-sil`` (4.9k free dofs) its numeric factorization
  took 0.3-0.6x CHOLMOD's time on one thread and about 0.3x on two (``softhand bench fe`` has
  whole runs).
- CHOLMOD (Chen, Davis, Hager and Rajamanickam, ACM TOMS 35, 2008; as shipped in CVXOPT's
  binary wheels for Linux, macOS and Windows: no compiler, no SuiteSparse headers): everywhere
  else. Its numeric factorization takes about 0.6x SuperLU's time.

Not in the default install because MKL's wheel is 230 MB (690 MB installed), which a user of the
handshake alone does not need. Once PARDISO has run, MKL's BLAS is among the process's global
symbols, so CHOLMOD run later in the same process may call it instead of its own: the same
answers to rounding (within 1e-11 N on a whole curve), not bit for bit.

The tangent is symmetric and almost always positive definite. One that is not (the
factorization reports it; a few iterations of a run as a pocket's roof buckles) is solved by
PARDISO's symmetric indefinite factorization, or without PARDISO by SuperLU in symmetric mode,
as the NumPy reference engine solves every tangent; or, where the run asks for it
(`softhand.fem.solver.IndentationSettings.indefinite_shift`), by the Cholesky of the tangent with
its diagonal raised (a Levenberg-Marquardt step: cheaper, and downhill in the step's energy).
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["SHIFT_TRIES", "SOLVERS", "TangentSystem", "pardiso_available", "resolve_solver"]

#: Most Cholesky tries of a shifted tangent, the shift 10x larger each (`TangentSystem.factorize`)
SHIFT_TRIES = 4

#: The sparse Cholesky behind `TangentSystem`: ``"auto"`` (PARDISO where it is installed, else
#: CHOLMOD), ``"cholmod"`` or ``"pardiso"``.
SOLVERS = ("auto", "cholmod", "pardiso")


def pardiso_available() -> bool:
    """Whether MKL PARDISO loads here (the ``softhand[mkl]`` extra: pypardiso and MKL)."""
    try:
        _Pardiso.library()
    except (ImportError, OSError):
        return False
    return True


def resolve_solver(solver: str) -> str:
    """The solver ``solver`` names, ``"auto"`` resolved.

    Raises:
        ValueError: an unknown name, or ``"pardiso"`` where it is not installed.
    """
    if solver not in SOLVERS:
        raise ValueError(f"solver = {solver!r}: allowed {', '.join(SOLVERS)}")
    if solver == "auto":
        return "pardiso" if pardiso_available() else "cholmod"
    if solver == "pardiso" and not pardiso_available():
        raise ValueError("solver = 'pardiso': MKL PARDISO is not installed here (install the "
                         "extra: pip install 'softhand[mkl]'; x86-64 Linux and Windows); "
                         "allowed here: auto, cholmod")
    return solver


class _NotPositiveDefiniteError(ArithmeticError):
    """The factorization met a pivot that is not positive."""


class _Cholmod:
    """CHOLMOD's supernodal Cholesky (CVXOPT) on the lower triangle in CSC; a tangent that is
    not positive definite goes to SuperLU in symmetric mode, as the NumPy reference engine
    solves every tangent."""

    #: the `TangentSystem.stats` key of `factorize_indefinite`
    indefinite = "superlu"

    def __init__(self) -> None:
        from cvxopt import cholmod, matrix, spmatrix

        self._cholmod, self._matrix, self._spmatrix = cholmod, matrix, spmatrix
        cholmod.options["supernodal"] = 2

    def analyse(self, n: int, rows: np.ndarray, cols: np.ndarray, indptr: np.ndarray) -> None:
        self._n, self._rows, self._indptr = n, rows, indptr
        probe = np.arange(rows.size, dtype=float) + 1.0
        matrix = self._matrix
        A = self._spmatrix(matrix(probe), matrix(rows), matrix(cols), (n, n))
        if not np.array_equal(np.asarray(A.V).ravel(), probe):  # CVXOPT keeps CSC order
            raise RuntimeError("CHOLMOD matrix does not keep the pattern's order")
        self._A = A
        self._symbolic = self._cholmod.symbolic(A, uplo="L")

    def factorize(self, vals: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        self._A.V = self._matrix(vals)  # A.V is a copy on reading: assign the whole
        try:
            self._cholmod.numeric(self._A, self._symbolic)
        except ArithmeticError as exc:
            raise _NotPositiveDefiniteError(str(exc)) from exc
        F, cholmod, matrix = self._symbolic, self._cholmod, self._matrix

        def solve(b: np.ndarray) -> np.ndarray:
            x = matrix(np.ascontiguousarray(b, dtype=float))
            cholmod.solve(F, x)
            return np.asarray(x).ravel()

        return solve

    def factorize_indefinite(self, vals: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        L = sp.csc_matrix((vals, self._rows, self._indptr), shape=(self._n, self._n))
        K = (L + L.T - sp.diags(L.diagonal())).tocsc()
        return spla.splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                         options={"SymmetricMode": True}).solve

    def close(self) -> None:
        pass


# mkl_service.h: MKL_THREADING_INTEL 0, SEQUENTIAL 1, PGI 2, GNU 3, TBB 4
_MKL_THREADING_SEQUENTIAL = 1
_MKL_THREADING_GNU = 3


class _Pardiso:
    """MKL PARDISO, called through ctypes on the library pypardiso loads, with MKL's default
    parameters (METIS nested-dissection ordering, one-based indices): real symmetric positive
    definite (``mtype = 2``), and for a tangent that is not, real symmetric indefinite
    (``mtype = -2``: Bunch-Kaufman pivoting, small pivots perturbed and the solution refined).
    The lower triangle in CSC is the upper triangle in CSR, the layout PARDISO takes, so the
    pattern's arrays serve as they are. MKL's threads are on GNU OpenMP (`library`), set for
    each call (``mkl_set_num_threads_local``) and put back after it."""

    indefinite = "indefinite"

    @staticmethod
    @functools.cache
    def library():
        import ctypes
        import ctypes.util

        from pypardiso.pardiso_wrapper import PyPardisoSolver

        loader = PyPardisoSolver(mtype=2)  # finds mkl_rt and declares pardiso's signature
        lib = loader.libmkl
        # One OpenMP runtime in the process: MKL's threads on GNU OpenMP, the runtime numba's
        # kernels run on. Its Intel layer would load Intel's runtime, whose GOMP entry points
        # then serve the whole process. The GNU layer finds libgomp among the process's global
        # symbols; without libgomp, MKL runs sequentially. Set before any other MKL call.
        try:
            ctypes.CDLL(ctypes.util.find_library("gomp") or "libgomp.so.1",
                        mode=ctypes.RTLD_GLOBAL)
            layer = _MKL_THREADING_GNU
        except OSError:
            layer = _MKL_THREADING_SEQUENTIAL
        if lib.MKL_Set_Threading_Layer(layer) != layer:
            lib.MKL_Set_Threading_Layer(_MKL_THREADING_SEQUENTIAL)
        return lib, loader._mkl_pardiso

    def __init__(self, threads: int) -> None:
        import ctypes

        self._ct = ctypes
        self._lib, self._call = self.library()
        self._threads = threads
        #: per matrix type, PARDISO's handle (its internal pointers) once analysed
        self._handles: dict[int, np.ndarray] = {}
        self._iparm = {2: np.zeros(64, dtype=np.int32), -2: np.zeros(64, dtype=np.int32)}

    def _run(self, mtype: int, phase: int, vals: np.ndarray,
             b: np.ndarray | None = None) -> np.ndarray:
        ct = self._ct
        i32, f64 = ct.POINTER(ct.c_int32), ct.POINTER(ct.c_double)
        rhs = np.zeros(self._n) if b is None else np.ascontiguousarray(b, dtype=float)
        x = np.zeros(self._n)
        err = ct.c_int32(0)
        pt = self._handles.setdefault(mtype, np.zeros(64, dtype=np.int64))
        before = self._lib.MKL_Set_Num_Threads_Local(self._threads)
        try:
            self._call(pt.ctypes.data_as(ct.POINTER(ct.c_int64)),
                       ct.byref(ct.c_int32(1)), ct.byref(ct.c_int32(1)),
                       ct.byref(ct.c_int32(mtype)), ct.byref(ct.c_int32(phase)),
                       ct.byref(ct.c_int32(self._n)), vals.ctypes.data_as(f64),
                       self._ia.ctypes.data_as(i32), self._ja.ctypes.data_as(i32),
                       self._perm.ctypes.data_as(i32), ct.byref(ct.c_int32(1)),
                       self._iparm[mtype].ctypes.data_as(i32), ct.byref(ct.c_int32(0)),
                       rhs.ctypes.data_as(f64), x.ctypes.data_as(f64), ct.byref(err))
        finally:
            self._lib.MKL_Set_Num_Threads_Local(before)
        if err.value == -4 and phase == 22 and mtype == 2:
            raise _NotPositiveDefiniteError("PARDISO: zero or negative pivot")
        if err.value != 0:
            raise RuntimeError(f"PARDISO (mtype {mtype}) phase {phase} failed with error "
                               f"{err.value}")
        return x

    def analyse(self, n: int, rows: np.ndarray, cols: np.ndarray, indptr: np.ndarray) -> None:
        self.close()
        self._n = n
        self._ia = (indptr + 1).astype(np.int32)
        self._ja = (rows + 1).astype(np.int32)
        self._perm = np.zeros(n, dtype=np.int32)
        self._vals = np.ones(rows.size)
        self._run(2, 11, self._vals)

    def _factorize(self, mtype: int, vals: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        if mtype not in self._handles:  # the indefinite type's analysis, on first use
            self._run(mtype, 11, self._vals)
        self._vals = np.ascontiguousarray(vals, dtype=float)  # PARDISO keeps a pointer to it
        self._run(mtype, 22, self._vals)

        def solve(b: np.ndarray) -> np.ndarray:
            return self._run(mtype, 33, self._vals, b)

        return solve

    def factorize(self, vals: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        return self._factorize(2, vals)

    def factorize_indefinite(self, vals: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        return self._factorize(-2, vals)

    def close(self) -> None:
        """Free PARDISO's memory (phase -1)."""
        for mtype in list(self._handles):
            self._run(mtype, -1, self._vals)
            del self._handles[mtype]


def _point_pairs(G: sp.csr_matrix, fmap: np.ndarray):
    """Per contact point, the pairs of its entries on free dofs that fall in the lower
    triangle: (point, entry a, entry b, row, column), grouped by point (CSR-like ``ptr``)."""
    G = G.tocsr()
    lengths = np.diff(G.indptr)
    pts, ia, ib = [], [], []
    for m in np.unique(lengths):
        if m == 0:
            continue
        rows = np.flatnonzero(lengths == m)
        ent = G.indptr[rows][:, None] + np.arange(m)  # (k, m) entry indices
        a, b = np.meshgrid(np.arange(m), np.arange(m), indexing="ij")
        a, b = a.ravel(), b.ravel()
        pts.append(np.repeat(rows, a.size))
        ia.append(ent[:, a].ravel())
        ib.append(ent[:, b].ravel())
    if not pts:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty, empty, empty, np.zeros(G.shape[0] + 1, dtype=np.int64)
    pt, ia, ib = np.concatenate(pts), np.concatenate(ia), np.concatenate(ib)
    r, c = fmap[G.indices[ia]], fmap[G.indices[ib]]
    keep = (r >= 0) & (c >= 0) & (r >= c)
    pt, ia, ib, r, c = pt[keep], ia[keep], ib[keep], r[keep], c[keep]
    order = np.argsort(pt, kind="stable")
    pt, ia, ib, r, c = pt[order], ia[order], ib[order], r[order], c[order]
    ptr = np.searchsorted(pt, np.arange(G.shape[0] + 1))
    return pt, ia, ib, r, c, ptr


class TangentSystem:
    """The lower triangle of the free-free tangent in a pattern fixed while the contact stays.

    The pattern holds the elements' couplings and those of the contact points it was analysed
    for. A contact set whose couplings all lie inside the elements' pattern (a plate or a
    round indenter on the outer faces) costs no fill and is in from the start; one that couples
    far dofs (the pocket: roof to floor) adds a point only once it closes, and the symbolic
    analysis is redone then (a few times a run: the pocket's couplings add a third to the
    factor when all are in, so a run does not pay for them before the pocket closes).

    Args:
        rows, cols: the elements' full pattern (one entry per stored value of the assembler's
            tangent data, ``tangent_of(raw=True)`` of `Assembler.evaluate`).
        free: the free dofs, sorted.
        n_dofs: all dofs.
        contacts: one template gap matrix per contact set (CSR, points x dofs); each later
            gap matrix of that set must have the same structure (the same rows and columns,
            values free).
        entries: for each entry of the element data `values` takes, the index of the
            pattern's value (``rows``, ``cols``) it adds to (the compiled element tangents,
            `Assembler.pattern`); None: the element data are the pattern's values themselves.
        solver: one of `SOLVERS`.
        threads: PARDISO's threads (CHOLMOD here runs on one).
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, free: np.ndarray, n_dofs: int,
                 contacts: list[sp.csr_matrix], entries: np.ndarray | None = None,
                 solver: str = "auto", threads: int = 1) -> None:
        self.solver = resolve_solver(solver)
        self._backend = _Pardiso(threads) if self.solver == "pardiso" else _Cholmod()
        fmap = np.full(n_dofs, -1, dtype=np.int64)
        fmap[free] = np.arange(free.size)
        n = free.size
        self.n = n
        r, c = fmap[rows], fmap[cols]
        keep = (r >= 0) & (c >= 0) & (r >= c)
        self._src = np.flatnonzero(keep)
        self._n_pattern = rows.size
        self._entries = (np.arange(rows.size) if entries is None
                         else np.asarray(entries, dtype=np.int64))
        self._element_keys = c[keep] * n + r[keep]  # column-major: CSC order of the lower part
        self._fmap = fmap
        self._contacts = [_point_pairs(G, fmap) for G in contacts]
        self._contact_nnz = [G.nnz for G in contacts]
        self._pair_keys = [p[4] * n + p[3] for p in self._contacts]
        self._key_order = np.argsort(self._element_keys)  # the element keys are distinct
        self._sorted_keys = self._element_keys[self._key_order]
        #: per contact set, the points the pattern holds
        self._active = [np.full(G.shape[0], bool(self._in_elements(k).all()))
                        for G, k in zip(contacts, self._pair_keys, strict=True)]
        #: factorizations: Cholesky, PARDISO's symmetric indefinite LDL^T, SuperLU's LU (each
        #: after a failed Cholesky), shifted Cholesky (`factorize`); and symbolic analyses of
        #: the pattern
        self.stats = {"cholesky": 0, "indefinite": 0, "superlu": 0, "shifted": 0,
                      "analyses": 0}
        self._analyse()

    def _analyse(self) -> None:
        """The pattern of the elements and the active contact points, and its symbolic
        Cholesky factorization."""
        n = self.n
        chosen = [active[p[0]] for active, p in zip(self._active, self._contacts, strict=True)]
        picked = [k[sel] for k, sel in zip(self._pair_keys, chosen, strict=True)]
        # the sorted union of the element keys (sorted once) and the contact keys they lack
        extra = np.concatenate([np.zeros(0, dtype=np.int64)] + picked)
        extra = np.unique(extra[~self._in_elements(extra)])
        ukeys = np.insert(self._sorted_keys,
                          np.searchsorted(self._sorted_keys, extra), extra)
        self.nnz = ukeys.size
        self._ukeys = ukeys
        inv = np.empty(self._element_keys.size, dtype=np.int64)
        inv[self._key_order] = (np.arange(self._sorted_keys.size)
                                + np.searchsorted(extra, self._sorted_keys))
        to_vals = np.full(self._n_pattern, -1, dtype=np.int64)  # pattern value -> lower value
        to_vals[self._src] = inv
        self._entry_dst = to_vals[self._entries]
        self._contact_dst = []
        for sel, keys in zip(chosen, picked, strict=True):
            dst = np.full(sel.size, -1, dtype=np.int64)
            dst[sel] = np.searchsorted(ukeys, keys)
            self._contact_dst.append(dst)
        self._rows = (ukeys % n).astype(np.int64)
        self._cols = (ukeys // n).astype(np.int64)
        self._indptr = np.searchsorted(self._cols, np.arange(n + 1))
        if not np.array_equal(self._rows[self._indptr[:-1]], np.arange(n)):
            raise RuntimeError("the tangent's pattern lacks a diagonal entry")  # every free
            # dof is in an element, so its diagonal is in the elements' pattern
        self._backend.analyse(n, self._rows, self._cols, self._indptr)
        self.stats["analyses"] += 1

    def set_contact(self, i: int, G: sp.csr_matrix) -> None:
        """Give contact set ``i`` a new structure (a sliding contact whose points now couple
        other dofs: `softhand.fem.contact.PocketContact`), the same points. A point stays in
        the pattern where the pattern holds all its new couplings; one that does not is added
        when it is next closed (`values`: a new symbolic analysis)."""
        pairs = _point_pairs(G, self._fmap)
        keys = pairs[4] * self.n + pairs[3]
        at = np.minimum(np.searchsorted(self._ukeys, keys), self._ukeys.size - 1)
        held = self._ukeys[at] == keys
        whole = np.ones(G.shape[0], dtype=bool)
        np.logical_and.at(whole, pairs[0], held)
        self._contacts[i], self._contact_nnz[i], self._pair_keys[i] = pairs, G.nnz, keys
        self._active[i] &= whole
        sel = self._active[i][pairs[0]]
        dst = np.full(sel.size, -1, dtype=np.int64)
        dst[sel] = at[sel]
        self._contact_dst[i] = dst

    def _in_elements(self, keys: np.ndarray) -> np.ndarray:
        """Which of ``keys`` the elements' lower triangle holds."""
        at = np.minimum(np.searchsorted(self._sorted_keys, keys), self._sorted_keys.size - 1)
        return self._sorted_keys[at] == keys

    def values(self, element_data: np.ndarray,
               contacts: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
        """The lower triangle's values: the elements' tangent data (``entries`` of the
        constructor), summed straight into it, plus, per contact set,
        ``(kw, G_data)``: each point's penalty stiffness ``eps * w * [g < 0]`` and its gap
        matrix's values (in the template's structure). A closed point the pattern does not
        hold yet is added to it first (a new symbolic analysis)."""
        from softhand.fem.kernels import scatter_add

        if element_data.size != self._entries.size:
            raise ValueError(f"element data has {element_data.size} entries, the pattern's "
                             f"map {self._entries.size}")
        closed = [np.flatnonzero(kw) for kw, _ in contacts]
        new = False
        for active, idx in zip(self._active, closed, strict=True):
            if not active[idx].all():
                active[idx] = True
                new = True
        if new:
            self._analyse()
        vals = np.zeros(self.nnz)
        scatter_add(vals, self._entry_dst, np.ascontiguousarray(element_data, dtype=float))
        for (pt, ia, ib, _, _, ptr), dst, nnz, (kw, gdata), idx in zip(
                self._contacts, self._contact_dst, self._contact_nnz, contacts, closed,
                strict=True):
            if gdata.size != nnz:
                raise ValueError(f"a gap matrix has {gdata.size} entries, its template {nnz}")
            if idx.size == 0:
                continue
            counts = ptr[idx + 1] - ptr[idx]
            sel = np.repeat(ptr[idx] - np.cumsum(np.r_[0, counts[:-1]]), counts) \
                + np.arange(counts.sum())
            vals += np.bincount(dst[sel], weights=kw[pt[sel]] * gdata[ia[sel]] * gdata[ib[sel]],
                                minlength=self.nnz)
        return vals

    def factorize(self, vals: np.ndarray, *, shift: float | None = None
                  ) -> Callable[[np.ndarray], np.ndarray]:
        """A function that solves K x = b for the symmetric K of lower triangle ``vals``,
        valid until the next call.

        ``shift``: for a K that is not positive definite, first try the Cholesky of
        ``K + mu I`` with ``mu = shift * mean|diag K|``, mu times 10 up to `SHIFT_TRIES` times,
        before the indefinite factorization: the solve is then that of the shifted K (a
        Levenberg-Marquardt step, a descent direction of the step's energy; each try costs
        one Cholesky, against about 3 for SuperLU's LU). Counted under ``stats["shifted"]``.
        """
        try:
            solve = self._backend.factorize(vals)
        except _NotPositiveDefiniteError:
            self.stats[self._backend.indefinite] += 1
            if shift is not None:
                diag = self._indptr[:-1]  # each column's first entry: its diagonal (_analyse)
                mu = shift * float(np.abs(vals[diag]).mean())
                for _ in range(SHIFT_TRIES):
                    shifted = vals.copy()
                    shifted[diag] += mu
                    try:
                        solve = self._backend.factorize(shifted)
                    except _NotPositiveDefiniteError:
                        mu *= 10.0
                        continue
                    self.stats["shifted"] += 1
                    return solve
            return self._backend.factorize_indefinite(vals)
        self.stats["cholesky"] += 1
        return solve

    def close(self) -> None:
        """Free the factorization's memory held outside Python (PARDISO's)."""
        self._backend.close()
