"""Embedded sensors on the hand (softhand.sensors, softhand.envs.sensing).

* the transfer law's hereditary recursion is exact (a step of the share against K(t) in closed
  form), and the env's online bank gives the batch law's reading (to its tabulated share's
  1e-5 N, carried on by the hereditary sums: 5e-5 N);
* the fit recovers a known law (dead band, share, kernel) from synthetic records;
* the shipped transfer laws exist for every design and placement, match the FE records they were
  fitted to and validated on within the docs' tolerances (docs/sensors.md), and keep the FE's dead band: a
  pocket-floor law reads exactly 0 until the pocket closes;
* the electronics: latency, sampling, threshold, saturation, quantization, seeded noise,
  hysteresis, each against its exact answer;
* the env: the observation carries the readings by default, ``info`` the true forces; bad input
  names the value.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from softhand.fem.geometry import DESIGNS, parse_design
from softhand.laws.elastic import ElasticLaw, knots_at
from softhand.paths import SENSORS_DIR
from softhand.sensors.calibrate import load_transfer_laws, read_records
from softhand.sensors.device import FLEXIFORCE_A101, SensorChain, SensorSpec, TransferBank
from softhand.sensors.transfer import SensorRecord, ShareKernel, TransferLaw, fit_transfer

#: the claims for the shipped laws (docs/sensors.md), % of the reading at the 20 N peak (fitted at
#: 0.5 mm/s and validated at 2 mm/s alike), and up to 2 N in % of the reading at 2 N
RMS_PCT, RAMP_MAX_PCT, HOLD_MAX_PCT, TO_2N_PCT = 1.0, 2.5, 2.0, 6.0

LAWS = load_transfer_laws(SENSORS_DIR / "transfer.json")


def _linear_share(slope: float, top: float = 20.0) -> ElasticLaw:
    """g(u) = slope * u (a constant-stiffness quadratic spline)."""
    knots = knots_at(top, ())
    return ElasticLaw(knots, np.full(knots.size - 3, slope))


def _law(dead=0.0, slope=0.3, c=(), tau=()) -> TransferLaw:
    return TransferLaw("pocket2-sil", "pocket-floor", 16.0, dead, _linear_share(slope),
                       ShareKernel(c, tau), 20.0)


# --- the law -------------------------------------------------------------------------------------
def test_kernel_of_a_step_is_the_closed_form():
    c, tau = (0.2, -0.1), (0.5, 4.0)
    law = _law(slope=0.5, c=c, tau=tau)
    t = np.concatenate([[0.0, 1e-6], np.linspace(0.01, 20.0, 400)])
    load = np.where(t > 0, 2.0, 0.0)
    k = 1 - sum(ci * (1 - np.exp(-t[1:] / ti)) for ci, ti in zip(c, tau, strict=True))
    np.testing.assert_allclose(law.reading(t, load)[1:], 1.0 * k, rtol=0, atol=5e-5)


def test_dead_band_reads_zero_until_the_load_passes_it():
    law = _law(dead=0.4, slope=0.3)
    t = np.linspace(0, 4, 401)
    load = 0.5 * t  # 0.5 N/s
    r = law.reading(t, load)
    assert np.all(r[load <= 0.4] == 0.0)
    np.testing.assert_allclose(r[load > 0.4], 0.3 * (load[load > 0.4] - 0.4), rtol=1e-12)


def test_online_bank_equals_the_batch_law():
    rng = np.random.default_rng(3)
    law = next(v for (d, p), v in LAWS.items() if p == "pocket-floor")
    other = LAWS[("solid-pu", "bone")]
    bank = TransferBank([law, other, None], 0.01)
    t = np.arange(300) * 0.01
    loads = np.abs(np.cumsum(rng.normal(0, 0.3, (300, 3)), axis=0))
    loads[0] = 0.0
    online = np.array([bank.step(f) for f in loads[1:]])
    # the same recursion; the bank's share is tabulated (1e-5 N: next test), whose error the
    # hereditary sums carry on
    np.testing.assert_allclose(online[:, 0], law.reading(t, loads[:, 0])[1:], atol=5e-5)
    np.testing.assert_allclose(online[:, 1], other.reading(t, loads[:, 1])[1:], atol=5e-5)
    np.testing.assert_allclose(online[:, 2], loads[1:, 2], atol=0)  # ideal surface sensor


def test_tabulated_share_is_the_spline_to_ten_micronewtons():
    u = np.linspace(-1.0, 30.0, 200_000).reshape(-1, 1000)  # 1000 regions at a time
    for law in LAWS.values():
        bank = TransferBank([law] * u.shape[1], 0.01)
        share = np.array([bank.share(row + law.dead_band_N) for row in u])
        assert np.abs(share - law.share.force(u)).max() < 1e-5


@pytest.mark.slow
def test_fit_recovers_a_known_law():
    truth = _law(dead=0.37, slope=0.3, c=(0.08,), tau=(2.0,))
    t = np.concatenate([np.linspace(0, 8, 161), 8 + np.geomspace(0.01, 10, 60)])
    hold = t > 8
    # a plate force that rises to 20 N and relaxes by 10 % in the hold
    force = np.where(hold, 20.0 * (0.9 + 0.1 * np.exp(-(t - 8) / 3.0)), 2.5 * t)
    rec = SensorRecord("pocket2-sil", 0.5, t, force, hold,
                       {"pocket-floor": truth.reading(t, force)}, {"pocket-floor": "pocket-floor"},
                       {"pocket-floor": 16.0})
    law = fit_transfer("pocket-floor", [rec], dead_band_steps=33)
    assert abs(law.dead_band_N - 0.37) <= 0.01  # the bracket is one 0.25 N step here
    assert law.fitted[0].rms_pct < 0.3 and law.fitted[0].hold_max_pct < 0.5
    assert law.sensitivity(5.0) == pytest.approx(0.3, rel=0.02)


# --- the shipped laws ----------------------------------------------------------------------------
def test_every_design_and_placement_has_a_law():
    for d in DESIGNS:
        have = {p for (dd, p) in LAWS if dd == d}
        want = {"bone", "interface"} | ({"pocket-floor"} if parse_design(d).geometry().has_pocket
                                        else set())
        assert have == want, (d, have)


@pytest.mark.parametrize("key", sorted(LAWS), ids=lambda k: f"{k[0]}@{k[1]}")
def test_shipped_law_matches_its_fe_records(key):
    law = LAWS[key]
    fit, val = read_records(SENSORS_DIR, law.design)
    name = next(n for n, p in fit[0].placements.items() if p == law.placement)
    for rec, stored in zip(fit + val, law.fitted + law.validated, strict=True):
        model = law.reading(rec.time_s, rec.force_N)
        target = np.maximum(rec.readings_N[name], 0.0)  # a compression sensor
        span = target[rec.peak_index]
        rms = 100 * np.sqrt(np.mean((model - target) ** 2)) / span
        assert rms == pytest.approx(stored.rms_pct, rel=1e-6, abs=1e-9)  # not stale
        assert rms < RMS_PCT, (key, rec.speed_mm_s, rms)
        assert stored.ramp_max_pct < RAMP_MAX_PCT and stored.hold_max_pct < HOLD_MAX_PCT
        assert stored.to_2N_rms_pct < TO_2N_PCT
        if rec is fit[0]:  # the dead band: nothing before the fitted record's first reading
            first = int(np.flatnonzero(target > 0)[0])
            assert np.all(model[:first] == 0.0), (key, model[:first].max())


def test_floor_dead_band_within_the_fe_bracket():
    for (d, p), law in LAWS.items():
        if p != "pocket-floor":
            continue
        fit, _ = read_records(SENSORS_DIR, d)
        f = fit[0].readings_N["pocket-floor"]
        i = int(np.flatnonzero(f > 1e-9)[0])
        assert fit[0].force_N[i - 1] - 1e-9 <= law.dead_band_N <= fit[0].force_N[i] + 1e-9


def test_transfer_file_errors_name_the_key(tmp_path):
    data = json.loads((SENSORS_DIR / "transfer.json").read_text())
    data["laws"]["pocket2-sil"]["bone"]["kernel"]["c"] = [0.6, 0.6]
    bad = tmp_path / "transfer.json"
    bad.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"laws\.pocket2-sil\.bone\.kernel.*K\(inf\)"):
        load_transfer_laws(bad)


# --- the electronics -----------------------------------------------------------------------------
IDEAL = SensorSpec(name="ideal", resolution_N=0.0, noise_N=0.0, threshold_N=0.0, period_s=0.01,
                   latency_s=0.0)


def _chain(spec: SensorSpec, step_s: float = 0.01) -> SensorChain:
    return SensorChain([None], spec, step_s)


def _run(chain: SensorChain, loads) -> np.ndarray:
    return np.array([chain.step(np.array([f]))[0] for f in loads])


def test_latency_and_period_delay_and_hold_the_sample():
    loads = np.r_[np.zeros(5), np.full(20, 3.0)]
    out = _run(_chain(replace(IDEAL, latency_s=0.03)), loads)
    assert np.all(out[:8] == 0) and np.all(out[8:] == 3.0)  # 3 steps late
    ramp = np.arange(1, 21, dtype=float)
    out = _run(_chain(replace(IDEAL, period_s=0.04)), ramp)
    np.testing.assert_array_equal(out, np.r_[0, 0, 0, np.repeat(ramp[3::4], 4)][:20])


def test_threshold_saturation_quantization():
    spec = replace(IDEAL, threshold_N=0.1, full_scale_N=5.0, resolution_N=0.25)
    out = _run(_chain(spec), [0.05, 0.2, 1.1, 1.2, 7.0])
    np.testing.assert_array_equal(out, [0.0, 0.25, 1.0, 1.25, 5.0])


def test_noise_is_seeded_and_has_its_rms():
    spec = replace(IDEAL, noise_N=0.05)
    a, b = _chain(spec), _chain(spec)
    a.reset(np.random.default_rng(7))
    b.reset(np.random.default_rng(7))
    x, y = _run(a, np.full(4000, 2.0)), _run(b, np.full(4000, 2.0))
    np.testing.assert_array_equal(x, y)
    assert np.std(x - 2.0) == pytest.approx(0.05, rel=0.05)


def test_hysteresis_band():
    spec = replace(IDEAL, full_scale_N=10.0, hysteresis_pct=10.0)  # band 1 N
    up = _run(_chain(spec), np.r_[np.linspace(0, 5, 11), np.linspace(5, 0, 11)])
    assert up[10] == pytest.approx(4.5) and up[-1] == 0.0
    assert up[15] - np.linspace(5, 0, 11)[4] == pytest.approx(0.5)


@pytest.mark.parametrize("kw, needles", [
    ({"noise_N": -0.1}, ["noise_N", "-0.1"]),
    ({"resolution_N": 50.0}, ["resolution_N", "50"]),
    ({"hysteresis_pct": 80.0}, ["hysteresis_pct", "80"]),
    ({"period_s": 0.0}, ["period_s", "0"]),
])
def test_bad_sensor_spec_names_the_value(kw, needles):
    with pytest.raises(ValueError) as e:
        replace(FLEXIFORCE_A101, **kw)
    for n in needles:
        assert n in str(e.value)


def test_latency_shorter_than_the_env_step_is_refused():
    with pytest.raises(ValueError, match=r"latency_s = 0.004 s is shorter than the env step 0.01"):
        _chain(replace(IDEAL, latency_s=0.004))
    with pytest.raises(ValueError, match=r"period_s = 0.005 s is shorter"):
        _chain(replace(IDEAL, period_s=0.005))
    assert _chain(replace(IDEAL, latency_s=0.026)).spec.latency_s == pytest.approx(0.03)


# --- on the hand ---------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def env_run():
    """One default handshake (neutral, seed 0) with every region's sensor under the outer layer,
    observing both the readings and the contact forces."""
    import softhand.envs  # noqa: F401
    from softhand.envs.handshake import HandshakeEnv
    from softhand.envs.run import run_handshake

    env = HandshakeEnv(observe="both")
    return env, run_handshake(env=env, seed=0)


def test_observation_carries_the_readings_and_info_the_true_forces(env_run):
    env, _ = env_run
    obs, info = env.reset(seed=1)
    n = (env.observation_space.shape[0] - 37) // 2
    for _ in range(150):  # into the grip
        obs, *_, info = env.step(np.zeros(6))
    names = env.region_names
    np.testing.assert_array_equal(obs[2 * n:2 * n + 18],
                                  [info["sensor_readings_N"][r] for r in names])
    np.testing.assert_array_equal(obs[2 * n + 18:2 * n + 36],
                                  [info["region_forces_N"][r] for r in names])
    assert max(info["region_forces_N"].values()) > 0.5  # the hands touch by then


def test_handshake_readings_follow_the_transfer_law(env_run):
    """The reading of the most loaded region is the interface law of its contact force, up to
    the electronics (one sample late, noise, threshold, 10-bit quantization)."""
    env, run = env_run
    i = int(np.argmax(run.region_force_N.sum(axis=0)))
    region = run.region_names[i]
    law = LAWS[(env.skins[region], "interface")]
    f = run.region_force_N[:, i]
    ideal = law.reading(run.time_s - run.time_s[0], f)
    late = np.r_[0.0, ideal[:-1]]  # latency 10 ms = one frame
    err = run.sensor_reading_N[:, i] - late
    q = FLEXIFORCE_A101.resolution_N
    on = late > FLEXIFORCE_A101.threshold_N + 4 * FLEXIFORCE_A101.noise_N
    assert f.max() > 2.0 and on.sum() > 50, (region, f.max(), on.sum())
    assert np.abs(err[on]).max() < q / 2 + 5 * FLEXIFORCE_A101.noise_N
    assert abs(np.mean(err[on])) < 0.5 * q
    assert run.table()[region]["sensor_peak"] == pytest.approx(run.sensor_reading_N[:, i].max())


def test_pocket_floor_sensor_is_blind_below_its_dead_band():
    from softhand.envs.handshake import HandshakeEnv

    env = HandshakeEnv(sensor_placement="pocket-floor",
                       sensor=replace(FLEXIFORCE_A101, noise_N=0.0, threshold_N=0.0))
    law = LAWS[(env.skins["Palm1"], "pocket-floor")]
    env.reset(seed=0)
    seen_blind = seen_on = loaded = False
    above = set()  # regions whose load has passed the dead band (then the hold's history counts)
    while True:
        *_, term, trunc, info = env.step(np.zeros(6))
        f, r = info["region_forces_N"], info["sensor_readings_N"]
        for region in env.region_names:
            if f[region] >= law.dead_band_N:
                above.add(region)
            if 0.02 < f[region] < law.dead_band_N and region not in above:
                seen_blind = True
                assert r[region] == 0.0, (region, f[region], r[region])
            if f[region] > 2 * law.dead_band_N:
                loaded = True
        # once a region is loaded past twice the dead band, the sensors read (after their latency)
        seen_on |= loaded and max(r.values()) > 0.0
        if term or trunc:
            break
    assert seen_blind and seen_on


@pytest.mark.parametrize("kw, needles", [
    ({"sensor_placement": "knee"}, ["'knee'", "bone, interface, pocket-floor"]),
    ({"sensor_placement": {"Palm9": "bone"}}, ["'Palm9'", "Palm1"]),
    ({"design": "solid-sil", "sensor_placement": "pocket-floor"},
     ["pocket-floor", "solid-sil", "no pocket", "bone, interface"]),
    ({"observe": "taxels"}, ["'taxels'", "sensor, load, contact, both"]),
    ({"sensor": replace(FLEXIFORCE_A101, latency_s=0.005)}, ["latency_s = 0.005", "0.01 s"]),
])
def test_env_bad_sensor_input_names_the_value(kw, needles):
    from softhand.envs.handshake import HandshakeEnv

    with pytest.raises(ValueError) as e:
        HandshakeEnv(**kw)
    for n in needles:
        assert n in str(e.value), (n, str(e.value))


@pytest.mark.parametrize("args, needles", [
    (["--sensor-noise", "-0.5"], ["'--sensor-noise'", "'-0.5'", "0 <= x <= 10 N"]),
    (["--sensor-latency", "0.004"], ["--sensor-latency", "0.004", "0.01 s"]),
    (["--sensor-period", "0.002"], ["--sensor-period", "0.002", "0.01 s"]),
    (["--sensor-placement", "Palm1=knee"], ["--sensor-placement", "'knee'", "Palm1"]),
    (["--sensor-placement", "pocket-floor", "--design", "solid-pu"],
     ["--sensor-placement", "solid-pu", "no pocket"]),
    (["--target", "3"], ["--target", "--controller force"]),
    (["--sensor-threshold", "50"], ["'--sensor-threshold'", "'50'"]),
])
def test_cli_bad_sensor_input_is_one_line(args, needles, monkeypatch):
    from click.testing import CliRunner

    import softhand.envs.run
    from softhand.cli import main

    def forbidden(*a, **k):
        raise AssertionError("the episode started before the input was rejected")

    monkeypatch.setattr(softhand.envs.run, "run_handshake", forbidden)
    res = CliRunner().invoke(main, ["handshake", *args])
    line = res.output.strip()
    assert res.exit_code == 2, (res.exit_code, res.output, res.exception)
    assert "\n" not in line and line.startswith("error: "), res.output
    for n in needles:
        assert n in line, (n, line)


def test_design_table_from_the_shipped_laws(tmp_path):
    """softhand bench sensors without handshakes: every design, the named usefulness criteria
    applied as stated, the floor's dead band inside its FE bracket, the plot written."""
    from softhand.bench.sensors import USEFUL, run_sensor_table

    md = run_sensor_table(tmp_path, handshakes=False)
    data = json.loads((tmp_path / "bench-sensors.json").read_text())
    assert set(data["designs"]) == set(DESIGNS)
    for d, row in data["designs"].items():
        for s in row["sensors"].values():
            want = (s["sensitivity"] >= USEFUL["sensitivity_min"]
                    and s["law_dead_band_N"] <= USEFUL["dead_band_max_N"]
                    and (s["relaxation_pct"] or 0) <= USEFUL["relaxation_max_pct"])
            assert s["useful"] == want, (d, s)
    assert (tmp_path / "bench-sensors.png").stat().st_size > 10_000
    assert "| pocket2-sil | 19 |" in md and "useful placements" in md


