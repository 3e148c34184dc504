"""Exact checks of the FE assembly: patch tests and the consistent tangent.

Patch test: on a block of distorted quadratic elements, prescribing u = (F - I) X on the boundary
must give u = (F - I) X inside and the closed-form hyperfoam stress at every Gauss point.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from softhand.fem.assembly import Assembler
from softhand.fem.contact import plate_gaps, pocket_gaps
from softhand.fem.elements import reference_element
from softhand.fem.geometry import parse_design
from softhand.fem.materials import material
from softhand.fem.mesh import MESH_LEVELS, Mesh, build_mesh


def _block_mesh(dim: int, n: int = 2, seed: int = 0) -> Mesh:
    """n^dim quadratic elements on the unit block, interior nodes moved at random."""
    m = 2 * n + 1
    axes = [np.linspace(0.0, 1.0, m)] * dim
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    ids = np.arange(m**dim).reshape((m,) * dim)
    rng = np.random.default_rng(seed)
    interior = np.all((grid > 1e-12) & (grid < 1 - 1e-12), axis=1)
    grid[interior] += rng.uniform(-0.06, 0.06, size=(interior.sum(), dim))
    elems = []
    for e in np.ndindex(*(n,) * dim):
        local = []
        for p in np.ndindex(*(3,) * dim):
            p = p[::-1]  # p0 fastest
            local.append(ids[tuple(2 * e[k] + p[k] for k in range(dim))])
        elems.append(local)
    boundary = np.flatnonzero(~interior)
    fixed = (boundary[:, None] * dim + np.arange(dim)).ravel()
    empty = np.zeros((0, 3 ** (dim - 1)), dtype=int)
    return Mesh(dim=dim, X=grid, elements=np.array(elems), layer=np.zeros(len(elems), int),
                ref=reference_element(dim), fixed=fixed, outer_faces=empty, roof_faces=empty,
                floor_faces=empty, symmetry_factor=1.0, length_mm=1.0)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("name", ["sil", "pu"])
def test_patch_test_recovers_homogeneous_finite_strain(dim, name):
    """Distorted Q9/Q27 patch: interior u = (F-I)X to 1e-9 mm and S = closed form to 1e-9 rel."""
    mesh = _block_mesh(dim)
    mat = material(name, elastic_only=True)
    asm = Assembler(mesh, [mat])
    Fh = np.eye(3)
    block = np.eye(dim) + np.array([[0.15, 0.05, -0.02], [-0.04, -0.2, 0.03],
                                    [0.01, 0.02, 0.1]])[:dim, :dim]
    # J = 1.003: large shear and stretch, small volume change (SIL's J^(-alpha beta) has
    # alpha beta = 380, so a few % of volume change is a GPa stress)
    Fh[:dim, :dim] = block * (1.003 / np.linalg.det(block)) ** (1.0 / dim)
    exact = (mesh.X @ (Fh[:dim, :dim] - np.eye(dim)).T).ravel()
    free = np.setdiff1d(np.arange(mesh.n_dofs), mesh.fixed)
    u = exact.copy()
    u[free] += 1e-4 * np.random.default_rng(3).standard_normal(free.size)  # start off the answer
    state = asm.initial_state()
    for _ in range(20):
        f, K, _ = asm.assemble(u, state, 0.0)
        if np.abs(f[free]).max() < 1e-13:
            break
        u[free] -= spla.spsolve(K[free][:, free].tocsc(), f[free])
    assert np.abs(u - exact).max() < 1e-9
    C = Fh.T @ Fh
    S_exact = mat.hyperfoam.stress(C[None], tangent=False)[0]
    F = asm.deformation_gradient(u).reshape(-1, 3, 3)
    S = mat.hyperfoam.stress(np.einsum("nki,nkj->nij", F, F), tangent=False)
    assert np.abs(S - S_exact).max() <= 1e-9 * np.abs(S_exact).max()


@pytest.mark.parametrize("mode", ["2d", "3d"])
def test_tangent_matches_finite_differences_with_viscoelastic_history(mode):
    """Assembled K v equals the central difference of the internal force to 1e-6 (relative)."""
    design = parse_design("pocket2-pu-sil")
    mesh = build_mesh(design.geometry(), MESH_LEVELS["coarse"], dim=2 if mode == "2d" else 3)
    asm = Assembler(mesh, [material("pu"), material("sil")])
    rng = np.random.default_rng(1)
    X = mesh.X
    u = np.zeros_like(X)  # smooth, nearly isochoric squeeze with shear
    u[:, 0] = 0.04 * X[:, 0] * X[:, 1] / 9.0 + 0.02 * np.sin(0.4 * X[:, 1])
    u[:, 1] = -0.04 * X[:, 1] ** 2 / 18.0
    u = u.ravel()
    u[mesh.fixed] = 0.0
    state = asm.initial_state()
    _, _, state = asm.assemble(0.5 * u, state, 0.3)  # some history
    v = rng.standard_normal(mesh.n_dofs)
    _, K, _ = asm.assemble(u, state, 0.2)
    h = 1e-6
    fp, _, _ = asm.assemble(u + h * v, state, 0.2, tangent=False)
    fm, _, _ = asm.assemble(u - h * v, state, 0.2, tangent=False)
    fd = (fp - fm) / (2 * h)
    assert np.abs(K @ v - fd).max() <= 1e-6 * np.abs(fd).max()
    assert abs(K - K.T).max() <= 1e-10 * abs(K).max()


def test_contact_tangent_and_force_are_consistent():
    """Penalty contact: K_c v equals the difference of r_c; force equals the plate residual sum."""
    design = parse_design("pocket2-sil")
    mesh = build_mesh(design.geometry(), MESH_LEVELS["coarse"], dim=2)
    plate, pocket = plate_gaps(mesh, 9.0), pocket_gaps(mesh)
    assert pocket is not None and pocket.size > 0
    u = np.zeros(mesh.n_dofs)
    u[1::2] = -0.3 * mesh.X[:, 1] / 9.0  # squeeze: closes plate contact near the top
    gaps = pocket.gaps(u)
    assert np.allclose(pocket.g0, 2.0, atol=1e-3)  # pocket height (quadratic geometry)
    v = np.random.default_rng(2).standard_normal(mesh.n_dofs) * 1e-9
    for gs, shift in ((plate, -0.5), (pocket, -2.05)):
        r0, kw, n_closed = gs.penalty_forces(u, 1000.0, shift)
        r1, _, _ = gs.penalty_forces(u + v, 1000.0, shift)
        assert n_closed > 0
        assert np.allclose(r1 - r0, gs.stiffness(kw) @ v, rtol=1e-6, atol=1e-12)
    r, _, _ = plate.penalty_forces(u, 1000.0, -0.5)
    assert plate.force(u, 1000.0, -0.5) == pytest.approx(r[1::2].sum(), rel=1e-12)
    assert gaps.min() > 0.0
