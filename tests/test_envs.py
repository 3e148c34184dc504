"""The handshake environment: Gymnasium contract, determinism, hard cases, bad input."""

from __future__ import annotations

import os
import re
import shutil

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)
from softhand.envs import HandshakeEnv
from softhand.envs.controllers import make_controller
from softhand.envs.run import (
    ContactAreas,
    mean_curvature_radius,
    run_handshake,
    sphere_overlap_area,
)
from softhand.envs.skins import SKIN_CHOICES, parse_skins
from softhand.hands import ArmConfig
from softhand.hands.constants import PROSTHETIC
from softhand.skin.files import SKINS_DIR


def _rollout(env: HandshakeEnv, seed: int) -> tuple[np.ndarray, float]:
    obs, info = env.reset(seed=seed)
    total, frames = 0.0, [obs]
    while True:
        a = np.full(6, 0.3 if info["phase"] in ("grip", "shake") else -0.3)
        obs, r, term, trunc, info = env.step(a)
        total += r
        frames.append(obs)
        if term or trunc:
            assert not term, "the simulation became unstable"
            return np.array(frames), total


def test_gym_make_and_check_env():
    env = gym.make("softhand/Handshake-v0", design="pocket2-sil")
    check_env(env.unwrapped, skip_render_check=True)
    assert env.unwrapped.action_space.shape == (6,)


def test_same_seed_same_rollout_and_no_nan():
    env = HandshakeEnv(design="pocket2-sil")
    a, ra = _rollout(env, 3)
    b, rb = _rollout(env, 3)
    np.testing.assert_array_equal(a, b)
    assert ra == rb and np.all(np.isfinite(a))
    c, _ = _rollout(env, 4)
    assert not np.array_equal(a, c)  # the seed varies the partner


def test_bad_input_names_the_value():
    with pytest.raises(ValueError, match="region 'Pinky9' is unknown"):
        parse_skins("pocket2-sil", {"Pinky9": "rigid"})
    with pytest.raises(ValueError, match="skin design 'pocket3-sil' is unknown"):
        HandshakeEnv(design="pocket3-sil")
    env = HandshakeEnv(design="rigid")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="outside the action space"):
        env.step(np.array([2.0, 0, 0, 0, 0, 0]))
    with pytest.raises(ValueError, match="outside the action space"):
        env.step(np.array([np.nan, 0, 0, 0, 0, 0]))


def _episode(env: HandshakeEnv, policy, seed: int = 0) -> dict:
    """Run one episode; return the largest region force, joint speed and arm offset seen."""
    obs, info = env.reset(seed=seed)
    m, d = env.model, env.data
    arm = m.body("hum_arm").id
    worst = {"force_N": 0.0, "qvel": 0.0, "arm_offset_m": 0.0}
    peaks = []
    while True:
        obs, _, term, trunc, info = env.step(policy(obs, info))
        assert np.all(np.isfinite(obs)) and not term, f"unstable at t = {d.time:.3f} s"
        peaks.append(max(info["region_forces_N"].values()))
        worst["force_N"] = max(worst["force_N"], peaks[-1])
        worst["force_p99_N"] = float(np.percentile(peaks, 99))
        worst["qvel"] = max(worst["qvel"], float(np.abs(d.qvel).max()))
        worst["arm_offset_m"] = max(worst["arm_offset_m"],
                                    float(np.linalg.norm(d.mocap_pos[0] - d.xpos[arm])))
        if trunc:
            return worst


def _bounded(worst: dict) -> None:
    # a region's force (its skin and its bone bottoming out under it) stays below the prosthetic
    # motors' 136 N stall grip in 99 % of the steps, and below 1.25x it at the impact of a slam
    # (motors slammed closed at full speed, bone on bone: 92 N with the plate laws; 148 N for one
    # step, 130 N at the 99th percentile, with the geometry laws, whose softer tissue under a
    # finger lets the index's bone reach the partner's palm); joints below 100 rad/s; the
    # partner's arm never more than 5 cm from its target (nothing flies away)
    assert worst["force_p99_N"] < PROSTHETIC["grip_force_n"], worst
    assert worst["force_N"] < 1.25 * PROSTHETIC["grip_force_n"], worst
    assert worst["qvel"] < 100.0, worst
    assert worst["arm_offset_m"] < 0.05, worst


@pytest.mark.parametrize("skin", SKIN_CHOICES)
def test_every_skin_design_runs_a_full_episode_finite_and_bounded(skin):
    _bounded(_episode(HandshakeEnv(design=skin), make_controller("neutral")))


def test_hard_case_partner_squeezes_five_times_harder():
    normal = _episode(HandshakeEnv(), make_controller("neutral"))
    hard = _episode(HandshakeEnv(squeeze=5.0), make_controller("neutral"))
    _bounded(hard)
    assert hard["force_N"] > normal["force_N"]  # the squeeze reaches the skins


def test_hard_case_controller_slams_the_fingers_closed_at_full_speed():
    _bounded(_episode(HandshakeEnv(), lambda obs, info: np.ones(6)))