def test_sensors_calibrate_guards_the_shipped_laws_and_checks_records_first(tmp_path, monkeypatch):
    """A subset cannot replace the shipped records; --fit-only needs the records; neither runs
    an FE job before saying so."""
    from click.testing import CliRunner

    import softhand.sensors.calibrate as cal
    from softhand.cli import main

    def forbidden(*a, **k):
        raise AssertionError("work started before the input was rejected")

    monkeypatch.setattr(cal, "run_sensor_fe", forbidden)
    monkeypatch.setattr(cal, "fit_all", forbidden)
    for args, needles in (
            (["--design", "pocket2-sil"], ["shipped calibration data", "--force"]),
            (["--fit-only", "--out", str(tmp_path)], ["--fit-only", str(tmp_path)]),
            (["--design", "pocket9-sil", "--out", str(tmp_path)], ["pocket9-sil"])):
        res = CliRunner().invoke(main, ["sensors", "calibrate", *args])
        line = res.output.strip()
        assert res.exit_code == 2 and "\n" not in line, (args, res.output)
        for n in needles:
            assert n in line, (n, line)


@pytest.mark.slow
def test_sensors_calibrate_fit_only_writes_the_same_laws(tmp_path):
    """Refitting from a copy of the shipped records reproduces the shipped laws (one design)."""
    import shutil

    from click.testing import CliRunner

    from softhand.cli import main

    shutil.copytree(SENSORS_DIR / "fe", tmp_path / "fe")
    res = CliRunner().invoke(main, ["sensors", "calibrate", "--fit-only", "--design",
                                    "pocket2-sil", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    new = load_transfer_laws(tmp_path / "transfer.json")
    for p in ("bone", "interface", "pocket-floor"):
        a, b = new[("pocket2-sil", p)], LAWS[("pocket2-sil", p)]
        assert a.dead_band_N == pytest.approx(b.dead_band_N, abs=1e-9)
        np.testing.assert_allclose(a.share.coefficients, b.share.coefficients, rtol=1e-6,
                                   atol=1e-9)


def test_a_stacked_chain_is_each_worlds_own_chain():
    """SensorChain.stack (the vector env's sensors): every world reads what its own one-world
    chain reads, bit for bit, with its own noise stream, worlds standing still (a mask) and reset
    apart, under hysteresis and a latency longer than the sampling period."""
    law = next(v for (d, p), v in LAWS.items() if p == "pocket-floor")
    other = LAWS[("solid-pu", "bone")]
    spec = replace(FLEXIFORCE_A101, hysteresis_pct=4.0, period_s=0.02, latency_s=0.05)
    rng = np.random.default_rng(11)
    worlds = [SensorChain([law, other, None], spec, 0.01) for _ in range(3)]
    for w, c in enumerate(worlds):
        c.reset(np.random.default_rng(100 + w))
    stacked = SensorChain.stack([SensorChain([law, other, None], spec, 0.01) for _ in range(3)])
    for w in range(3):
        stacked.reset(np.random.default_rng(100 + w), w)
    for k in range(200):
        loads = np.abs(rng.normal(2.0, 1.5, (3, 3)))
        mask = rng.uniform(size=3) > 0.2
        if k == 120:  # world 1 starts again, the others go on
            worlds[1].reset(np.random.default_rng(7))
            stacked.reset(np.random.default_rng(7), 1)
        got = stacked.step(loads, worlds=mask)
        for w in np.flatnonzero(mask):
            np.testing.assert_array_equal(got[w], worlds[w].step(loads[w]))
        np.testing.assert_array_equal(stacked.readings, [c.readings[0] for c in worlds])
        # the estimates made with the readings are the bank's inversion of them
        np.testing.assert_array_equal(stacked.estimates, stacked.bank.load_estimate(
            stacked.readings.ravel()).reshape(3, 3))
    assert (stacked.readings > 0).any(axis=1).all()  # every world reads a load
    assert (stacked.estimates > stacked.readings).any()  # a pocket's share is under its load


def test_a_sensor_placement_a_skin_cannot_take_is_refused_not_ignored():
    """The human hand (human tissue, no FE model of an embedded sensor: surface pads) refuses a
    placement asked for every region, and any skin without an FE model refuses one asked for
    its region; it was ignored (the readings were the surface's)."""
    from softhand.envs import HandshakeEnv

    with pytest.raises(ValueError, match=r"sensor placement 'bone' for region Thumb1: its skin "
                                         r"human-middle-phalanx has no FE model"):
        HandshakeEnv(hand="human", sensor_placement="bone")
    with pytest.raises(ValueError, match=r"placement 'bone' for region Index1: its skin rigid"):
        HandshakeEnv(skins={"Index1": "rigid"}, sensor_placement={"Index1": "bone"})
    env = HandshakeEnv(skins={"Index1": "rigid"}, sensor_placement="bone")  # honoured elsewhere
    assert env.sensor_placements["Index2"] == "bone" and env.sensor_placements["Index1"] == "surface"


def test_a_transfer_file_without_the_design_says_which_designs_it_has(tmp_path):
    """A transfer.json that lacks the skin's design altogether said "allowed: " with an empty
    list; now it names the designs the file has and what to run."""
    import json

    from softhand.envs import HandshakeEnv
    from softhand.paths import SENSORS_DIR

    data = json.loads((SENSORS_DIR / "transfer.json").read_text(encoding="utf-8"))
    del data["laws"]["pocket2-sil"]
    (tmp_path / "transfer.json").write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(ValueError, match=r"has no transfer law for pocket2-sil at any placement "
                                         r"\(it has pocket1-pu, .*\): run `softhand sensors "
                                         r"calibrate` for pocket2-sil"):
        HandshakeEnv(sensor_dir=tmp_path)
