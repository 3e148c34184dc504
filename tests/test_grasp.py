"""The handshake grasp solved from its contacts (softhand.hands.grasp): what a biomechanist checks.

Each assertion is a target of the grasp's definition (module docstring of softhand.hands.grasp):
palms pressed together, each thumb over the back of the other hand's index metacarpal, fingertips
wrapped past the other hand's mid-plane, no hand inside itself, bones apart, every partner joint
inside its range by the grasp's margin. Measured values (default hands, 190 x 88 mm both) are in
the comments; the tolerances are the definition's, not the measurement's.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from softhand.hands import SceneConfig, partner_contact_pose, solve_grasp
from softhand.hands.config import HandConfig, PartnerConfig
from softhand.hands.grasp import GRASP_SETTINGS, grasp_metrics, set_grasp_state
from softhand.hands.layout import hand_layout
from softhand.hands.scene import scene_spec


def _state(config: SceneConfig):
    grasp = solve_grasp(config)
    model = scene_spec(config).compile()
    data = mujoco.MjData(model)
    set_grasp_state(model, data, grasp)
    return grasp, model, data


def _bone_distance(model, data) -> float:
    name = lambda g: model.geom(g).name  # noqa: E731
    pro = [g for g in range(model.ngeom) if name(g).startswith("pro_bone")]
    hum = [g for g in range(model.ngeom) if name(g).startswith("hum_bone")]
    ft = np.zeros(6)
    return min(mujoco.mj_geomDistance(model, data, a, b, 0.05, ft) for a in pro for b in hum)


def _check(config: SceneConfig) -> dict:
    grasp, model, data = _state(config)
    pro, hum = hand_layout(config.prosthetic.hand), hand_layout(config.partner.hand)
    m = grasp_metrics(model, data, pro, hum)
    # palms pressed across their width: both palmar quarters within 1 mm of the partner's palm
    # (measured -0.9 / -0.7 mm), none deeper than the grasp's allowance
    for gap in m["palm_gap_mm"].values():
        assert -1e3 * GRASP_SETTINGS.max_depth_m - 0.5 <= gap <= 1.0, m["palm_gap_mm"]
    # each thumb pad over the back of the other hand (dorsal of its mid-plane by more than half
    # the palm's thickness less the pad's press), on the radial half of the back (y > 0 is the
    # index side of the mid-line; 3.2 mm at least, measured at the four corners below)
    for key, other in (("partner_on_prosthetic", pro), ("prosthetic_on_partner", hum)):
        _, y, z = m["thumb_tip_in_other_mm"][key]
        assert z > 0.5e3 * other.thickness_m - 5.0, (key, m["thumb_tip_in_other_mm"])
        assert y > -5.0, (key, m["thumb_tip_in_other_mm"])
    # the fingers wrap round the ulnar border: each hand's middle fingertip past the other's
    # mid-plane, onto its back (the default hands: all four, test below; a short -2.5 SD partner,
    # 159 mm, reaches round the 190 mm hand with index to ring but its little fingertip stays
    # 7.2 mm short of the mid-plane when the hand is wide, 107 mm; middle fingertips measured at
    # 7.1 mm and more over the corners)
    for hand in ("partner", "prosthetic"):
        assert m["fingertip_z_in_other_mm"][hand]["middle"] > 0.0, m["fingertip_z_in_other_mm"]
    # no hand inside itself (the test of the definition: 1 mm), bones apart, joints off their stops
    assert max(m["self_penetration_mm"].values()) < 1.0, m["self_penetration_mm"]
    assert _bone_distance(model, data) > GRASP_SETTINGS.bone_clearance_m - 1e-3
    assert m["partner_limit_margin_deg"] >= GRASP_SETTINGS.limit_margin_deg - 1e-6
    assert grasp.touching_phalanges, "no partner phalanx touches the other hand at the grasp"
    return m


def test_default_grasp_is_a_handshake():
    """Two 190 x 88 mm hands: every fingertip of each hand past the other's mid-plane (measured
    10-27 mm)."""
    m = _check(SceneConfig())
    for hand, tips in m["fingertip_z_in_other_mm"].items():
        assert all(z > 0.0 for z in tips.values()), (hand, tips)


def test_contact_pose_is_the_grasp_pose():
    """The scene's contact pose is where the grasp puts the partner, not a clearance rule."""
    grasp = solve_grasp(SceneConfig())
    pos, quat = partner_contact_pose(SceneConfig())
    np.testing.assert_array_equal(pos, grasp.partner_pos_m)
    np.testing.assert_array_equal(quat, grasp.partner_quat)