@pytest.mark.parametrize("timestep_s", [0.0005, 0.001, 0.002])
@pytest.mark.slow
def test_hard_case_timesteps_half_to_two_milliseconds(timestep_s):
    env = HandshakeEnv(timestep_s=timestep_s)
    assert env.frame_skip == round(0.01 / timestep_s)  # actions stay at 100 Hz
    _bounded(_episode(env, make_controller("open-loop")))


@pytest.mark.parametrize("controller", ["neutral", "open-loop", "force"])
@pytest.mark.slow
def test_default_timestep_reproduces_half_a_millisecond(controller):
    """The 2 ms default against 0.5 ms, same partner and controller: every region's mean force
    within 0.35 N and the summed mean forces within 8 % (measured at seed 1 for the whole-hand
    skin; the benchmark's worst of seeds 0-3, neutral / open-loop / force: 0.01 / 0.11 / 0.01 N and
    -0.6 / -6.1 / +0.2 %; before the partner's joints had armature: 0.45 N, and sums off by -7 % to
    -52 %)."""
    fine = run_handshake(controller=controller, seed=1, timestep_s=0.0005).table()
    coarse = run_handshake(controller=controller, seed=1).table()
    diffs = [abs(coarse[r]["mean_N"] - v["mean_N"]) for r, v in fine.items()]
    assert max(diffs) < 0.35, dict(zip(fine, np.round(diffs, 3), strict=True))
    total = sum(v["mean_N"] for v in fine.values())
    assert sum(v["mean_N"] for v in coarse.values()) == pytest.approx(total, rel=0.08)


def _one_and_two_milliseconds_agree(controller: str, seed: int) -> None:
    fine = run_handshake(controller=controller, seed=seed, timestep_s=0.001).table()
    coarse = run_handshake(controller=controller, seed=seed, timestep_s=0.002).table()
    loaded = [r for r, v in fine.items() if v["peak_N"] > 1.0]
    assert loaded
    for r in loaded:
        for what in ("peak_N", "mean_N"):
            assert coarse[r][what] == pytest.approx(fine[r][what], rel=0.05), (r, what)


@pytest.mark.parametrize("controller", ["neutral", "open-loop", "force"])
@pytest.mark.slow
def test_one_and_two_milliseconds_agree_within_5_percent_on_every_region_over_1_n(controller):
    """Issue 35, item 7: 2 ms against 1 ms, same partner and controller (seed 0), every region
    whose peak passes 1 N: its peak and its mean within 5 % (measured: worst peak 4.6 %, Palm1's
    grip transient, neutral). Before the clock's slack (partner.CLOCK_SLACK_S) the
    open-loop close took one action more at 1 ms and its middle phalanges were 8-10 % apart."""
    _one_and_two_milliseconds_agree(controller, seed=0)


@pytest.mark.slow
@pytest.mark.xfail(strict=True, raises=AssertionError, reason=(
    "issue 35, item 7: at seed 1 Back1's grip transient peaks at 8.96 N at 2 ms against 7.28 N "
    "at 1 and 0.5 ms (23 %; reports/bench-handshake.md, worst of seeds 0-3): the partner's "
    "index middle phalanx on the palm's wrist-crease face lies inside Back1's zone at 2 ms only"))
def test_one_and_two_milliseconds_agree_at_seed_1():
    """The same bar at seed 1, where at the grip's peak (1.04 s) the partner's index middle
    phalanx presses the palm's proximal end (its flat wrist-crease face) with 3.1-3.3 N at both
    timesteps, at the edge of Back1's zone (the palm's mid-plane): 3.5 mm outside it at 1 ms,
    1.8 mm inside at 2 ms, so Back1 reads it at 2 ms only (the mean within 2 %). Expected to
    fail until a region's reading does not step at a zone's edge, or the contact lies where both
    timesteps put it (strict: it fails the suite once it passes, so that the mark comes off)."""
    _one_and_two_milliseconds_agree("neutral", seed=1)


def test_open_loop_closes_for_the_same_number_of_actions_at_every_timestep():
    """The open-loop close lasts close_s of the simulation clock, a sum of timesteps that lands
    on it from either side: the motors' commanded positions at the end of the grip are the same
    at 0.5, 1 and 2 ms (to 1e-5 rad: measured 1.2e-6 at most, one motor, since the border's
    oblique pairs took the tissue's crossing laws, 1e-6 before; one action apart they differed
    by 0.0094 rad)."""
    ends = []
    for ts in (0.0005, 0.001, 0.002):
        env = HandshakeEnv(timestep_s=ts)
        ctrl = make_controller("open-loop")
        obs, info = env.reset(seed=0)
        while info["phase"] != "hold":
            obs, _, _, _, info = env.step(ctrl(obs, info))
        ends.append(env.data.act[:6].copy())
        env.close()
    np.testing.assert_allclose(ends[0], ends[1], atol=1e-5)
    np.testing.assert_allclose(ends[1], ends[2], atol=1e-5)


