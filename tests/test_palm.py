"""The palm model: its geometry's checks, its mesh, the finite plate and its exact answers.

Reference numbers (issue 22 item 2's report has the palm-against-phalanx table): the palm's
half length and mesh levels were chosen by the runs quoted in :mod:`softhand.fem.palm`
(PalmGeometry.half_length_mm, PALM_MESH_LEVELS); a laterally confined flat layer follows the
hyperfoam's uniaxial-strain law to the Newton tolerance (measured 4e-5 relative, 2D coarse).
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq

from softhand.fem.body import body_mesh, check_body
from softhand.fem.contact import plate_gaps
from softhand.fem.geometry import PhalanxGeometry, parse_design
from softhand.fem.materials import material, phi1
from softhand.fem.mesh import MESH_LEVELS, build_mesh, full_model
from softhand.fem.palm import (
    PALM_MESH_LEVELS,
    PALM_RANGES,
    PalmGeometry,
    PalmMeshSpec,
    bone_height,
    palm_mesh,
)
from softhand.fem.solver import IndentationSettings, indent

ELASTIC = dict(elastic_only=True, hold_s=0.0, threads=1, max_force_N=1e4)


def _det_j(mesh) -> np.ndarray:
    J = np.einsum("qnk,end->eqdk", mesh.ref.dN, mesh.X[mesh.elements])
    return np.linalg.det(J)


# --- geometry ---------------------------------------------------------------------------------
@pytest.mark.parametrize("field, value, words", [
    ("spacing_mm", 30.0, "spacing_mm = 30.0: expected a finite number in [14, 26]"),
    ("spacing_mm", "20", "spacing_mm = '20': expected a finite number"),
    ("bone_rise_mm", -1.0, "bone_rise_mm = -1.0: expected a finite number in [0, 8]"),
    ("bone_half_width_mm", float("nan"), "bone_half_width_mm = nan: expected"),
    ("skin_mm", 25.0, "skin_mm = 25.0: expected a finite number in [4.5, 20]"),
    ("half_length_mm", 5.0, "half_length_mm = 5.0: expected a finite number in [10, 50]"),
    ("side_cells", 1.5, "side_cells = 1.5: expected an integer in [0, 3]"),
    ("side_cells", True, "side_cells = True: expected an integer"),
])
def test_a_bad_field_is_refused_naming_it_its_value_and_range(field, value, words):
    with pytest.raises(ValueError) as exc:
        PalmGeometry(**{field: value})
    assert words in str(exc.value)


def test_the_fields_must_fit_together():
    with pytest.raises(ValueError, match=r"bone_half_width_mm = 4.0: allowed range \[2.5, 3.5\] "
                                         r"at spacing_mm = 14"):
        PalmGeometry(spacing_mm=14.0, bone_half_width_mm=4.0)
    # the design's bands (pocket2: 1.4 roof + 2 pocket + 1 floor) over a 1 mm core
    with pytest.raises(ValueError, match=r"skin_mm = 5.0: allowed range \[5.4, 20\]"):
        palm_mesh("pocket2-sil", PalmGeometry(skin_mm=5.0))
    palm_mesh("pocket2-sil", PalmGeometry(skin_mm=5.4), "coarse")
    wide = PhalanxGeometry(width_mm=20.0, pocket_height_mm=2.0, pocket_half_width_mm=8.0)
    with pytest.raises(ValueError, match=r"pocket_half_width_mm = 8.0: allowed range \[0.5, 6.5\] "
                                         r"at spacing_mm = 14"):
        palm_mesh("pocket2-sil", PalmGeometry(spacing_mm=14.0, bone_half_width_mm=3.5),
                  layers=wide)


@pytest.mark.parametrize("kwargs, words", [
    (dict(dim=1), "dim = 1: allowed 2 (plane strain) or 3"),
    (dict(spec="uniform"), "spec = 'uniform': allowed coarse, default, fine"),
    (dict(plate_mm=(20.0, 0.0)), "plate_mm[1] = 0.0: expected a finite number in (0, 1000]"),
    (dict(plate_mm=20.0), "plate_mm = 20.0: expected (across, along)"),
])
def test_bad_mesh_arguments_are_refused(kwargs, words):
    with pytest.raises(ValueError) as exc:
        palm_mesh("solid-sil", **kwargs)
    assert words in str(exc.value)


def test_spec_counts_are_checked():
    with pytest.raises(ValueError, match="n_core = 0: expected an integer in"):
        PalmMeshSpec(n_core=0)
    with pytest.raises(ValueError, match=r"far_grading = 0.0: expected a finite number in \(0, 1\]"):
        PalmMeshSpec(far_grading=0.0)
    assert PALM_MESH_LEVELS["fine"].n_plate == 2 * PALM_MESH_LEVELS["default"].n_plate


def test_the_default_spacing_is_the_papers_hand_width_over_4_4():
    assert PalmGeometry().spacing_mm == pytest.approx(88.0 / 4.4)


def test_the_bone_is_a_smooth_bump_of_the_shafts_width():
    g = PalmGeometry()
    b = g.bone_half_width_mm
    assert bone_height(g, 0.0) == pytest.approx(g.bone_rise_mm)
    assert bone_height(g, b) == pytest.approx(0.5 * g.bone_rise_mm)  # 2b wide at half rise
    assert bone_height(g, 2 * b) == pytest.approx(0.0, abs=1e-12)
    x = np.linspace(0.0, g.spacing_mm / 2, 2001)
    slope = np.gradient(bone_height(g, x), x)
    assert np.abs(slope).max() == pytest.approx(g.max_slope, rel=1e-3)
    # the bones repeat every spacing
    np.testing.assert_allclose(bone_height(g, x + g.spacing_mm), bone_height(g, x), atol=1e-12)


# --- mesh -------------------------------------------------------------------------------------
def _corners():
    """Every corner of the ranges (the bone's half width at its largest allowed value)."""
    names = list(PALM_RANGES)
    for values in itertools.product(*(PALM_RANGES[n] for n in names)):
        kw = dict(zip(names, values, strict=True))
        kw["bone_half_width_mm"] = min(kw["bone_half_width_mm"], kw["spacing_mm"] / 4)
        yield kw


@pytest.mark.parametrize("design", ["solid-sil", "pocket2-sil"])
@pytest.mark.parametrize("dim", [2, 3])
def test_every_corner_of_the_ranges_meshes_with_positive_jacobians(design, dim):
    n = 0
    for kw in _corners():
        kw["skin_mm"] = max(kw["skin_mm"], 5.4)  # the default layers' bands over a 1 mm core
        for level in ("coarse", "default"):
            mesh = palm_mesh(design, PalmGeometry(**kw), level, dim=dim)
            assert _det_j(mesh).min() > 0, (kw, level)
            n += 1
    assert n == 64
    mesh = palm_mesh(design, PalmGeometry(side_cells=2), "default", dim=dim)
    assert _det_j(mesh).min() > 0


@pytest.mark.parametrize("design", ["solid-pu-sil", "pocket1-sil", "pocket2-sil-pu"])
@pytest.mark.parametrize("side_cells", [0, 1])
def test_layers_are_exact_under_the_flat_top(design, side_cells):
    g = PalmGeometry(side_cells=side_cells)
    layers = parse_design(design).geometry()
    mesh = palm_mesh(design, g, "coarse", dim=3)
    X, top = mesh.X, g.top_mm
    # the outer surface is the flat top, the whole modelled width and length
    np.testing.assert_allclose(X[mesh.outer_faces][..., 1], top, atol=1e-12)
    assert X[:, 1].max() == pytest.approx(top)
    np.testing.assert_allclose([X[:, 0].max(), X[:, 2].max()], [g.width_mm, g.half_length_mm])
    # the outer layer (layer 1) is exactly outer_layer_mm thick everywhere
    outer_y = X[mesh.elements[mesh.layer == 1]][..., 1]
    np.testing.assert_allclose(outer_y.min(axis=1), top - layers.outer_layer_mm, atol=1e-12)
    np.testing.assert_allclose(outer_y.max(axis=1), top, atol=1e-12)
    assert (X[mesh.elements[mesh.layer == 0]][..., 1].max(axis=1)
            <= top - layers.outer_layer_mm + 1e-12).all()
    # the pocket: roof and floor faces paired at the same (x, z), pocket_height_mm apart, over
    # each bone within pocket_half_width_mm, along the whole modelled length
    h = layers.pocket_height_mm
    if h == 0:
        assert mesh.roof_faces.size == mesh.floor_faces.size == 0
        return
    roof, floor = X[mesh.roof_faces], X[mesh.floor_faces]
    np.testing.assert_allclose(roof[..., 1], top - layers.pocket_roof_mm, atol=1e-12)
    np.testing.assert_allclose(floor[..., 1], top - layers.pocket_roof_mm - h, atol=1e-12)
    np.testing.assert_allclose(roof[..., [0, 2]], floor[..., [0, 2]], atol=1e-12)
    x = roof[..., 0]
    to_bone = np.abs(x - g.spacing_mm * np.round(x / g.spacing_mm))
    assert to_bone.max() == pytest.approx(layers.pocket_half_width_mm)
    assert roof[..., 2].max() == pytest.approx(g.half_length_mm)
    spec = PALM_MESH_LEVELS["coarse"]  # n_top columns on each side of each bone, every slice
    n_slices = spec.n_plate + spec.n_far
    assert mesh.roof_faces.shape[0] == (1 + 2 * side_cells) * spec.n_top * n_slices


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("side_cells", [0, 1])
def test_the_bone_is_fixed_and_the_sides_are_symmetry_planes(dim, side_cells):
    """The lowest node of every column lies on y_b(x) with all its dofs fixed; the planes x = 0
    and x = width (and z = 0, z = half_length in 3D) hold only their normal dof."""
    g = PalmGeometry(side_cells=side_cells)
    mesh = palm_mesh("pocket2-sil", g, "coarse", dim=dim)
    X = mesh.X
    bone = np.flatnonzero(np.isclose(X[:, 1], bone_height(g, X[:, 0]), atol=1e-12))
    columns = np.unique(X[:, [0, 2] if dim == 3 else [0]].round(9), axis=0)
    assert bone.size == columns.shape[0]  # one bone node under each column of nodes
    fixed = set(mesh.fixed.tolist())
    assert all({dim * a + c for c in range(dim)} <= fixed for a in bone)
    others = set(np.setdiff1d(np.arange(X.shape[0]), bone).tolist())
    held = [{a for a in others if dim * a + c in fixed} for c in range(dim)]
    on_x = set(np.flatnonzero(np.isclose(X[:, 0], 0.0) | np.isclose(X[:, 0], g.width_mm)))
    assert held[0] == on_x & others and held[1] == set()
    if dim == 3:
        on_z = np.isclose(X[:, 2], 0.0) | np.isclose(X[:, 2], g.half_length_mm)
        assert held[2] == set(np.flatnonzero(on_z)) & others


def test_the_2d_section_is_the_3d_mesh_at_z_0():
    g = PalmGeometry()
    m2, m3 = (palm_mesh("pocket2-sil", g, "default", dim=d) for d in (2, 3))
    at_0 = m3.X[np.isclose(m3.X[:, 2], 0.0)][:, :2]
    np.testing.assert_allclose(np.unique(m2.X.round(9), axis=0), np.unique(at_0.round(9), axis=0))
    assert (m2.symmetry_factor, m2.length_mm) == (2.0, 2 * g.half_length_mm)
    assert (m3.symmetry_factor, m3.length_mm) == (4.0, 1.0)


# --- the finite plate -------------------------------------------------------------------------
def test_a_finite_plate_presses_only_the_points_under_it():
    g = PalmGeometry()
    mesh = palm_mesh("solid-sil", g, "coarse", dim=3)  # the paper's 20 x 10 mm plate
    assert mesh.plate_half_mm == (10.0, 5.0)
    gaps = plate_gaps(mesh, g.top_mm)
    assert (np.abs(gaps.points[:, 2]) <= 5.0).all()
    assert gaps.weight.sum() == pytest.approx(10.0 * 5.0)  # the quarter of 20 x 10 mm
    mesh.plate_half_mm = None
    whole = plate_gaps(mesh, g.top_mm)
    assert whole.weight.sum() == pytest.approx(g.width_mm * g.half_length_mm)
    # a plate covering the modelled top needs no mask
    assert palm_mesh("solid-sil", g, "coarse", plate_mm=(20.0, 70.0)).plate_half_mm is None
    assert palm_mesh("solid-sil", g, "coarse", dim=2, plate_mm=(20.0, 1.0)).plate_half_mm is None
    # over side cells the plate's 20 mm cover the loaded cell only
    side = palm_mesh("solid-sil", PalmGeometry(side_cells=1), "coarse", dim=2)
    assert plate_gaps(side, g.top_mm).weight.sum() == pytest.approx(10.0)


def test_the_phalanx_plate_is_unchanged_and_the_full_model_keeps_the_plates_size():
    phalanx = build_mesh(parse_design("pocket2-sil").geometry(), MESH_LEVELS["coarse"])
    assert phalanx.plate_half_mm is None
    gaps = plate_gaps(phalanx, 9.0)
    assert gaps.size == phalanx.outer_faces.shape[0] * 16
    assert full_model(palm_mesh("solid-sil", spec="coarse")).plate_half_mm == (10.0, 5.0)


# --- exact answers ----------------------------------------------------------------------------
def _confined_force(d_mm: float, area_mm2: float, thickness_mm: float, penalty: float) -> float:
    """Force of a laterally confined hyperfoam layer (uniaxial strain, stretch lambda = 1 -
    d_layer / t): P = -tau_1 / lambda with the principal Kirchhoff stress of materials.py,
    tau_1 = sum 2 mu_i [l phi1(alpha_i l) + beta l phi1(-alpha_i beta l)], l = ln lambda, in series
    with the contact penalty (plate travel d = d_layer + P / penalty)."""
    law = material("sil", elastic_only=True).hyperfoam
    b = law.beta

    def pressure(dl: float) -> float:
        lam = 1.0 - dl / thickness_mm
        l = np.log(lam)
        tau = sum(2 * mu * (l * phi1(a * l) + b * l * phi1(-a * b * l))
                  for mu, a in zip(law.mu, law.alpha, strict=True))
        return float(-tau / lam)

    dl = brentq(lambda x: x + pressure(x) / penalty - d_mm, 0.0, d_mm)
    return area_mm2 * pressure(dl)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_flat_bone_under_a_covering_plate_is_a_laterally_confined_layer(dim):
    """No bone rise, a plate over the whole modelled top, symmetry (or roller) on every side:
    uniaxial strain. At small depth the force is E_oed A d / t with the constrained modulus
    E_oed = K + 4G/3 = 2 G (1 - nu) / (1 - 2 nu) of Table 3's silicone (G = sum mu_i); at any
    depth it is the hyperfoam's uniaxial-strain law (which stiffens fast: alpha_2 beta = 380).
    Quadratic elements hold a homogeneous strain exactly and the penalty's compliance is in the
    exact answer, so the FE force is exact to the Newton tolerance (1e-4 N + 1e-4 F): 5e-4."""
    g = PalmGeometry(bone_rise_mm=0.0, half_length_mm=10.0)
    mesh = palm_mesh("solid-sil", g, "coarse", dim=dim, plate_mm=(40.0, 40.0))
    s = IndentationSettings(mode=f"{dim}d", max_depth_mm=0.15, **ELASTIC)
    r = indent("solid-sil", s, mesh=mesh)
    area, t = g.spacing_mm * 2 * g.half_length_mm, g.skin_mm
    for d, f in zip(r.displacement_mm[1:], r.force_N[1:], strict=True):
        assert f == pytest.approx(_confined_force(d, area, t, s.penalty_N_mm3), rel=5e-4)
    law = material("sil", elastic_only=True).hyperfoam
    G, nu = law.shear_modulus, law.nu
    e_oed = 2 * G * (1 - nu) / (1 - 2 * nu)
    assert e_oed == pytest.approx(law.bulk_modulus + 4 * G / 3)
    k = 1.0 / (t / (e_oed * area) + 1.0 / (s.penalty_N_mm3 * area))  # layer and penalty in series
    assert _confined_force(1e-6, area, t, s.penalty_N_mm3) / 1e-6 == pytest.approx(k, rel=1e-4)
    tiny = indent("solid-sil", replace(s, max_depth_mm=1e-4), mesh=mesh)
    assert tiny.force_N[-1] / 1e-4 == pytest.approx(k, rel=1e-3)  # the law: +2e-4 by 1e-4 mm


def test_a_cylinder_along_the_metacarpal_is_plane_strain():
    """The roller at the far end makes the 3D palm under a cylinder at 0 deg a plane-strain
    problem: its force is the 2D section's force per mm times the modelled length (same in-plane
    mesh), to the Newton tolerance."""
    base = dict(max_depth_mm=0.3, indenter="cylinder:8@0", **ELASTIC)
    f = {dim: indent("pocket2-sil", IndentationSettings(mode=f"{dim}d", **base),
                     mesh=palm_mesh("pocket2-sil", spec="coarse", dim=dim)).force_at(0.3)
         for dim in (2, 3)}
    assert f[3] == pytest.approx(f[2], rel=5e-4)


@pytest.mark.slow
def test_the_palm_under_a_cylinder_is_softer_than_under_the_plate_stiffer_than_the_phalanx():
    """Coarse 3D solid-sil, elastic, 0.5 mm. The cylinder (R = 8 mm across the metacarpals)
    presses a strip about 2 sqrt(2 R d) = 5.7 mm wide where the plate presses its 10 mm: less
    tissue pressed, less force (the 0.3-0.8x of DESIGN's contact-geometry section). The same
    cylinder on the phalanx meets less and freer tissue: the phalanx's top is rounded (the
    cylinder meets its 16 mm width only near the top), it is a 10 mm segment with free ends,
    and its sides are free, where the palm's flat top spans its cell, continues along the
    metacarpal and is held at its sides by the next cells."""
    base = dict(max_depth_mm=0.5, mesh="coarse", **ELASTIC)
    mesh = palm_mesh("solid-sil", spec="coarse")
    plate = indent("solid-sil", IndentationSettings(**base), mesh=mesh).force_at(0.5)
    cyl = IndentationSettings(**base, indenter="cylinder:8@90")
    palm = indent("solid-sil", cyl, mesh=mesh).force_at(0.5)
    phalanx = indent("solid-sil", cyl).force_at(0.5)
    assert phalanx < palm < plate


# --- bodies -----------------------------------------------------------------------------------
def test_body_mesh_builds_either_body_and_names_what_it_refuses():
    phalanx = body_mesh("phalanx", "pocket2-sil", "coarse", 3)
    ref = build_mesh(parse_design("pocket2-sil").geometry(), MESH_LEVELS["coarse"])
    np.testing.assert_array_equal(phalanx.X, ref.X)
    palm = body_mesh("palm", "pocket2-sil", "coarse", 2)
    np.testing.assert_array_equal(palm.X, palm_mesh("pocket2-sil", spec="coarse", dim=2).X)
    with pytest.raises(ValueError, match="body = 'foot': allowed phalanx, palm"):
        check_body("foot")
    with pytest.raises(ValueError, match="mesh_level = 'uniform' for body 'palm': allowed"):
        body_mesh("palm", "solid-sil", "uniform")
    with pytest.raises(ValueError, match="or a PalmMeshSpec"):
        body_mesh("palm", "solid-sil", MESH_LEVELS["coarse"])
    spec = PalmMeshSpec(n_far=2)
    assert body_mesh("palm", "solid-sil", spec, 2).spec is spec
    with pytest.raises(ValueError, match=r"indenter = 'cylinder:8@45' on body 'palm'"):
        body_mesh("palm", "solid-sil", indenter="cylinder:8@45")
    check_body("phalanx", "cylinder:8@45")  # the phalanx has its full model


@pytest.mark.slow
def test_the_cli_indents_the_palm_and_refuses_what_its_quarter_cell_cannot_carry():
    """`fe indent --body palm` runs the palm (named in the header, stiffer than the phalanx
    under the same plate); an oblique cylinder, which needs a full model the palm does not have,
    is refused in one line naming --body, before any work."""
    import json

    from click.testing import CliRunner

    from softhand.cli import main

    res = CliRunner().invoke(main, ["fe", "indent", "pocket2-sil", "--body", "palm",
                                    "--indenter", "cylinder:9@45", "--mesh", "coarse"])
    assert res.exit_code == 2
    assert "--body palm" in res.output and "cylinder:9@45" in res.output
    assert "Traceback" not in res.output
    args = ["fe", "indent", "solid-sil", "--mesh", "coarse", "--hold", "0", "--max-force",
            "0.5", "--json"]
    palm = json.loads(CliRunner().invoke(main, [*args, "--body", "palm"]).output)
    phalanx = json.loads(CliRunner().invoke(main, args).output)
    assert palm["body"] == "palm" and phalanx["body"] == "phalanx"
    assert palm["displacement_at_2N_mm"] is None  # the ramp stops at 0.5 N
    d_palm = palm["displacement_mm"][-1]
    d_phalanx = phalanx["displacement_mm"][-1]
    assert d_palm < 0.5 * d_phalanx  # the confined slab: 5-50x stiffer (module docstring)
