"""The compiled FE engine (numba kernels, CHOLMOD on a fixed pattern) against the NumPy
reference: the same element arithmetic to rounding, the same curves within the Newton
tolerance, and the linear algebra against SciPy's direct solve."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from softhand.fem.assembly import Assembler
from softhand.fem.geometry import parse_design
from softhand.fem.kernels import sym_eig3
from softhand.fem.linear import TangentSystem, pardiso_available
from softhand.fem.materials import material
from softhand.fem.mesh import build_mesh
from softhand.fem.solver import IndentationSettings, indent


def _smooth_field(X: np.ndarray, seed: int) -> np.ndarray:
    """A smooth finite-strain displacement (a few percent strain, rotations included)."""
    rng = np.random.default_rng(seed)
    dim = X.shape[1]
    M = rng.normal(scale=0.05, size=(dim, dim))
    wave = 0.05 * np.sin(0.7 * X[:, :1] + 0.3 * X[:, 1:2])
    return (X @ M + wave).ravel()


@pytest.mark.parametrize("dim", [2, 3])
def test_compiled_elements_equal_the_numpy_reference_to_rounding(dim):
    """Internal force, tangent and Prony history after two viscous steps, both layers (PU
    inner, silicone outer: both materials' Prony series)."""
    design = parse_design("pocket2-pu-sil")
    mesh = build_mesh(design.geometry(), IndentationSettings().mesh_spec, dim=dim)
    mats = [material(design.inner), material(design.outer)]
    ref = Assembler(mesh, mats, threads=1, engine="numpy")
    new = Assembler(mesh, mats, threads=2, engine="compiled")
    u1 = _smooth_field(mesh.X, 0)
    free = np.flatnonzero(~np.isin(np.arange(mesh.n_dofs), mesh.fixed))
    s_ref, s_new = ref.initial_state(), new.initial_state()
    for u, dt in ((u1, 0.1), (1.3 * u1, 0.05)):
        f_ref, K_ref, s_ref = ref.evaluate(u, s_ref, dt)
        f_new, K_new, s_new = new.evaluate(u, s_new, dt)
        scale = np.abs(f_ref).max()
        assert np.abs(f_new - f_ref).max() <= 1e-11 * scale
    Kr, Kn = K_ref(free), K_new(free)
    assert abs(Kn - Kr).max() <= 1e-11 * abs(Kr).max()
    for a, b in zip(s_ref.groups, s_new.groups, strict=True):
        assert np.abs(b.S0 - a.S0).max() <= 1e-11 * np.abs(a.S0).max()
        assert np.abs(b.H - a.H).max() <= 1e-11 * np.abs(a.H).max()
    ref.close()
    new.close()


def test_inverted_elements_are_refused_by_both_engines():
    design = parse_design("solid-sil")
    mesh = build_mesh(design.geometry(), IndentationSettings().mesh_spec, dim=2)
    mats = [material(design.inner), material(design.outer)]
    u = np.zeros_like(mesh.X)
    u[:, 0] = -1.5 * mesh.X[:, 0]  # x -> -0.5 x: every element mirrored, det F < 0
    u = u.ravel()
    for engine in ("numpy", "compiled"):
        asm = Assembler(mesh, mats, threads=1, engine=engine)
        with pytest.raises(FloatingPointError, match="det F <= 0"):
            asm.evaluate(u, asm.initial_state(), 0.1)


@pytest.mark.parametrize("kind", ["distinct", "double", "triple", "tiny-gap"])
def test_jacobi_eigenpairs_reconstruct_the_matrix(kind):
    rng = np.random.default_rng(1)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    lam = {"distinct": [0.7, 1.0, 1.9], "double": [1.2, 1.2, 0.8], "triple": [1.1, 1.1, 1.1],
           "tiny-gap": [1.0, 1.0 + 1e-9, 1.3]}[kind]
    A = Q @ np.diag(lam) @ Q.T
    A = 0.5 * (A + A.T)
    w, V = np.empty(3), np.empty((3, 3))
    sym_eig3(A, w, V)
    assert np.allclose(V.T @ V, np.eye(3), atol=1e-14)
    assert np.allclose(V @ np.diag(w) @ V.T, A, atol=1e-14)
    assert np.allclose(np.sort(w), np.sort(lam), rtol=1e-13)


needs_pardiso = pytest.mark.skipif(not pardiso_available(),
                                   reason="MKL PARDISO is not installed (extra softhand[mkl])")
SOLVER_CASES = ["cholmod", pytest.param("pardiso", marks=needs_pardiso)]


@pytest.mark.parametrize("solver", SOLVER_CASES)
def test_tangent_system_solves_like_scipy_and_falls_back_when_indefinite(solver):
    rng = np.random.default_rng(2)
    n = 60
    B = sp.random(n, n, density=0.08, random_state=3, format="csr")
    K = (B @ B.T + sp.identity(n) * 0.5).tocsr()
    rows, cols = K.nonzero()
    G = sp.csr_matrix((rng.normal(size=8), (np.arange(4).repeat(2), rng.integers(0, n, 8))),
                      shape=(4, n))
    free = np.arange(n)
    system = TangentSystem(rows, cols, free, n, [G], solver=solver)
    assert system.solver == solver
    data = np.asarray(K[rows, cols]).ravel()
    kw = np.array([2.0, 0.0, 3.0, 0.0])
    vals = system.values(data, [(kw, G.data)])
    b = rng.normal(size=n)
    full = K + G.T @ sp.diags(kw) @ G
    x = system.factorize(vals)(b)
    assert np.allclose(x, spla.spsolve(full.tocsc(), b), rtol=1e-10, atol=1e-12)
    assert system.stats == {"cholesky": 1, "indefinite": 0, "superlu": 0, "shifted": 0,
                            "analyses": 2}
    # an indefinite tangent (a negative pivot) is solved by LU instead
    shifted = K - sp.identity(n) * (0.5 + 2.0 * spla.eigsh(B @ B.T, 1, which="SA")[0][0] + 1.0)
    data = np.asarray(shifted.tocsr()[rows, cols]).ravel()
    x = system.factorize(system.values(data, [(np.zeros(4), G.data)]))(b)
    assert np.allclose(shifted @ x, b, atol=1e-8)
    # CHOLMOD hands it to SuperLU, PARDISO to its own symmetric indefinite factorization
    fallback = "superlu" if solver == "cholmod" else "indefinite"
    assert system.stats[fallback] == 1 and system.stats["cholesky"] == 1
    system.close()


@pytest.mark.parametrize("solver", SOLVER_CASES)
def test_a_shifted_tangent_is_the_tangent_plus_mu_times_the_identity(solver):
    """K = [[1, 2], [2, 1]] (eigenvalues 3 and -1, mean |diagonal| 1): with shift 0.02 the tries
    are K + 0.02 I, 0.2 I, 2 I, the third the first positive definite; with 1e-4 none of the 4
    tries (up to 0.1 I) is, and the indefinite factorization solves K itself."""
    K = np.array([[1.0, 2.0], [2.0, 1.0]])
    rows, cols = np.nonzero(np.ones((2, 2)))
    b = np.array([1.0, -3.0])
    system = TangentSystem(rows, cols, np.arange(2), 2, [], solver=solver)
    vals = system.values(K[rows, cols], [])
    x = system.factorize(vals, shift=2e-2)(b)
    assert np.allclose(x, np.linalg.solve(K + 2.0 * np.eye(2), b), rtol=1e-12)
    assert system.stats["shifted"] == 1 and system.stats["cholesky"] == 0
    x = system.factorize(vals, shift=1e-4)(b)
    assert np.allclose(x, np.linalg.solve(K, b), rtol=1e-10)
    assert system.stats["shifted"] == 1
    assert system.stats["superlu" if solver == "cholmod" else "indefinite"] == 2
    system.close()


def test_the_solver_is_checked_before_any_work(monkeypatch):
    import softhand.fem.linear as linear

    with pytest.raises(ValueError, match="solver = 'lu': allowed auto, cholmod, pardiso"):
        IndentationSettings(solver="lu")
    monkeypatch.setattr(linear, "pardiso_available", lambda: False)
    with pytest.raises(ValueError, match=r"solver = 'pardiso': MKL PARDISO is not installed"):
        IndentationSettings(solver="pardiso")
    assert linear.resolve_solver("auto") == "cholmod"


@pytest.mark.parametrize("solver", SOLVER_CASES)
@pytest.mark.parametrize(("design", "indenter"), [("pocket2-sil", "plate"),
                                                  ("pocket1-pu-sil", "plate"),
                                                  ("solid-sil", "cylinder:9@0")])
def test_compiled_curves_equal_the_reference_within_the_newton_tolerance(design, indenter,
                                                                         solver):
    """Whole 2D runs, ramp and hold: the same steps, iterations and forces, on each sparse
    solver."""
    runs = {e: indent(design, IndentationSettings(mode="2d", hold_s=2.0, indenter=indenter,
                                                  engine=e, threads=1, solver=solver))
            for e in ("numpy", "compiled")}
    ref, new = runs["numpy"], runs["compiled"]
    assert (ref.linear_solver, new.linear_solver) == ("superlu", solver)
    assert new.summary()["linear_solver"] == solver
    assert [r["iterations"] for r in new.log] == [r["iterations"] for r in ref.log]
    assert new.time_s.shape == ref.time_s.shape
    tol = IndentationSettings().tol_N + IndentationSettings().tol_rel * np.abs(ref.force_N)
    assert np.all(np.abs(new.force_N - ref.force_N) <= tol)
    assert np.allclose(new.displacement_mm, ref.displacement_mm, rtol=0, atol=1e-9)


def test_the_engine_is_checked_and_not_a_curve_setting():
    from softhand.fem.sweep import _settings_of

    with pytest.raises(ValueError, match="engine = 'fast'"):
        IndentationSettings(engine="fast")
    assert "engine" not in _settings_of(IndentationSettings(engine="numpy"))


def test_element_entries_sum_into_the_tangent_as_bincount_does():
    """The compiled engine hands the solver unassembled element tangents: their sum in the
    lower triangle equals the assembled pattern's values bit for bit, and the backtracking's
    inversion count equals NumPy's determinant test."""
    spec = IndentationSettings(mesh="coarse").mesh_spec
    mesh = build_mesh(parse_design("pocket2-sil").geometry(), spec, dim=3)
    mats = [material("sil"), material("sil")]
    asm = Assembler(mesh, mats, threads=1, engine="compiled")
    rng = np.random.default_rng(4)
    u = 0.02 * rng.normal(size=mesh.n_dofs)
    _, tangent_of, _ = asm.evaluate(u, asm.initial_state(), 0.1)
    rows, cols, entries = asm.pattern()
    raw = tangent_of(raw=True)
    assert raw.size == entries.size
    data = np.bincount(entries, weights=raw, minlength=rows.size)
    free = np.setdiff1d(np.arange(mesh.n_dofs), mesh.fixed)
    by_entries = TangentSystem(rows, cols, free, mesh.n_dofs, [], entries).values(raw, [])
    by_pattern = TangentSystem(rows, cols, free, mesh.n_dofs, []).values(data, [])
    assert np.array_equal(by_entries, by_pattern)
    full = tangent_of(free).toarray()
    lower = sp.csc_matrix((by_entries, *_lower_pattern(rows, cols, free, mesh.n_dofs)),
                          shape=full.shape).toarray()
    assert np.allclose(np.tril(full), lower, rtol=0, atol=1e-12 * np.abs(full).max())
    for scale in (0.02, 3.0):  # none inverted; most inverted
        v = scale * rng.normal(size=mesh.n_dofs)
        with np.errstate(over="ignore", invalid="ignore"):
            expect = int((~(np.linalg.det(asm.deformation_gradient(v)) > 0)).sum())
        assert asm.inverted(v) == expect
        assert (expect == 0) == (scale < 1)


def _lower_pattern(rows, cols, free, n):
    """CSC row indices and column pointers of the free-free lower triangle of a pattern."""
    fmap = np.full(n, -1)
    fmap[free] = np.arange(free.size)
    r, c = fmap[rows], fmap[cols]
    keep = (r >= 0) & (c >= 0) & (r >= c)
    keys = np.unique(c[keep] * free.size + r[keep])
    return keys % free.size, np.searchsorted(keys // free.size, np.arange(free.size + 1))


@needs_pardiso
def test_pardiso_and_cholmod_give_the_same_3d_curve_through_indefinite_tangents(monkeypatch):
    """pocket2-sil (3D, coarse) meets tangents that are not positive definite as the pocket's
    roof gives way: PARDISO's indefinite factorization takes them where CHOLMOD hands them to
    SuperLU, and the curves agree to rounding with the same Newton iterations."""
    import softhand.fem.linear as linear

    calls = {"indefinite": 0}
    original = linear._Pardiso.factorize_indefinite

    def counted(self, vals):
        calls["indefinite"] += 1
        return original(self, vals)

    monkeypatch.setattr(linear._Pardiso, "factorize_indefinite", counted)
    runs = {s: indent("pocket2-sil", IndentationSettings(mesh="coarse", hold_s=0, solver=s))
            for s in ("cholmod", "pardiso")}
    a, b = runs["cholmod"], runs["pardiso"]
    assert calls["indefinite"] >= 1
    assert [r["iterations"] for r in a.log] == [r["iterations"] for r in b.log]
    assert np.allclose(a.force_N, b.force_N, rtol=0, atol=1e-9)
    assert np.allclose(a.displacement_mm, b.displacement_mm, rtol=0, atol=1e-9)