@pytest.mark.slow
@pytest.mark.parametrize("dl, dw", [(-2.5, -2.5), (-2.5, 2.5), (2.5, -2.5), (2.5, 2.5)])
def test_grasp_holds_at_the_corners_of_the_subjects_sizes(dl, dw):
    """Partners at the +-2.5 SD corners of the paper's subjects (Table 1: 187.5 +- 11.37 mm long,
    89.53 +- 6.80 mm wide) shake the default prosthetic hand with the same grasp definition."""
    length = (187.5 + dl * 11.37) / 1000.0
    width = (89.53 + dw * 6.80) / 1000.0
    config = SceneConfig(partner=PartnerConfig(hand=HandConfig(hand_length_m=length,
                                                               hand_width_m=width)))
    m = _check(config)
    assert math.isfinite(m["partner_limit_margin_deg"])


def test_pruned_residual_equals_measuring_every_pair_and_its_jacobian_is_the_derivative():
    """The grasp's residual measures only the pairs whose bounding spheres can reach the
    residual's threshold; it must give the same floating-point numbers as measuring every pair,
    at states near and far from the grasp. Its analytic Jacobian (bodies' Jacobians, distances'
    witness points) must be the residual's derivative: against central differences (step 1e-7)
    each state's Jacobian within 1e-3 in Frobenius norm (measured 3e-10 to 8e-4: the distance
    routine's witness points of meshes are exact to about 1e-5 relative), and the evaluation with
    the Jacobian returns the same residual."""
    from softhand.hands.grasp import _Problem

    problem = _Problem(SceneConfig(), GRASP_SETTINGS)
    m, d, s = problem.m, problem.d, problem.s
    ft = np.zeros(6)

    def every(pairs, cap):
        return np.array([mujoco.mj_geomDistance(m, d, int(a), int(b), cap, ft) for a, b in pairs])

    rng = np.random.default_rng(7)
    bounds = problem.bounds
    checked = 0
    for k in range(12):
        x = np.clip(problem.prior + rng.normal(0.0, 0.2 if k % 2 else 0.03, problem.n), *bounds)
        problem.set_state(x)
        for pairs, cap, above in ((problem.soft_pairs, 0.01, -s.max_depth_m),
                                  (problem.bone_pairs, 0.02, s.bone_clearance_m),
                                  (problem.self_pairs, 0.01, 0.0)):
            full = every(pairs, cap)
            # the bound holds for every pair, and the pruned distances agree where they matter
            lower = problem.lower_bounds(pairs)
            assert np.all((lower <= full + 1e-12) | (full >= cap))
            pruned = problem.distances(pairs, cap, above)
            near = full < above
            assert np.array_equal(pruned[near], full[near])
            assert np.all(pruned[~near] >= above)
            checked += int(near.sum())
        for mine, others in problem.gap_sets:
            expect = [min(every([(g, o) for o in others], 0.05)) for g in mine]
            assert problem.nearest(mine, others) == expect
        if k % 3:
            continue
        for contacts in (False, True):
            r, jac = problem.residual(x, contacts=contacts, jacobian=True)
            assert np.array_equal(r, problem.residual(x, contacts=contacts))
            step = 1e-7 * np.eye(problem.n)
            central = np.stack([(problem.residual(x + e, contacts=contacts)
                                 - problem.residual(x - e, contacts=contacts)) / 2e-7
                                for e in step], axis=1)
            assert np.linalg.norm(jac - central) <= 1e-3 * np.linalg.norm(central), (k, contacts)
            assert np.count_nonzero(jac) > 0
    assert checked > 50  # the states include overlapping pairs (measured 1,000 and more)


def test_a_cached_grasp_is_the_solved_one_and_keyed_by_its_config(tmp_path, monkeypatch):
    """solve_grasp keeps each solution in softhand.paths.cache_dir(); a new process reads it back
    instead of solving: the same grasp bit for bit. Another hand size is another entry; a
    corrupt entry is solved again; SOFTHAND_CACHE_DIR=off keeps nothing."""
    from softhand.hands import grasp as g

    monkeypatch.setenv("SOFTHAND_CACHE_DIR", str(tmp_path))
    real_solve_starts = g._solve_starts
    config = SceneConfig()
    # solves (an empty cache) and writes the entry
    solved = g._solve_grasp.__wrapped__(config, g.GRASP_SETTINGS)
    entries = list((tmp_path / "grasps").glob("*.json"))
    assert len(entries) == 1
    calls = []
    monkeypatch.setattr(g, "_solve_starts", lambda *a: calls.append(a) or pytest.fail("solved"))
    read = g._solve_grasp.__wrapped__(config, g.GRASP_SETTINGS)
    assert not calls
    for field in ("partner_pos_m", "partner_quat", "partner_q", "prosthetic_q"):
        assert np.array_equal(getattr(read, field), getattr(solved, field)), field
    assert (read.cost, read.iterations, read.metrics, read.touching_phalanges) == (
        solved.cost, solved.iterations, solved.metrics, solved.touching_phalanges)
    other = SceneConfig(partner=PartnerConfig(hand=HandConfig(hand_length_m=0.18)))
    assert g._cache_path(other, GRASP_SETTINGS) != entries[0]
    entries[0].write_text("{not json")
    monkeypatch.setattr(g, "_solve_starts", lambda *a: calls.append(a) or (
        solved.cost, np.concatenate([np.zeros(6), solved.partner_q, solved.prosthetic_q]),
        list(solved.iterations)))
    g._solve_grasp.__wrapped__(config, g.GRASP_SETTINGS)
    assert len(calls) == 1  # the corrupt entry was solved again
    # finite but wrong numbers (its variables zeroed): their cost is not the entry's, so it is
    # solved again and the entry rewritten, not used
    import json

    g._write_cached(entries[0], solved.cost, np.zeros_like(np.array(json.loads(
        entries[0].read_text())["x"])), list(solved.iterations))
    monkeypatch.setattr(g, "_solve_starts", lambda *a: calls.append(a) or real_solve_starts(*a))
    again = g._solve_grasp.__wrapped__(config, g.GRASP_SETTINGS)
    assert len(calls) == 2
    assert np.array_equal(again.partner_q, solved.partner_q)
    assert json.loads(entries[0].read_text())["x"] != [0.0] * len(again.partner_q)
    monkeypatch.setenv("SOFTHAND_CACHE_DIR", "off")
    assert g._cache_path(config, GRASP_SETTINGS) is None