def test_the_hold_is_read_once_the_shakes_last_swing_has_died_out():
    """Issue 35, item 4: the hold begins where the shake ends, and the shake's last swing rings
    on through the arms for about 0.18 s. Read from a quarter second in (HOLD_SETTLE_S), a
    memoryless skin's hold keeps the force between the hands within 0.3 % (measured -0.005 %,
    seed 0); read from the hold's first instant the same run "fell" by 1.07 %, the swing's phase."""
    from softhand.envs.run import HOLD_SETTLE_S

    run = run_handshake(seed=0)
    hold = run.hold_relaxation()
    assert hold["settle_s"] == pytest.approx(HOLD_SETTLE_S, abs=0.011)
    assert abs(hold["decay_pct"]) < 0.3, hold
    assert abs(run.hold_relaxation(settle_s=0.0)["decay_pct"]) > 0.5  # the swing, unsettled


def test_partner_joints_stay_within_their_ranges_under_a_5x_squeeze():
    """Joint limits hold within 3 deg over a full episode with the partner gripping 5x harder and
    the prosthetic closing open loop (without armature the distal joints went 0.95 rad past)."""
    run = run_handshake(controller="open-loop", seed=1, squeeze=5.0)
    m = run.model
    for j in np.flatnonzero(m.jnt_limited):
        q = run.qpos[:, m.jnt_qposadr[j]]
        lo, hi = m.jnt_range[j]
        past = max(float(np.max(lo - q)), float(np.max(q - hi)), 0.0)
        assert past < np.radians(3.0), f"{m.joint(j).name} {np.degrees(past):.1f} deg past its limit"


def test_corrupt_calibration_file_names_the_file(tmp_path):
    for f in SKINS_DIR.glob("*.json"):
        shutil.copy(f, tmp_path / f.name)
    (tmp_path / "pocket2-sil.json").write_text("{ not json")
    with pytest.raises(ValueError, match="pocket2-sil"):
        HandshakeEnv(design="pocket2-sil", calibration_dir=tmp_path)


def test_contact_area_is_the_overlap_circle_of_two_spheres():
    """Two spheres (R1 = 10 mm, R2 = 30 mm) pressed 1 mm into each other: the circle where the
    surfaces cross has area 2 pi R1 R2 / (R1 + R2) delta (to first order in delta)."""
    model = mujoco.MjModel.from_xml_string("""
    <mujoco><worldbody>
      <geom name="skin_A" type="sphere" size="0.010"/>
      <body pos="0 0 0.039"><freejoint/><geom name="tissue_B" type="sphere" size="0.030"/></body>
      <body pos="0.2 0 0"><freejoint/><geom name="bone_a" type="capsule" size="0.01 0.02"/></body>
      <body pos="0.2 0 0.0195"><freejoint/><geom name="bone_b" type="sphere" size="0.01"/></body>
    </worldbody></mujoco>""")
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert mean_curvature_radius(model, 0) == 0.010
    assert mean_curvature_radius(model, 2) == pytest.approx(0.020)  # capsule: 2 r
    area, rigid, rows = ContactAreas(model, [0])(data)
    assert rows.shape == (2, 7) and np.all(rows[:, 6] > 0)  # two contacts, positive forces
    d, r1, r2 = 39.0, 10.0, 30.0  # exact circle of intersection of the two sphere surfaces
    exact = np.pi * (4 * d**2 * r1**2 - (d**2 - r2**2 + r1**2) ** 2) / (4 * d**2)
    assert area[0] == pytest.approx(exact, rel=1e-9)  # mm^2
    assert area[0] == pytest.approx(2 * np.pi * 10 * 30 / 40 * 1.0, rel=0.05)  # first order
    # saturates at the smaller cross-section, never grows without bound with the depth
    assert sphere_overlap_area(0.01, 0.03, 0.05) == pytest.approx(np.pi * 1e-4)
    assert sphere_overlap_area(0.01, 0.03, -0.001) == 0.0
    assert rigid > 0.0  # the bone capsule and bone sphere touch: force counted as bone on bone


def test_ellipsoid_mean_curvature_radius_at_its_flattest_pole():
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><geom type="ellipsoid" size="0.02 0.01 0.005"/></worldbody></mujoco>')
    # principal radii at the 5 mm pole: 20^2/5 = 80 mm and 10^2/5 = 20 mm; harmonic mean 32 mm
    assert mean_curvature_radius(model, 0) == pytest.approx(0.032)


