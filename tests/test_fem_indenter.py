"""Round indenters (cylinder, sphere) in the FE: parsing, the nonlinear gap, Hertz, plate limit.

Reference numbers (measured with the scripts' settings below, softhand 2026-12):

* Sphere R = 20 mm, 0.05 mm deep, on the 40 x 20 x 40 mm block (a = 1 mm, chi = a / h = 0.05):
  n = 4 elements per edge +4.1 %, n = 6 +5.1 % against half-space Hertz; the bonded layer's
  correction (Dimitriadis et al., Biophys. J. 82, 2798, 2002, nu = 0.3) is +4.6 %, so the mesh
  is within 0.5 % of the layer's Hertz force either way.
* Cylinder R = 20 mm, 0.05 mm deep, plane strain on a 40 x 20 mm block: contact half-width from
  the pressure's second moment -0.8 % (n = 8), +0.6 % (n = 12) against Hertz for the FE force.
* Full model (a cylinder at an angle other than 0 or 90 deg), coarse solid-sil, elastic,
  R = 7.4 mm: 89.9 deg gives the quarter model's 90 deg force at 0.5 mm to 1.4e-7, 0.1 deg its
  0 deg force to 2e-6; 45 deg lies between (0.643 N against 0.516 and 0.917 N).
* Phalanx, 2D coarse, elastic: a cylinder along the phalanx (0 deg) of R = 50, 200, 1000 mm
  gives solid-sil's plate force at 1 mm to -5.9, -2.1, -0.42 % (pocket2-sil -5.5, -3.1, -0.64 %),
  about 1/R as the gap difference x^2 / 2R.
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import pytest

from softhand.fem.block import block_mesh
from softhand.fem.contact import RoundGaps
from softhand.fem.geometry import parse_design
from softhand.fem.indenter import parse_indenter
from softhand.fem.mesh import MESH_LEVELS, build_mesh, full_model
from softhand.fem.solver import IndentationSettings, indent
from softhand.fem.sweep import folder_conflict

#: a linear-elastic-equivalent skin at small strain: shear modulus 0.05 MPa, nu = 0.3
LINEAR = {"sil": {"nu": 0.3, "mu_MPa": [0.05], "alpha": [2.0], "g": [], "tau_s": []}}
E_STAR = 2 * 0.05 * 1.3 / (1 - 0.3**2)  # plane-strain modulus E / (1 - nu^2), MPa


@pytest.mark.parametrize("text, canonical", [
    ("plate", "plate"), ("cylinder:7.4", "cylinder:7.4@90"), ("cylinder:10.7@0", "cylinder:10.7@0"),
    (" sphere:5 ", "sphere:5"), ("cylinder:1000@90.0", "cylinder:1000@90"),
])
def test_indenter_forms_parse_to_a_canonical_text(text, canonical):
    assert parse_indenter(text).text == canonical
    assert IndentationSettings(indenter=text).indenter == canonical


@pytest.mark.parametrize("text, words", [
    ("disc:5", "expected plate, cylinder"), ("cylinder", "expected plate"),
    ("cylinder:0", "[1, 1000] mm"), ("sphere:1001", "[1, 1000] mm"), ("sphere:nan", "[1, 1000]"),
    ("cylinder:0.000001@90", "[1, 1000] mm"), ("sphere:0.5", "[1, 1000] mm"),
    ("cylinder:5@100", "[0, 90] deg"), ("cylinder:5@-1", "[0, 90] deg"),
    ("sphere:5@90", "takes no angle"), ("plate:5", "takes no radius"), ("cylinder:x", "expected"),
])
def test_bad_indenters_are_refused_naming_the_value(text, words):
    with pytest.raises(ValueError, match="indenter = ") as exc:
        parse_indenter(text)
    assert words in str(exc.value)


@pytest.mark.parametrize("text", ["sphere:5", "cylinder:5@90"])
def test_2d_takes_only_the_plate_and_a_cylinder_along_the_phalanx(text):
    with pytest.raises(ValueError, match="plane-strain"):
        IndentationSettings(mode="2d", indenter=text)
    assert IndentationSettings(mode="2d", indenter="cylinder:5@0").indenter == "cylinder:5@0"


def test_the_indenter_is_a_settings_field_and_an_old_folder_is_a_plate_folder():
    s = IndentationSettings(indenter="cylinder:7.4")
    assert asdict(s)["indenter"] == "cylinder:7.4@90"
    assert asdict(IndentationSettings())["indenter"] == "plate"
    old = {"provenance": {"settings": {k: v for k, v in asdict(IndentationSettings()).items()
                                       if k != "indenter"}},  # written before indenters
           "designs": {"solid-sil": {}}}
    assert "indenter 'plate' (the folder) vs 'cylinder:7.4@90'" in folder_conflict(
        old, s, ["pocket2-sil"])
    assert folder_conflict(old, IndentationSettings(), ["pocket2-sil"]) is None


@pytest.mark.parametrize("axis", [None, np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])])
def test_round_gap_is_exact_and_its_linearisation_is_its_derivative(axis):
    mesh = block_mesh(width_mm=4, height_mm=2, length_mm=4, n=2, ratio=0.5)
    gaps = RoundGaps(mesh, 2.0, 3.0, axis, n_gauss=2)
    x = gaps.points
    c = np.array([0.0, 2.0 + 3.0 - 0.1, 0.0])
    r = x - c
    if axis is not None:
        r = r - np.outer(r @ axis, axis)
    u0 = np.zeros(mesh.n_dofs)
    np.testing.assert_allclose(gaps.linearised(u0, 0.1).gaps(u0),
                               np.linalg.norm(r, axis=1) - 3.0, atol=1e-12)
    rng = np.random.default_rng(0)
    u = 0.01 * rng.standard_normal(mesh.n_dofs)
    du = 1e-6 * rng.standard_normal(mesh.n_dofs)
    lin = gaps.linearised(u, 0.1)
    exact = gaps.linearised(u + du, 0.1).gaps(u + du)
    np.testing.assert_allclose(lin.gaps(u + du), exact, atol=1e-10)


def test_sphere_on_a_thick_block_gives_the_hertz_force():
    """F = 4/3 E* sqrt(R) d^1.5 times the bonded-layer correction 1 - 2 alpha0 chi / pi +
    4 alpha0^2 chi^2 / pi^2 (Dimitriadis 2002; chi = sqrt(R d) / h): within 1.5 %."""
    R, d, h = 20.0, 0.05, 20.0
    mesh = block_mesh(width_mm=2 * h, height_mm=h, length_mm=2 * h, n=4, ratio=0.1)
    s = IndentationSettings(indenter=f"sphere:{R:g}", elastic_only=True, hold_s=0.0,
                            max_force_N=10.0, max_depth_mm=d, max_step_mm=d / 4,
                            materials=LINEAR, threads=1)
    r = indent("solid-sil", s, mesh=mesh)
    nu = 0.3
    alpha0 = -(1.2876 - 1.4678 * nu + 1.3442 * nu**2) / (1 - nu)
    chi = np.sqrt(R * d) / h
    layer = 1 - 2 * alpha0 * chi / np.pi + 4 * alpha0**2 * chi**2 / np.pi**2
    hertz = 4 / 3 * E_STAR * np.sqrt(R) * d**1.5
    assert r.force_N[-1] == pytest.approx(hertz * layer, rel=0.015)
    assert r.force_N[-1] == pytest.approx(hertz, rel=0.06)  # the half-space, for scale


def test_cylinder_on_a_thick_block_gives_the_hertz_half_width():
    """Plane strain: a = sqrt(4 F' R / (pi E*)); FE a from the pressure's second moment
    (Hertz: integral p x^2 / F' = a^2 / 4), within 2 %."""
    R, d = 20.0, 0.05
    mesh = block_mesh(width_mm=40.0, height_mm=20.0, n=8, ratio=0.1, dim=2)
    s = IndentationSettings(mode="2d", indenter=f"cylinder:{R:g}@0", elastic_only=True,
                            hold_s=0.0, max_force_N=10.0, max_depth_mm=d, max_step_mm=d / 4,
                            materials=LINEAR, threads=1)
    r = indent("solid-sil", s, mesh=mesh)
    p = r.plate_pressure
    wp = p["weight_mm2"] * p["pressure_MPa"]
    a = 2 * np.sqrt((wp * p["points_mm"][:, 0] ** 2).sum() / wp.sum())
    force_per_mm = r.force_N[-1]  # whole width, per mm of length
    assert a == pytest.approx(np.sqrt(4 * force_per_mm * R / (np.pi * E_STAR)), rel=0.02)


@pytest.mark.parametrize("design", ["solid-sil", "pocket2-sil"])
def test_a_growing_cylinder_converges_to_the_plate(design):
    """2D coarse: R = 50, 200, 1000 mm along the phalanx approach the plate's force at 1 mm
    monotonically, to within 1 % at 1000 mm."""
    base = dict(mode="2d", mesh="coarse", elastic_only=True, hold_s=0.0, max_force_N=20.0,
                max_depth_mm=1.0, threads=1)
    plate = indent(design, IndentationSettings(**base)).force_at(1.0)
    err = [indent(design, IndentationSettings(**base, indenter=f"cylinder:{R}@0")).force_at(1.0)
           / plate - 1 for R in (50, 200, 1000)]
    assert err[0] < err[1] < err[2] < 0
    assert err[2] > -0.01


@pytest.mark.slow
def test_3d_round_indenters_run_to_the_force_and_are_softer_than_the_plate():
    """Coarse 3D, elastic: sphere and cylinders reach 2 N; at 0.5 mm each is below the plate."""
    base = dict(mesh="coarse", elastic_only=True, hold_s=0.0, threads=1)
    plate = indent("solid-sil", IndentationSettings(**base)).force_at(0.5)
    for text in ("sphere:7.4", "cylinder:7.4@90", "cylinder:7.4@0"):
        r = indent("solid-sil", IndentationSettings(**base, indenter=text))
        assert r.status.value == "reached_force"
        assert 0.3 * plate < r.force_at(0.5) < plate
        assert r.summary()["indenter"] == text


def test_full_model_mirrors_the_quarter():
    """Four copies sharing the symmetry-plane nodes, every element right-handed, only the base
    fixed, each face set four times."""
    q = build_mesh(parse_design("pocket2-sil").geometry(), MESH_LEVELS["coarse"])
    f = full_model(q)
    on_x, on_z = np.abs(q.X[:, 0]) < 1e-9, np.abs(q.X[:, 2]) < 1e-9
    assert f.X.shape[0] == 4 * q.X.shape[0] - 2 * on_x.sum() - 2 * on_z.sum() + (on_x & on_z).sum()
    assert f.elements.shape[0] == 4 * q.elements.shape[0]
    J = np.einsum("qnk,end->eqdk", f.ref.dN, f.X[f.elements])
    assert np.linalg.det(J).min() > 0
    np.testing.assert_allclose(np.sort(f.X[:, 0]), np.sort(-f.X[:, 0]), atol=1e-12)
    np.testing.assert_allclose(np.sort(f.X[:, 2]), np.sort(-f.X[:, 2]), atol=1e-12)
    assert set(np.unique(f.fixed // 3)) == set(np.flatnonzero(np.abs(f.X[:, 1]) < 1e-9))
    for name in ("outer", "roof", "floor"):
        assert getattr(f, f"{name}_faces").shape[0] == 4 * getattr(q, f"{name}_faces").shape[0]
    assert f.symmetry_factor == 1.0


@pytest.mark.slow
def test_plate_on_the_full_model_equals_the_quarter():
    """Same curve from the whole phalanx as from its quarter x 4 (coarse, 0.4 mm): 1e-4."""
    base = dict(mesh="coarse", elastic_only=True, hold_s=0.0, max_depth_mm=0.4, threads=1,
                sensors=())
    quarter = indent("pocket2-sil", IndentationSettings(**base))
    mesh = full_model(build_mesh(parse_design("pocket2-sil").geometry(), MESH_LEVELS["coarse"]))
    whole = indent("pocket2-sil", IndentationSettings(**base), mesh=mesh)
    assert whole.force_at(0.4) == pytest.approx(quarter.force_at(0.4), rel=1e-4)


@pytest.mark.slow
def test_a_crossing_cylinder_runs_on_the_full_model_continuous_in_the_angle():
    """Coarse solid-sil, R = 7.4 mm: 89.9 and 0.1 deg (full model) give the 90 and 0 deg
    forces of the quarter at 0.5 mm to 1e-4; 45 deg lies between them."""
    base = dict(mesh="coarse", elastic_only=True, hold_s=0.0, threads=1)
    f = {a: indent("solid-sil", IndentationSettings(**base, indenter=f"cylinder:7.4@{a}"))
         for a in (0, 0.1, 45, 89.9, 90)}
    assert f[0.1].n_dofs == f[45].n_dofs > 3 * f[0].n_dofs  # the full model
    at = {a: r.force_at(0.5) for a, r in f.items()}
    assert at[89.9] == pytest.approx(at[90], rel=1e-4)
    assert at[0.1] == pytest.approx(at[0], rel=1e-4)
    assert at[90] < at[45] < at[0]


def test_a_long_part_keeps_the_phalanx_mesh_under_the_plate_and_grows_to_its_ends():
    """A part longer than the plate (a stand-in for a long rounded edge): the same elements as
    the 10 mm phalanx over the central 10 mm (a mesh line where the plate's face ends), then
    elements growing to the end; a plate presses that central length only; a 2D section is
    refused naming the field."""
    spec = MESH_LEVELS["default"]
    short = build_mesh(parse_design("pocket2-sil").geometry(), spec)
    long = build_mesh(parse_design("pocket2-sil").geometry(length_mm=40.0), spec)
    z_short, z_long = np.unique(short.X[:, 2].round(9)), np.unique(long.X[:, 2].round(9))
    np.testing.assert_allclose(z_long[:len(z_short)], z_short, atol=1e-9)
    assert z_long.max() == pytest.approx(20.0)
    steps = np.diff(z_long[::2])  # element edges (quadratic: every other node line)
    assert np.all(np.diff(steps[spec.n_length - 1:]) > 0)  # growing beyond the plate
    assert (short.plate_half_mm, long.plate_half_mm) == (None, (10.0, 5.0))
    whole = full_model(long)
    J = np.einsum("qnk,end->eqdk", whole.ref.dN, whole.X[whole.elements])
    assert np.linalg.det(J).min() > 0
    with pytest.raises(ValueError, match=r"length_mm = 40: a 2D section is as long as the plate"):
        build_mesh(parse_design("pocket2-sil").geometry(length_mm=40.0), spec, dim=2)
    with pytest.raises(ValueError, match=r"length_mm = 40: .* at most 10 mm; use mode 3d"):
        IndentationSettings(mode="2d", geometry={"length_mm": 40.0})  # before any work


@pytest.mark.slow
def test_a_part_long_enough_for_its_contact_has_converged_in_length():
    """A finger-sized cylinder across a rounded edge (coarse, elastic, 1.5 mm): a 40 mm part
    gives the 60 mm part's force within 1 % (0.4 % measured: its ends are too far to matter), while the
    paper's 10 mm phalanx, whose free ends the contact reaches, is softer by over 5 % (22 %)."""
    base = dict(mesh="coarse", elastic_only=True, hold_s=0.0, threads=1, max_depth_mm=1.5,
                max_force_N=50.0, indenter="cylinder:9@90", sensors=())
    f = {L: indent("solid-sil", IndentationSettings(**base, geometry={
        "width_mm": 20.0, "height_mm": 8.0, "length_mm": L})).force_at(1.5) for L in (10, 40, 60)}
    assert f[40] == pytest.approx(f[60], rel=1e-2)
    assert f[10] < 0.95 * f[60]