@pytest.mark.slow
def test_the_grasp_has_one_answer_whichever_solver_finds_it(monkeypatch):
    """The grasp is the cheapest of the solver's starts, then hops to any cheaper minimum nearby:
    its cost is at most the cheapest start's. For a 161 x 88 mm partner (of the 30-partner
    population, seed 0) finite differences (another solver of the same definition) stopped
    40 deg (ring PIP) and 16 mm from the grasp, in a minimum 23 % dearer, until every other hop
    moved one digit alone; with them, finite differences and other hop seeds (2 and 3) land
    within the issue's 2 deg and 2 mm of the grasp (measured 0.0 deg; over the population and
    the +-2.5 SD corners: reports/grasp-agreement.md)."""
    from softhand.hands.grasp import _TIE, _Problem, _solve_grasp, _solve_starts, _start_runs

    monkeypatch.setenv("SOFTHAND_CACHE_DIR", "off")
    config = SceneConfig(partner=PartnerConfig(hand=HandConfig(
        hand_length_m=0.16106440009235646, hand_width_m=0.0880422166852587)))
    grasp = _solve_grasp.__wrapped__(config, GRASP_SETTINGS)
    problem = _Problem(config, GRASP_SETTINGS)
    costs = [cost for cost, _, _ in _start_runs(problem, GRASP_SETTINGS)]
    assert grasp.cost <= min(costs) * (1.0 + _TIE)  # starts that tie to rounding: the first
    for how in ({"finite_differences": True}, {"seeds": (2, 3)}):
        _, x, _ = _solve_starts(problem, GRASP_SETTINGS, **how)
        joints = np.degrees(np.abs(x[6:] - np.concatenate([grasp.partner_q,
                                                            grasp.prosthetic_q])).max())
        pos, _ = problem.pose(x)
        assert joints < 2.0, f"{how}: largest joint difference {joints:.2f} deg"
        assert 1e3 * np.linalg.norm(pos - grasp.partner_pos_m) < 2.0, how


@pytest.mark.slow
def test_the_palm_alignment_weight_turns_the_partners_palm_parallel(monkeypatch):
    """The grasp's palms-parallel target is weighted `GraspSettings.palm_align_weight`: at the
    shipped 0.2 the default grasp holds the palms parallel (measured 1.4 deg) and pressed; at
    0.02, the weight before, it rolled the partner's palm onto one edge of the prosthetic palm
    (measured 14.5 deg) and the palms carried none of the force (reports/palm-alignment.md).
    `solve_grasp()` reads the module's `GRASP_SETTINGS` at the call (tools/palm_alignment.py
    replaces it), never a grasp cached under other settings."""
    import dataclasses

    from softhand.hands import grasp as g

    config = SceneConfig()
    shipped = solve_grasp(config)
    light = dataclasses.replace(GRASP_SETTINGS, palm_align_weight=0.02)
    monkeypatch.setattr(g, "GRASP_SETTINGS", light)
    rolled = solve_grasp(config)
    assert rolled.settings == light and shipped.settings == GRASP_SETTINGS
    assert rolled.metrics["palm_angle_deg"] > 10.0
    assert shipped.metrics["palm_angle_deg"] < 3.0
    assert -GRASP_SETTINGS.max_depth_m * 1e3 < shipped.metrics["palm_gap_mm"]["Palm"] < 0.0
    assert shipped.cost < g.GOOD_COST_M2