@pytest.mark.slow
def test_force_accounting_adds_up_and_follows_the_skins():
    """Classes add up to the total; rigid regions carry no skin law; a skin run does."""
    from softhand.envs.run import ACCOUNT_CLASSES

    rigid = run_handshake(design="rigid", seed=0).force_accounting()
    assert rigid["skin_law_Ns"] == 0.0 and rigid["calibrated_share_pct"] == 0.0
    skin = run_handshake(seed=0).force_accounting()
    parts = sum(skin[f"{k}_Ns"] for k in ACCOUNT_CLASSES)
    assert parts == pytest.approx(skin["total_Ns"], rel=1e-12) and skin["total_Ns"] > 0
    assert 0.0 < skin["calibrated_share_pct"] <= 100 * skin["skin_law_Ns"] / skin["total_Ns"]
    assert 0.0 <= skin["out_of_range_time_pct"] <= 100.0
    assert skin["bone_on_bone_peak_N"] >= 0.0
    assert 0.0 <= skin["unsensed_skin_Ns"] <= skin["skin_law_Ns"] + 1e-12


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_the_default_handshake_stays_inside_its_laws_at_other_partners_seeds(seed):
    """Issue 35, item 5 beyond seed 0: the default run of seeds 1-4 ends without a range
    warning, all of its pair force inside its laws' calibrated ranges. The largest carrier, the
    partner's thumb metacarpal on the palm's radial border (border/finger@30), peaks at
    8.4-10.9 N; on the tissue's plate data alone (8.7 N) seeds 1, 2 and 4 warned; with the
    tissue FE of its class (to 11.6 N, `tissue_class_depths`) none does."""
    import warnings

    from softhand.envs.skins import CalibratedRangeWarning

    with warnings.catch_warnings():
        warnings.simplefilter("error", CalibratedRangeWarning)
        run = run_handshake(seed=seed)
    assert run.force_accounting()["calibrated_share_pct"] >= 99.9


@pytest.mark.slow
def test_default_handshake_accounts_for_every_newton_and_the_partner_grips_like_a_person():
    """The default handshake (seed 0, pocket2-sil, neutral) in the grasp solved from its contacts:
    all the force between the hands through a skin x tissue law, inside its calibrated range for
    >= 99 % of it and no range warning at the episode's end (the main job ends without one), no
    bone on bone, none through a bare shell; the partner's summed digit force
    follows its sampled grip within 15 % (95th percentile over the grip and shake, after its
    0.2 s close); no hand more than 1.5 mm inside itself at any step (the partner's thumb pad
    on its middle fingertip, a stop as stiff as MuJoCo integrates at 2 ms, `partner.SELF_SOLREF`:
    two pulps pressed together compress several mm each at a few N, so 1.5 mm of overlap is
    a stop that holds, not a thumb through a finger); the partner's joints stay inside their
    ranges (MuJoCo's limits are soft: 3 deg)."""
    import warnings

    from softhand.envs.skins import CalibratedRangeWarning
    from softhand.hands.grasp import grasp_metrics
    from softhand.hands.layout import hand_layout

    with warnings.catch_warnings():
        warnings.simplefilter("error", CalibratedRangeWarning)
        run = run_handshake(seed=0)
    acc = run.force_accounting()
    assert acc["tissue_law_only_Ns"] == 0.0 and acc["no_law_Ns"] == 0.0  # no bare shell
    # measured 100.0 % since the partner's phalanx crossed obliquely by the palm's border takes
    # the tissue's crossing law (TISSUE_CROSSINGS: the partner's thumb metacarpal, 7.9 N at
    # about 30 deg, rests on the tissue's data to 8.7 N and on its FE to 11.6 N); 64.7 % before,
    # when every finger-like contact on the partner counted 4.8 N (tissue_class_data_range);
    # 97.3 % counted to 7 N
    assert acc["calibrated_share_pct"] >= 99.0, acc
    assert acc["bone_on_bone_Ns"] == 0.0 and acc["bone_on_bone_peak_N"] == 0.0, acc
    kin = run.kinematics()
    assert kin["partner_beyond_range_deg"]["max"] < 3.0, kin  # soft limits, 3 deg
    checks = run.grasp_checks()
    # the palms press each other at mid-shake (measured -3.0 mm: pressed; 0.6 mm apart when the
    # grasp rolled the partner's palm, test_the_palms_meet_and_carry_force_through_the_handshake
    # measures their force); each thumb pad lies over the other hand's back (its dorsal skin is
    # 15 mm from its mid-plane: measured 29 and 37 mm); no partner joint reaches a stop while it
    # holds (measured 4.9 deg)
    assert checks["palm_gap_mm"]["Palm"] < 1.0, checks
    assert all(v[2] > 15.0 for v in checks["thumb_tip_in_other_mm"].values()), checks
    assert checks["partner_limit_margin_deg"] > 2.0, checks
    # measured 1.17 mm in one 10 ms frame as the partner closes (t = 1.07 s; 0.54 mm the next),
    # since the border's law is the 40 mm stand-in's (0.71 mm before)
    assert max(checks["self_penetration_mm"].values()) < 1.5, checks
    env = HandshakeEnv()
    controller = make_controller("neutral")
    obs, info = env.reset(seed=0)
    pro, hum = hand_layout(env.config.prosthetic.hand), hand_layout(env.config.partner.hand)
    errors, worst = [], 0.0
    grip_start = env.scenario.script.timeline.ends[0] + 0.25
    while True:
        obs, _, term, trunc, info = env.step(controller(obs, info))
        if info["phase"] in ("grip", "shake") and info["time_s"] > grip_start:
            errors.append(abs(info["partner_grip_measured_N"] / info["partner_grip_N"] - 1))
        m = grasp_metrics(env.model, env.data, pro, hum)
        worst = max(worst, *m["self_penetration_mm"].values())
        if term or trunc:
            break
    assert np.percentile(errors, 95) < 0.15, np.percentile(errors, 95)  # measured 8.6 %
    assert worst < 1.5, worst  # the partner's thumb on its fingers, at every step


