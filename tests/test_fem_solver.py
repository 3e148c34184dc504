"""Indentation solver: relaxation, hard cases, mesh convergence (2D), and run bookkeeping.

Hard cases run in the 2D plane-strain mode (the same solver, elements and contact as 3D) so the
suite stays fast; the 3D runs are in test_fem_paper.py.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from softhand.fem.materials import material
from softhand.fem.mesh import MESH_LEVELS
from softhand.fem.solver import IndentationSettings, Status, indent

S2D = dict(mode="2d")


def _finite_monotone_ramp(r):
    ramp = ~r.hold
    assert np.all(np.isfinite(r.force_N)) and np.all(np.isfinite(r.displacement_mm))
    assert np.all(np.diff(r.displacement_mm[ramp]) > 0)
    assert np.all(np.diff(r.force_N[ramp]) > -1e-9)


@pytest.mark.parametrize("name", ["sil", "pu"])
def test_fast_ramp_then_hold_relaxes_like_the_prony_series(name):
    """Plate at 1000 mm/s (a step), then hold: F(t)/F(0+) = g(t) within 0.5 % of F(0+)."""
    r = indent(f"solid-{name}", IndentationSettings(speed_mm_s=1000.0, hold_s=60.0, **S2D))
    _finite_monotone_ramp(r)
    t0 = r.time_s[~r.hold][-1]
    t = r.time_s[r.hold] - t0
    ratio = r.force_N[r.hold] / r.force_N[~r.hold][-1]
    g = material(name).prony.relaxation(t)
    assert np.abs(ratio - g).max() < 5e-3
    assert np.all(np.diff(r.force_N[r.hold]) < 1e-5)  # never rises beyond the Newton tolerance


def test_long_pu_hold_reaches_the_long_term_elastic_state():
    """PU, tau3 = 25 s, 300 s hold: final force = long-term elastic force at that depth (1 %)."""
    r = indent("solid-pu", IndentationSettings(hold_s=300.0, **S2D))
    _finite_monotone_ramp(r)
    depth = r.displacement_mm[-1]
    relaxed = indent("solid-pu", IndentationSettings(elastic_only=True, max_force_N=50.0,
                                                     max_depth_mm=depth, **S2D))
    assert relaxed.displacement_mm[-1] == pytest.approx(depth, abs=1e-9)
    assert r.force_N[-1] == pytest.approx(relaxed.force_N[-1], rel=1e-2)
    assert r.force_N[-1] < 0.75 * r.force_N[~r.hold][-1]


@pytest.mark.slow
def test_pocket_closes_under_20_newton_without_failure():
    """pocket2-sil to 20 N: reaches the force, pocket contact closed, stiffening after closure."""
    r = indent("pocket2-sil", IndentationSettings(max_force_N=20.0, hold_s=1.0, **S2D))
    assert r.status is Status.REACHED_FORCE
    _finite_monotone_ramp(r)
    assert r.force_N[~r.hold][-1] >= 20.0
    assert max(rec["pocket_points"] for rec in r.log) > 0
    d02, d2, d20 = r.displacement_at(0.2), r.displacement_at(2.0), r.displacement_at(20.0)
    assert d2 > 2.0  # the 2 mm pocket has closed before 2 N
    open_stiffness = 0.2 / d02
    closed_stiffness = 18.0 / (d20 - d2)
    assert closed_stiffness > 10 * open_stiffness


@pytest.mark.slow
def test_plate_at_100_mm_per_s_is_stiffer_for_the_viscous_pu():
    """100 mm/s vs 0.5 mm/s: finite, and PU needs less travel to reach 2 N (less relaxation)."""
    fast = indent("pocket2-pu", IndentationSettings(speed_mm_s=100.0, hold_s=1.0, **S2D))
    slow = indent("pocket2-pu", IndentationSettings(hold_s=0.0, **S2D))
    _finite_monotone_ramp(fast)
    assert fast.displacement_at(2.0) < slow.displacement_at(2.0)


def test_alpha_to_zero_is_continuous_in_the_structure():
    """SIL alpha1 = 0.001 vs 1e-9: displacement at 2 N agrees to 0.1 %."""
    base = indent("solid-sil", IndentationSettings(**S2D, hold_s=0.0))
    tiny = indent("solid-sil", IndentationSettings(
        **S2D, hold_s=0.0, materials={"sil": {"alpha": [1e-9, 15.5]}}))
    assert tiny.displacement_at(2.0) == pytest.approx(base.displacement_at(2.0), rel=1e-3)


@pytest.mark.slow
@pytest.mark.parametrize("design", ["solid-sil", "pocket2-sil"])
def test_2d_default_mesh_converges_within_one_percent(design):
    """2D: d(2 N) changes < 1 % from the default mesh to the fine mesh (every count doubled)."""
    d = [indent(design, IndentationSettings(mesh=m, hold_s=0.0, **S2D)).displacement_at(2.0)
         for m in ("default", "fine")]
    assert abs(d[0] - d[1]) / d[1] < 0.01


@pytest.mark.slow
def test_2d_uniform_mesh_converges_slowly_near_the_closed_pocket():
    """2D pocket2-sil on uniform meshes: O(h^p) with p < 1.5 (crack-like pocket ends).

    Measured (roof 1.2 mm): 2.519, 2.558, 2.572 mm for 1x, 2x, 3x: the reason the default
    mesh is graded towards the pocket ends.
    """
    spec = MESH_LEVELS["uniform"]
    d = [indent("pocket2-sil", IndentationSettings(mesh=m, hold_s=0.0, **S2D)).displacement_at(2.0)
         for m in (spec, spec.refined(2), spec.refined(3))]
    ratio = (d[1] - d[0]) / (d[2] - d[1])  # 3.0 for p = 1, 4.0 for p = 1.5, 5.4 for p = 2
    assert d[0] < d[1] < d[2]
    assert ratio < 3.9


def test_result_bookkeeping_and_interpolation():
    """Curve starts at 0, log has one record per step, interpolation hits the target force."""
    r = indent("solid-pu", IndentationSettings(hold_s=2.0, **S2D))
    assert r.time_s[0] == 0 and r.force_N[0] == 0
    assert len(r.log) == len(r.time_s) - 1
    assert r.force_N[~r.hold][-1] >= 2.0
    d2 = r.displacement_at(2.0)
    assert r.displacement_mm[~r.hold][-2] < d2 <= r.displacement_mm[~r.hold][-1]
    assert r.force_at(d2) == pytest.approx(2.0, rel=1e-9)
    assert r.force_at(10.0) is None
    s = r.summary()
    for key in ("design", "displacement_at_2N_mm", "force_at_2mm_N", "wall_s", "time_s",
                "displacement_mm", "force_N"):
        assert key in s
    assert r.time_s[r.hold][-1] == pytest.approx(r.time_s[~r.hold][-1] + 2.0, abs=1e-9)


@pytest.mark.parametrize("bad", [dict(max_indefinite=0), dict(max_indefinite=1.5),
                                 dict(max_newton=0), dict(indefinite_shift=0.0),
                                 dict(indefinite_shift=float("nan")), dict(line_searches=-1),
                                 dict(line_searches=1.5)])
def test_bad_newton_limits_are_refused(bad):
    (name, _value), = bad.items()
    with pytest.raises(ValueError, match=name):
        IndentationSettings(**bad)


def _every_tangent_indefinite(monkeypatch):
    """Make CHOLMOD report every tangent not positive definite: each is then solved by
    SuperLU in symmetric mode (`softhand.fem.linear`), the same system to rounding."""
    from softhand.fem import linear

    def refuse(self, vals):
        raise linear._NotPositiveDefiniteError("forced by the test")

    monkeypatch.setattr(linear._Cholmod, "factorize", refuse)


def test_max_indefinite_cuts_first_tries_only_and_keeps_the_equilibria(monkeypatch):
    """With every tangent indefinite, ``max_indefinite=2`` cuts each step's first try at its
    second factorization and retries it a quarter as long, never more than once (a retry runs
    on to max_newton). The elastic, frictionless problem has one equilibrium per plate
    displacement whatever the steps: both runs land on 1 mm and 2 mm, where the forces agree."""
    s = IndentationSettings(mode="2d", mesh="coarse", hold_s=0.0, max_force_N=1.0,
                            elastic_only=True, solver="cholmod", contact_points=2)
    plain = indent("pocket2-sil", s)
    _every_tangent_indefinite(monkeypatch)
    same = indent("pocket2-sil", s)  # no limit: the same steps, each solved by SuperLU
    assert [r["iterations"] for r in same.log] == [r["iterations"] for r in plain.log]
    assert same.force_N == pytest.approx(plain.force_N, rel=1e-6, abs=1e-9)
    cut = indent("pocket2-sil", replace(s, max_indefinite=2))
    assert all(r["retries"] <= 1 for r in cut.log)
    # a first try that needed 2 or more factorizations (3 iterations) was cut
    assert all(r["iterations"] <= 2 for r in cut.log if not r["retries"])
    assert plain.log[1]["iterations"] == 3 and plain.log[1]["retries"] == 0
    assert cut.log[1]["retries"] == 1
    assert cut.log[1]["increment"] == pytest.approx(0.25 * 1.5 * cut.log[0]["increment"])
    assert len(cut.log) > len(plain.log)
    for depth in (1.0, 2.0):
        assert depth in cut.displacement_mm and depth in plain.displacement_mm
        assert cut.force_at(depth) == pytest.approx(plain.force_at(depth), rel=1e-4)


def test_a_shifted_cholesky_keeps_the_equilibria_without_the_indefinite_factorization(
        monkeypatch):
    """With every tangent's Cholesky refused and its shifted one accepted, ``indefinite_shift``
    solves each Newton step by the shifted tangent, never by SuperLU: the steps converge more
    slowly, to the same equilibria (the forces where both runs land on 1 mm and 2 mm)."""
    from softhand.fem import linear

    s = IndentationSettings(mode="2d", mesh="coarse", hold_s=0.0, max_force_N=0.7,
                            elastic_only=True, solver="cholmod", contact_points=2, tol_N=1e-7,
                            tol_rel=0.0, threads=1)  # tightly: shifted steps converge linearly
    plain = indent("pocket2-sil", s)
    factorize, calls = linear._Cholmod.factorize, []

    def every_other(self, vals):  # TangentSystem.factorize: a tangent, then its shifted try
        calls.append(len(calls))
        if len(calls) % 2:
            raise linear._NotPositiveDefiniteError("forced by the test")
        return factorize(self, vals)

    def no_lu(self, vals):
        raise AssertionError("the indefinite factorization was called")

    monkeypatch.setattr(linear._Cholmod, "factorize", every_other)
    monkeypatch.setattr(linear._Cholmod, "factorize_indefinite", no_lu)
    shifted = indent("pocket2-sil", replace(s, indefinite_shift=1e-6))
    assert len(calls) % 2 == 0 and len(calls) >= 2 * sum(r["iterations"] - 1
                                                         for r in shifted.log) > 0
    assert (sum(r["iterations"] for r in shifted.log)
            >= sum(r["iterations"] for r in plain.log))
    for depth in (1.0, 2.0):
        assert depth in shifted.displacement_mm and depth in plain.displacement_mm
        assert shifted.force_at(depth) == pytest.approx(plain.force_at(depth), rel=1e-4)


class _Springs:
    """A stand-in for the solver's model: free residual ``r(u) = A u - b`` (linear, so the
    secant root along an update is the exact root of ``s(a) = du . r(u + a du)``)."""

    def __init__(self, A, b):
        self.A, self.b = np.asarray(A, dtype=float), np.asarray(b, dtype=float)
        self.free = np.arange(self.b.size)

    def residual(self, u, state, dt, d, pocket):
        return (self.A @ u - self.b,)

    def search(self, du):
        from softhand.fem.solver import _Model

        u = np.zeros(self.b.size)
        r0, r1 = self.residual(u, *_NONE)[0], self.residual(u + du, *_NONE)[0]
        return _Model._line_search(self, u, du, r0, r1, *_NONE)


_NONE = (None, 0.0, 0.0, None)


def test_the_line_search_lands_on_the_secant_root_of_an_overshooting_update():
    """r = (u0 - 1, 2e5 u1), du = (2, 1e-3): s(a) = -2 + 4.2 a and the largest residual entry
    grows 200-fold over du, so the search lands on the root a = 10/21, where du . r = 0."""
    m = _Springs(np.diag([1.0, 2e5]), [1.0, 0.0])
    du = np.array([2.0, 1e-3])
    u, res = m.search(du)
    assert u == pytest.approx(10.0 / 21.0 * du, rel=1e-12)
    assert du @ res[0] == pytest.approx(0.0, abs=1e-12)


def test_the_line_search_takes_a_tenth_at_least_and_only_after_a_large_growth():
    """300 times the Newton update of a linear residual: the root 1/300 is below the floor 0.1,
    which is taken. 3 times it overshoots (s(1) = 6 q > 3 q / 2) but the residual only doubles
    (< `LINE_SEARCH_GROWTH`): kept whole. The Newton update itself does not overshoot."""
    from softhand.fem.solver import LINE_SEARCH_GROWTH

    m = _Springs([[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]], [1.0, -2.0, 0.5])
    newton = np.linalg.solve(m.A, m.b)  # from u = 0
    u, res = m.search(300.0 * newton)
    assert u == pytest.approx(30.0 * newton, rel=1e-12)
    assert res[0] == pytest.approx(m.residual(u, *_NONE)[0], rel=1e-12)
    assert LINE_SEARCH_GROWTH > 2.0
    assert m.search(3.0 * newton) is None
    assert m.search(newton) is None


def test_line_searches_keep_the_equilibria(monkeypatch):
    """``line_searches`` changes Newton's path, not where it lands: the 2D screen of the design
    search's trial 293 (its first winner, whose roof buckles; one search, where the pocket
    closes) lands on 1 mm and 2 mm at the forces of full updates, within the tolerance."""
    from softhand.design.evaluate import fe_design
    from softhand.design.space import Candidate
    from softhand.fem.solver import _Model

    trial_293 = Candidate(outer_layer_mm=0.5554, pocket_roof_mm=1.3826, pocket_height_mm=1.7903,
                          pocket_half_width_mm=5.7079, inner="ecoflex-00-50",
                          outer="ecoflex-00-10")
    design, s = fe_design(trial_293, IndentationSettings(mode="2d", hold_s=0.0,
                                                         elastic_only=True, solver="cholmod",
                                                         contact_points=2, threads=1))
    plain = indent(design, s)
    search, taken = _Model._line_search, []

    def counted(self, *args):
        out = search(self, *args)
        taken.append(out is not None)
        return out

    monkeypatch.setattr(_Model, "_line_search", counted)
    searched = indent(design, replace(s, line_searches=2))
    assert sum(taken) > 0
    for depth in (1.0, 2.0):
        assert depth in searched.displacement_mm and depth in plain.displacement_mm
        assert searched.force_at(depth) == pytest.approx(plain.force_at(depth), rel=1e-4)
