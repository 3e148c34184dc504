"""MuJoCo skins: the contact law against MuJoCo itself, calibration recovery, mass and posture
independence, the relaxation pad, hard cases and bad input."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import mujoco
import numpy as np
import pytest

from softhand.laws import Curve, ElasticLaw, Prony, SkinLaw, fit_skin_law, load_curve, qlv_force
from softhand.laws.elastic import knot_vector
from softhand.laws.fit import FitStatus, split_errors
from softhand.skin.calibrate import CALIBRATION_MASS_KG, SkinCalibration, calibrate_design
from softhand.skin.files import load_calibration, save_calibration
from softhand.skin.finger import POSTURES_DEG, press_finger
from softhand.skin.pad import PadParams, evaluate_pieces, spline_pieces
from softhand.skin.representations import loading_ramp
from softhand.skin.rig import BONE_DEPTH_M, RigSettings, SkinRangeWarning, build_rig, run_rig
from softhand.skin.soft_contact import SoftContactParams, fit_soft_contact

FE = Path(__file__).resolve().parents[1] / "calibration" / "fe"
KNOWN = SoftContactParams(900.0, 1.0, (0.05, 0.25, 0.004, 0.4, 3.0))


@pytest.fixture(scope="module")
def pocket_pu() -> Curve:
    return load_curve(FE / "pocket2-pu.csv")


@pytest.fixture(scope="module")
def pocket_soft(pocket_pu) -> SoftContactParams:
    _, d, f = loading_ramp(pocket_pu)
    return fit_soft_contact(d, f, reference_mass_kg=0.01 * CALIBRATION_MASS_KG)[0]


def _rest_force(params: SoftContactParams, mass: float, load: float) -> tuple[float, float]:
    """Penetration (mm) and contact force (N) of a mass resting on the skin under ``load``."""
    st = RigSettings(mass_kg=mass, load_cell_hz=0.0)
    model = build_rig("soft-contact", params, settings=st)
    model.dof_damping[0] = 2 * np.sqrt(2000.0 * mass)  # settle a dead weight (~critical)
    data = mujoco.MjData(model)
    for k in range(8000):
        data.qfrc_applied[0] = -load * min(1.0, k / 2000)
        mujoco.mj_step(model, data)
    c = data.contact[0]
    return -1e3 * c.dist, float(data.efc_force[c.efc_address])


@pytest.mark.parametrize("mass", [0.002, 0.2, 20.0])
def test_closed_form_contact_law_is_what_mujoco_computes_at_rest(mass):
    pen, force = _rest_force(KNOWN, mass, 1.5)
    assert force == pytest.approx(1.5, rel=1e-4)
    assert float(KNOWN.force(pen)) == pytest.approx(force, rel=1e-3)


def test_soft_contact_fit_recovers_known_parameters():
    d = np.linspace(0.0, 3.5, 120)
    fit, rms, status = fit_soft_contact(d, KNOWN.force(d))
    assert status is FitStatus.CONVERGED
    assert rms < 1e-4
    assert fit.stiffness == pytest.approx(KNOWN.stiffness, rel=0.02)
    np.testing.assert_allclose(fit.solimp, KNOWN.solimp, rtol=0.02)


def test_shipped_soft_contact_follows_every_fe_loading_curve_to_20_newtons_within_5_percent():
    """The shipped solref/solimp of each design against its whole 0-20 N FE ramp (closed-form rest
    law): the impedance sigmoid cannot follow a pocket's soft start and closing knee exactly
    (calibration/skins/*.json, soft-contact rms_pct_of_2N_to_2N: up to 4.5 % of 2 N below 2 N).
    Refitting is covered by the calibration test."""
    worst_low = worst_high = 0.0
    for path in sorted(FE.glob("*.csv")):
        _, d, f = loading_ramp(load_curve(path))
        params = load_calibration(path.stem).soft_contact
        err = split_errors(params.force(d[1:]), f[1:])
        worst_low = max(worst_low, err["rms_pct_of_2N_to_2N"])
        worst_high = max(worst_high, err["rms_pct_above_2N"])
    assert worst_low < 5.0  # measured 4.5 % of 2 N (pocket1-pu-sil)
    assert worst_high < 5.0  # measured 4.1 % of the force (pocket1-pu-sil)


def test_pair_law_is_skin_and_tissue_in_series_over_the_whole_range():
    """The shipped pair law of pocket2-sil against human tissue follows the two laws in series to
    20 N (no refit truncated at 2.5 N, which was 7-9 % soft beyond it): up to 2 N within 3 % of
    2 N, above within 1.5 % of the force; calibrated to 7 N (the tissue's data), fitted to 20 N."""
    from softhand.skin.pair import loading_inverse, series_curve

    cal = load_calibration("pocket2-sil")
    human = load_calibration("human-middle-phalanx")
    pair = cal.pair_law
    assert pair.against == "human-middle-phalanx"
    assert pair.calibrated_max_N == pytest.approx(7.0) and pair.fitted_max_N >= 20.0 - 1e-9
    d, f = series_curve(cal.law, human.law, pair.fitted_max_N)
    for force in (0.5, 2.0, 7.0, 15.0):  # the composition itself: depths add at equal force
        i = int(np.argmin(abs(f - force)))
        expect = (loading_inverse(cal.law, f[i:i + 1], top_N=pair.fitted_max_N)[0]
                  + human.law.elastic.displacement_at(f[i]))
        assert d[i] == pytest.approx(expect, rel=1e-9)
    err = split_errors(pair.params.force(d[1:]), f[1:])
    assert err["rms_pct_of_2N_to_2N"] < 3.0  # measured 2.5 %
    assert err["rms_pct_above_2N"] < 1.5  # measured 0.8 %
    at10 = int(np.argmin(abs(f - 10.0)))
    assert pair.params.force(d[at10]) == pytest.approx(f[at10], rel=0.02)


def test_soft_contact_in_the_rig_is_mass_independent(pocket_pu, pocket_soft):
    t, d, f = loading_ramp(pocket_pu)
    curves = {}
    for factor in (0.01, 1.0, 100.0):
        st = RigSettings(mass_kg=CALIBRATION_MASS_KG * factor)
        out = run_rig(build_rig("soft-contact", pocket_soft, settings=st), t, d, settings=st)
        curves[factor] = out
        err = split_errors(out.force_N[1:], np.interp(out.displacement_mm[1:], d, f))
        assert err["rms_pct_of_2N_to_2N"] < 5.0  # of the FE, 0-2 N (the 0-20 N fit's accuracy)
        assert err["rms_pct_above_2N"] < 5.0
    ref = curves[1.0]
    for factor in (0.01, 100.0):
        other = np.interp(ref.displacement_mm, curves[factor].displacement_mm,
                          curves[factor].force_N)
        assert 100 * np.sqrt(np.mean((other - ref.force_N) ** 2)) / 2 < 2.0


@pytest.mark.parametrize("timestep", [0.5e-3, 2e-3])
def test_soft_contact_in_the_rig_is_the_same_law_at_every_supported_timestep(pocket_pu, pocket_soft,
                                                                              timestep):
    """The handshake runs at 2 ms: the loading curve there (and at 0.5 ms) is the 1 ms curve
    within 0.1 % of 2 N (measured: identical to 0.01 %)."""
    t, d, _ = loading_ramp(pocket_pu)
    ref_st, st = RigSettings(), RigSettings(timestep=timestep)
    ref = run_rig(build_rig("soft-contact", pocket_soft, settings=ref_st), t, d,
                  settings=ref_st)
    out = run_rig(build_rig("soft-contact", pocket_soft, settings=st), t, d, settings=st)
    other = np.interp(ref.displacement_mm, out.displacement_mm, out.force_N)
    on = ref.displacement_mm > 0.05
    assert 100 * np.sqrt(np.mean((other[on] - ref.force_N[on]) ** 2)) / 2 < 0.1


@pytest.mark.parametrize("posture", list(POSTURES_DEG))
def test_soft_contact_on_an_articulated_finger_gives_the_same_law(pocket_soft, posture):
    press = press_finger(pocket_soft, posture, depth_mm=4.0)
    loaded = press.force_N > 0.02
    assert press.force_N.max() > 1.0
    err = press.force_N[loaded] - pocket_soft.force(press.displacement_mm[loaded])
    assert 100 * np.sqrt(np.mean(err**2)) / 2 < 2.0  # measured < 0.01 %


def test_spline_pieces_are_the_law_exactly():
    law = ElasticLaw(knot_vector(2.0, 7), np.array([0.1, 0.1, 0.3, 0.2, 1.0, 3.0, 4.0]))
    x = np.linspace(0, 4.0, 401)
    np.testing.assert_allclose(evaluate_pieces(spline_pieces(law), x * 1e-3), law.force(x),
                               atol=1e-9)


def test_relaxation_pad_reproduces_a_known_qlv_law_in_the_rig():
    law = SkinLaw("synthetic", ElasticLaw(knot_vector(2.5, 6),
                                          np.array([0.2, 0.3, 0.5, 0.9, 2.0, 3.0])),
                  Prony((0.2, 0.15), (0.2, 2.0)))
    depth = law.elastic.displacement_at(2.0)
    t = np.concatenate([np.linspace(0, depth / 0.5, 200), depth / 0.5 + np.linspace(0.01, 6, 100)])
    d = np.minimum(0.5 * t, depth)
    f = law.force(t, d)
    pad = PadParams(law, depth, 300 * 3.0e3, 3 * law.elastic.max_mm)
    st = RigSettings()
    out = run_rig(build_rig("soft-contact+relaxation", pad, settings=st), t, d, settings=st)
    err = out.force_N - np.interp(out.time_s, t, f)
    assert 100 * np.sqrt(np.mean(err**2)) / 2 < 1.0
    hold = out.time_s > depth / 0.5
    assert 100 * np.abs(err[hold]).max() / f[199] < 2.0


@pytest.mark.slow
def test_calibrate_design_meets_the_issue_targets_on_a_pocket_design(pocket_pu):
    cal = calibrate_design("pocket2-pu", fe_dir=FE,
                           representations=("soft-contact", "soft-contact+relaxation"))
    soft = cal.representations["soft-contact"]
    relax = cal.representations["soft-contact+relaxation"]
    # soft contact over the 0-20 N ramp; the pad over the social-touch record (ramp to 2 N)
    assert soft.extra["rms_pct_of_2N_to_2N"] < 5.0 and soft.extra["rms_pct_above_2N"] < 5.0
    assert relax.rms_error_pct_of_2N < 3.0
    assert relax.relaxation_error_pct < 5.0
    assert soft.mass_sensitivity_pct < 2.0 and relax.mass_sensitivity_pct < 2.0
    assert cal.pair_law is not None and cal.pair_law.calibrated_max_N == pytest.approx(7.0)
    assert cal.provenance["fe_curves"]["pocket2-pu@0.5mm/s"] == pocket_pu.sha256


@pytest.mark.parametrize("timestep", [0.5e-3, 1e-3, 2e-3, 5e-3])
@pytest.mark.parametrize("rep", ["soft-contact", "soft-contact+relaxation"])
def test_impact_and_overload_stay_bounded(pocket_pu, pocket_soft, rep, timestep):
    law = fit_skin_law("pocket2-pu", [pocket_pu])
    params = pocket_soft if rep == "soft-contact" else PadParams(
        law, law.elastic.displacement_at(2.0), 300 * 6e3, 3 * law.elastic.max_mm)
    st = RigSettings(timestep=timestep, mass_kg=CALIBRATION_MASS_KG, load_cell_hz=0.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = build_rig(rep, params, settings=st)
    outside = any(issubclass(w.category, SkinRangeWarning) for w in caught)
    assert outside == (timestep > 2e-3)  # 5 ms is outside the calibrated range: said so
    data = mujoco.MjData(model)
    data.qvel[0] = -1.0  # the indenter hits the skin at 1 m/s
    depth = []
    for _ in range(int(0.1 / timestep)):
        mujoco.mj_step(model, data)
        depth.append(-1e3 * data.qpos[0])
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    assert max(depth) < 1e3 * BONE_DEPTH_M + 3.0  # the bone stop under the skin holds it
    data = mujoco.MjData(model)
    for k in range(int(2.0 / timestep)):  # 20 N dead weight
        data.qfrc_applied[0] = -20.0 * min(1.0, k * timestep)
        mujoco.mj_step(model, data)
    assert np.all(np.isfinite(data.qpos))
    assert -1e3 * data.qpos[0] < 5.0


def test_rig_rejects_unknown_representation_and_bad_settings():
    with pytest.raises(ValueError, match="representation 'jelly' is unknown"):
        build_rig("jelly")
    with pytest.raises(ValueError, match="timestep"):
        RigSettings(timestep=0.0)
    with pytest.raises(ValueError, match="mass_kg"):
        RigSettings(mass_kg=-1.0)


def test_calibration_file_round_trips_and_foreign_versions_are_refused(tmp_path):
    law = SkinLaw("x", ElasticLaw(knot_vector(1.0, 3), np.array([1.0, 1.0, 1.0])), Prony())
    cal = SkinCalibration("x", law, {}, {"test": True})
    save_calibration(cal, tmp_path)
    back = load_calibration("x", tmp_path)
    assert back.law.elastic.force(0.5) == pytest.approx(law.elastic.force(0.5))
    data = json.loads((tmp_path / "x.json").read_text())
    data["format_version"] = 99
    (tmp_path / "x.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match="format_version 99"):
        load_calibration("x", tmp_path)
    (tmp_path / "x.json").write_text("{not json")
    with pytest.raises(ValueError, match="not a readable calibration"):
        load_calibration("x", tmp_path)
    with pytest.raises(ValueError, match="no calibration for skin 'y'"):
        load_calibration("y", tmp_path)


def test_qlv_record_helper_is_consistent():
    law = ElasticLaw(knot_vector(1.0, 3), np.array([1.0, 1.0, 1.0]))
    t = np.linspace(0, 1, 11)
    np.testing.assert_allclose(qlv_force(law.force(t), t, Prony()), law.force(t))