def test_each_pair_of_geoms_touches_in_one_point_so_the_law_holds_per_pair():
    """The skin laws are per contact point (calibrated on one-point contacts): with MuJoCo's
    multiccd on (its default) a phalanx capsule lying on a palm mesh touched in two points, twice
    as stiff as calibrated (15 % of the default handshake's force); the scene turns it off, and no
    geom pair has two contacts at any step of the default handshake."""
    env = HandshakeEnv()
    ctrl = make_controller("neutral")
    obs, info = env.reset(seed=0)
    most = 0
    while True:
        obs, _, term, trunc, info = env.step(ctrl(obs, info))
        d = env.data
        pairs = [tuple(sorted(c.geom)) for c in d.contact[:d.ncon]] if d.ncon else []
        most = max(most, max((pairs.count(p) for p in set(pairs)), default=0))
        if term or trunc:
            break
    assert most == 1


@pytest.mark.slow
@pytest.mark.parametrize("controller", ["neutral", "open-loop", "force"])
def test_bones_never_meet_with_any_shipped_skin_at_the_defaults(controller):
    """Issue 11's requirement: with every shipped skin and each controller at its default
    settings (seed 0), no bone-on-bone contact at any physics step (accounting at every 2 ms
    step, not only at the 100 Hz frames). Measured: 0 N for all 14 skins x 3 controllers (before
    the bones were inset by the skin thickness, the force controller pressed 30.7 N bone on
    bone, a fingertip on the partner's little metacarpal head and the two little fingers in the
    release)."""
    import warnings

    from softhand.envs.skins import CalibratedRangeWarning

    peaks = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CalibratedRangeWarning)  # reported, not at issue here
        for skin in SKIN_CHOICES:
            acc = run_handshake(design=skin, controller=controller, seed=0,
                                record_every=1).force_accounting()
            peaks[skin] = acc["bone_on_bone_peak_N"]
    assert all(v == 0.0 for v in peaks.values()), peaks


def test_contact_beyond_the_calibrated_range_warns_once_per_episode():
    """A 5x squeeze drives contacts past the 7 N the pair laws are calibrated to: one
    CalibratedRangeWarning for the episode (not one per pair or step) that names the worst pair,
    and the info counts them (tests/test_env_inputs.py checks the summary)."""
    from softhand.envs.skins import CalibratedRangeWarning

    env = HandshakeEnv(squeeze=5.0)
    ctrl = make_controller("open-loop")
    obs, info = env.reset(seed=1)
    beyond = 0
    with pytest.warns(CalibratedRangeWarning) as caught:
        while True:
            obs, _, term, trunc, info = env.step(ctrl(obs, info))
            beyond += info["contacts_beyond_range"]
            if term or trunc:
                break
    ranged = [str(w.message) for w in caught if issubclass(w.category, CalibratedRangeWarning)]
    worst = info["beyond_range_summary"]["worst_pair"]
    assert len(ranged) == 1 and f"pair {worst}, carried" in ranged[0], ranged
    assert beyond >= info["beyond_range_summary"]["pairs"] > 1
    assert all("calibrated to" in str(w.message) for w in caught
               if issubclass(w.category, CalibratedRangeWarning))


@pytest.mark.slow
def test_shipped_mjcf_is_the_simulated_model():
    """models/mjcf/handshake_scene.xml, loaded by plain MuJoCo and fed the env's inputs, gives the
    env's region forces (skin and bone sensors) at every step (to 1e-9 N): the skin laws are in
    the MJCF."""
    from pathlib import Path

    xml = Path(__file__).resolve().parents[1] / "models" / "mjcf" / "handshake_scene.xml"
    model = mujoco.MjModel.from_xml_path(str(xml))  # no softhand code from here on
    data = mujoco.MjData(model)
    env = HandshakeEnv(frame_skip=1)  # one physics step per action: the inputs of every step
    ctrl = make_controller("neutral")
    obs, info = env.reset(seed=0)
    state = mujoco.mjtState.mjSTATE_INTEGRATION
    buf = np.empty(mujoco.mj_stateSize(env.model, state))
    mujoco.mj_getState(env.model, env.data, buf, state)
    mujoco.mj_setState(model, data, buf, state)
    # contact sensors, slots of (found, force xyz): each region's skin and its bones under it
    names = [model.sensor(i).name for i in range(model.nsensor)]
    slots = [[(model.sensor(n).adr[0], model.sensor(n).dim[0]) for n in names
              if n == f"pro_touch_{r}" or n.startswith(f"pro_touch_bone_{r}_")]
             for r in env.region_names]
    worst, steps, total = 0.0, 0, 0.0
    while True:
        obs, _, term, trunc, info = env.step(ctrl(obs, info))
        data.ctrl[:] = env.data.ctrl
        data.mocap_pos[:] = env.data.mocap_pos
        data.mocap_quat[:] = env.data.mocap_quat
        mujoco.mj_step(model, data)
        forces = np.array([info["region_forces_N"][r] for r in env.region_names])
        plain = np.array([sum(data.sensordata[a:a + n].reshape(-1, 4)[:, 1].sum() for a, n in s)
                          for s in slots])
        worst = max(worst, float(np.abs(plain - forces).max()))
        total += forces.sum()
        steps += 1
        if term or trunc:
            break
    assert steps > 1000 and total > 100.0  # a whole handshake, with contact
    assert worst <= 1e-9


def test_a_region_has_contact_area_exactly_when_its_sensor_reads_force():
    """Areas count the contacts inside a region's sensor zone, as its force does: the unsensed
    skin (dorsal phalanges, palm borders) adds to neither (before, Back2 showed 701 mm^2 at 0 N)."""
    table = run_handshake(seed=0).table()
    for region, v in table.items():
        assert (v["peak_area_mm2"] > 0) == (v["peak_N"] > 0), (region, v)
    assert sum(v["peak_N"] > 0 for v in table.values()) >= 5


def test_bone_bottoming_out_under_a_region_is_in_its_reading():
    """Motors slammed closed through the grip: the prosthetic's bones meet the partner's. Every
    newton of that bone-on-bone contact inside a region's sensor zone, on that region's body, is
    in the reading of that region (``info["region_bone_N"]``, part of ``region_forces_N``), the
    overload term sees it and it counts as beyond calibration; a bone contact outside every zone
    (a phalanx's dorsal half, the thumb's metacarpal under the thenar) is unsensed, as its skin's
    is. The arms are made stiff (5 kN/m, 50 N m/rad): on the default ones the hands give way and
    the bones never meet (measured at the peak: 14.2 N on Index1, 18.3 N on Index2 and 21.1 N on
    the dorsal side of Middle1's bone, unsensed)."""
    from softhand.envs.run import _box_contains

    stiff = {"stiffness_n_per_m": 5000.0, "rot_stiffness_nm_per_rad": 50.0}
    env = HandshakeEnv(sensored_arm=ArmConfig.of("prosthesis-user", **stiff),
                       partner_arm=ArmConfig.of("active", **stiff))
    _, info = env.reset(seed=0)
    m, d = env.model, env.data
    bones = {g for g in range(m.ngeom) if m.geom(g).name.startswith("pro_bone")}
    zones = {r: (m.site(f"pro_touch_{r}").id, int(m.geom(env.region_geoms[i]).bodyid[0]))
             for i, r in enumerate(env.region_names)}
    peak = (0.0, None, None)
    while True:
        action = np.ones(6) if info["phase"] in ("grip", "shake", "hold") else np.zeros(6)
        _, _, term, trunc, info = env.step(action)
        inside = dict.fromkeys(env.region_names, 0.0)
        contact = 0.0
        for c in d.contact:
            if c.efc_address < 0 or not (c.geom[0] in bones or c.geom[1] in bones):
                continue
            f = d.efc_force[c.efc_address]
            contact += f
            g = c.geom[0] if c.geom[0] in bones else c.geom[1]
            for r, (site, body) in zones.items():
                if m.geom_bodyid[g] == body and _box_contains(d, m, site, c.pos):
                    inside[r] += f
        if contact > peak[0]:
            peak = (contact, info, inside)
        if term or trunc:
            break
    contact, at, inside = peak
    assert contact > 10.0, contact
    bone = at["region_bone_N"]
    for r in env.region_names:
        assert bone[r] == pytest.approx(inside[r], rel=1e-9, abs=1e-9), (r, bone, inside)
    assert sum(bone.values()) > 10.0, bone
    assert all(at["region_forces_N"][r] >= v for r, v in bone.items())
    assert at["contacts_beyond_range"] >= sum(v > 0 for v in bone.values())
    assert at["reward_terms"]["overload"] < 0.0


@pytest.mark.slow
def test_human_hand_runs_the_papers_protocol_whatever_the_action():
    """hand="human": human tissue on every region (the human law in series with the partner's),
    soft position servos instead of motors, surface sensors; the relaxed hand follows its own
    neutral script, so two episodes with different actions are identical; everything through a
    calibrated law, no bone on bone (measured 100 %, 0 N at seed 0)."""
    from softhand.laws.references import HUMAN

    env = HandshakeEnv(hand="human")
    assert set(env.skins.values()) == {HUMAN} and set(env.sensor_placements.values()) == {"surface"}
    m = env.model
    drives = [m.actuator(a).id for a in ("pro_index_motor", "pro_thumb_rot_motor")]
    assert all(m.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_AFFINE for a in drives)
    assert all(m.actuator_dyntype[a] == mujoco.mjtDyn.mjDYN_NONE for a in drives)  # no setpoint
    forces = []
    for action in (np.zeros(6), np.ones(6)):
        _, info = env.reset(seed=0)
        trace = []
        while True:
            _, _, term, trunc, info = env.step(action)
            trace.append(list(info["region_forces_N"].values()))
            if term or trunc:
                break
        forces.append(np.array(trace))
    np.testing.assert_array_equal(forces[0], forces[1])
    acc = run_handshake(env=env, seed=0).force_accounting()
    # measured 68.9 % since the relaxed hand's border has its crossing laws (stiffer at 30 deg:
    # the partner's thumb metacarpal carries 13.5 N on the 30 deg law, whose tissue FE stops at
    # 3.72 mm, 6.7 N of data); 72.0 % before (72.2 % before its class laws' ranges ended where
    # the tissue's data do) with the palm one surface: human tissue on both hands, the partner's
    # thumb metacarpal 14 mm into the relaxed hand's back in one contact, past the tissue's data
    # (98.0 % when the palm was four skins, whose seams split those indentations between two
    # contacts; 99+ % on a fixed hand before the arms)
    assert acc["calibrated_share_pct"] >= 65.0 and acc["bone_on_bone_peak_N"] == 0.0, acc


@pytest.mark.parametrize("kwargs, needle", [
    ({"hand": "robot"}, "hand = 'robot': allowed prosthetic, human"),
    ({"hand": "human", "design": "pocket2-sil"}, "design = 'pocket2-sil'"),
    ({"hand": "human", "representation": "rigid"}, "representation = 'rigid'"),
])
def test_bad_hand_arguments_name_the_value(kwargs, needle):
    with pytest.raises(ValueError, match=re.escape(needle)):
        HandshakeEnv(**kwargs)


def test_a_new_touch_is_a_scenario_not_a_copy_of_the_env():
    """The scenario seam: "a hand held still" (the handshake's reach and grip, the mount held at
    the grasp instead of shaking) is a 6-line Scenario subclass run by the generic two-hand touch
    env; the handshake's shake moves the mount +-5 mm, the held hand not at all."""
    from softhand.envs.scenarios import HandshakeScenario
    from softhand.envs.touch import TwoHandTouchEnv

    class HeldStill(HandshakeScenario):
        name = "held-still"

        def mount(self, t):
            pos = self.script.mount(t)
            return self.script.contact.copy() if self.phase(t) == "shake" else pos

    swings = {}
    for scenario in (HandshakeScenario(), HeldStill()):
        env = TwoHandTouchEnv(scenario=scenario)
        _, info = env.reset(seed=0)
        z, touched = [], 0.0
        while True:
            _, _, term, trunc, info = env.step(np.zeros(6))
            if info["phase"] == "shake":
                z.append(env.data.mocap_pos[0, 2])
                touched = max(touched, sum(info["region_forces_N"].values()))
            if term or trunc:
                break
        swings[scenario.name] = (max(z) - min(z), touched)
    assert swings["handshake"][0] > 5e-3 and swings["held-still"][0] == 0.0, swings
    assert swings["held-still"][1] > 1.0, swings  # the hands hold each other in both


def test_info_names_an_overload_at_the_step_it_starts():
    """``info["overload_started"]`` names each region at the step its load first passes
    ``overload_N`` (here 1 N, so that the default handshake passes it), with its load, and
    not again while it stays over; the episode's summary keeps the first such step; a bone
    bottoming out is named as "{region} bone" (motors slammed closed on stiff arms)."""
    env = HandshakeEnv(overload_N=1.0)
    obs, info = env.reset(seed=0)
    policy = make_controller("neutral")
    over = dict.fromkeys(env.region_names, False)
    first = None
    while True:
        obs, _, term, trunc, info = env.step(policy(obs, info))
        forces = info["region_forces_N"]
        started = {k: v for k, v in info["overload_started"].items() if not k.endswith(" bone")}
        expected = {r: f for r, f in forces.items() if f > 1.0 and not over[r]}
        assert started == expected, (info["time_s"], started, expected)
        if started and first is None:
            first = (info["time_s"], started)
        over = {r: f > 1.0 for r, f in forces.items()}
        if term or trunc:
            break
    assert first is not None
    summary = info["beyond_range_summary"]
    assert summary["first_overload_time_s"] == pytest.approx(first[0])
    assert {k: v for k, v in summary["first_overload"].items()
            if not k.endswith(" bone")} == first[1]
    stiff = {"stiffness_n_per_m": 5000.0, "rot_stiffness_nm_per_rad": 50.0}
    env = HandshakeEnv(sensored_arm=ArmConfig.of("prosthesis-user", **stiff),
                       partner_arm=ArmConfig.of("active", **stiff))
    _, info = env.reset(seed=0)
    named = set()
    while True:
        action = np.ones(6) if info["phase"] in ("grip", "shake", "hold") else np.zeros(6)
        _, _, term, trunc, info = env.step(action)
        named |= {k for k, v in info["overload_started"].items() if k.endswith(" bone")}
        if any(v > 0 for v in info["region_bone_N"].values()):
            assert named, info["region_bone_N"]
        if term or trunc:
            break
    assert named <= {f"{r} bone" for r in env.region_names} and named


@pytest.mark.parametrize("seed, hand", [(0, "prosthetic"), (1, "prosthetic"), (0, "human")])
def test_no_indentation_is_counted_twice_at_a_seam(seed, hand):
    """Where one partner geom touches two skin geoms at points under 2 mm apart (a seam between
    two skins, a crease at a knuckle), the smaller contact is an indentation resisted twice: its
    share of the force between the hands, while they hold each other. With the palm one surface:
    measured 0.0 % (prosthetic, seeds 0 and 1; human hand); 0.8 %, 0.9 % and 2.1 % when the palm
    was four skins, 12-15 % and 2.3 % before the hands rode arms (reports/load-path.md)."""
    run = run_handshake(seed=seed, hand=hand)
    share = run.double_count()["double_share_pct"]
    assert 0.0 <= share < 0.1, share


@pytest.mark.parametrize("seed, hand", [(0, "prosthetic"), (3, "prosthetic"), (0, "human")])
def test_the_palms_meet_and_carry_force_through_the_handshake(seed, hand):
    """Issue 35, item 1, the outcome: while the hands hold each other, the sensored palm's palmar
    face presses the partner's palm piece (not a thumb or a finger on a palm, not the thenars)
    with a share of the force between the hands. Measured with the palms held parallel by the
    grasp (GraspSettings.palm_align_weight 0.2): 4.4 and 4.2 % (prosthetic, seeds 0 and 3),
    6.7 % (human hand); 0.0 % when the grasp rolled the partner's palm 14.5 deg onto one edge
    (weight 0.02, reports/palm-alignment.md)."""
    share = run_handshake(seed=seed, hand=hand).palm_on_palm()
    assert share["palm_share_pct"] > 2.0, share
    assert share["with_thenars_pct"] >= share["palm_share_pct"]


def test_each_contact_on_the_palm_surface_is_one_zones():
    """The palm's one skin carries Palm1, Palm2, Back1 and Back2 as zones: at mid-shake the
    zones' skin forces (ContactAreas.region_at: inside a zone, that one; on a border, the nearest)
    add up to the normal force of every contact on the palm's skin, counted once, and each
    zone's reading (its sensor: contacts inside its zone) is at most its skin force."""
    from softhand.envs.controllers import make_controller
    from softhand.envs.run import ContactAreas

    env = HandshakeEnv()
    policy = make_controller("neutral")
    obs, info = env.reset(seed=0)
    while env.data.time < 1.9:
        obs, _, _, _, info = env.step(policy(obs, info))
    m, d = env.model, env.data
    areas = ContactAreas(m, [m.geom(g).id for g in env.region_geoms], None,
                         [m.site(f"pro_touch_{r}").id for r in env.region_names])
    areas(d)
    palm, total, ft = m.geom("pro_skin_Palm").id, 0.0, np.zeros(6)
    for i in range(d.ncon):
        if palm in (d.contact[i].geom1, d.contact[i].geom2) and d.contact[i].efc_address >= 0:
            mujoco.mj_contactForce(m, d, i, ft)
            total += ft[0]
    zones = [env.region_names.index(z) for z in ("Palm1", "Palm2", "Back1", "Back2")]
    assert total > 5.0  # the palm is loaded (measured 26 N)
    assert areas.skin_force[zones].sum() == pytest.approx(total, rel=1e-12)
    for z in zones:
        assert info["region_forces_N"][env.region_names[z]] <= areas.skin_force[z] + 1e-9


def test_the_env_refuses_pickle_and_deepcopy_in_one_line():
    """Pickling or deep-copying the env is refused with one TypeError that says why and what to
    do instead (it failed deep inside with "cannot pickle 'mujoco._structs.MjOption'"); a
    shallow copy shares the simulation (the vector env's worlds of one scene)."""
    import copy
    import pickle

    env = HandshakeEnv()
    for attempt in (pickle.dumps, copy.deepcopy):
        with pytest.raises(TypeError, match=r"^HandshakeEnv cannot be pickled or deep-copied: .*"
                                            r"make another with the same arguments"):
            attempt(env)
    pickle.loads(pickle.dumps((env.model, env.data)))  # MuJoCo's own pickle
    assert copy.copy(env).data is env.data


def test_render_works_headless_without_mujoco_gl():
    """On a machine without a display and without MUJOCO_GL, importing softhand picks EGL (else
    OSMesa) before mujoco is imported, as the command line does, so env.render() works out of
    the box (it ended in mujoco.FatalError)."""
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items()
           if k not in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY", "PYOPENGL_PLATFORM")}
    code = ("import os, softhand; from softhand.envs import HandshakeEnv; "
            "e = HandshakeEnv(render_mode='rgb_array'); e.reset(seed=0); "
            "print(os.environ['MUJOCO_GL'], e.render().shape)")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    gl, shape = out.stdout.split(maxsplit=1)
    assert gl in ("egl", "osmesa") and shape.strip() == "(480, 640, 3)", out.stdout


@pytest.mark.parametrize("size", [{180.0: 1, 85.0: 2}, "18", b"18", (180.0,), (180.0, 85.0, 1.0)])
def test_a_partner_size_that_is_not_two_numbers_is_refused(size):
    """partner_size is a sequence of two numbers (length, width mm); a mapping (its keys were
    taken as the size), a string or another length is one ValueError naming it."""
    from softhand.envs.partner import check_partner_size

    with pytest.raises(ValueError, match=r"partner_size = .*expected \(length_mm, width_mm\)"):
        check_partner_size(size)
