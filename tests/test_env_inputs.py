"""The env's inputs and its warnings (issue 20, items 5 and 6): every keyword checked before any
model is built, a closed env refused, masked actions refused, and one range warning per episode
that points at the code that called ``step()``, through Gymnasium's wrappers too."""

from __future__ import annotations

import math
import re
import warnings

import gymnasium as gym
import numpy as np
import numpy.ma as ma
import pytest

import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)
from softhand.envs import HandshakeEnv
from softhand.envs.controllers import make_controller
from softhand.envs.partner import MAX_SQUEEZE
from softhand.envs.scenarios import HandshakeScenario
from softhand.envs.skins import CalibratedRangeWarning
from softhand.sensors.device import FLEXIFORCE_A101
from softhand.skin.rig import SkinRangeWarning

NAN, INF = math.nan, math.inf
SQUEEZE = "expected a finite number in (0, 5]"


@pytest.fixture(scope="module")
def env():
    return HandshakeEnv(design="rigid")


@pytest.mark.parametrize("kwargs, needle", [
    ({"design": ""}, "skin design '' is unknown; allowed: "),
    ({"design": 5}, "skin design 5 is unknown"),
    ({"representation": ""}, "representation '' is unknown; allowed: rigid, soft-contact"),
    ({"representation": 5}, "representation 5 is unknown"),
    ({"calibration_dir": ""}, "calibration_dir = '': expected a folder path, got an empty string"),
    ({"calibration_dir": " "}, "calibration_dir = ' ': expected a folder path, got an empty"),
    ({"calibration_dir": 5}, "calibration_dir = 5: expected a folder path (a str or os.PathLike)"),
    ({"sensor_dir": ""}, "sensor_dir = '': expected a folder path, got an empty string"),
    ({"sensor_dir": 3.0}, "sensor_dir = 3.0: expected a folder path"),
    ({"skins": "Index1=rigid"}, "skins = 'Index1=rigid': expected a mapping region -> DESIGN"),
    ({"skins": {"Index1": ""}}, "skin '' for region Index1 is unknown"),
    ({"skins": {"Index1": None}}, "skin None for region Index1: expected DESIGN or DESIGN@"),
    ({"skins": {"Index1": "pocket2-sil@"}}, "representation for region Index1 '' is unknown"),
    ({"skins": {"": "rigid"}}, "region '' is unknown"),
    ({"squeeze": 1e6}, f"squeeze = 1000000.0: {SQUEEZE}"),
    ({"squeeze": 5.01}, f"squeeze = 5.01: {SQUEEZE}"),
    ({"squeeze": 0.0}, f"squeeze = 0.0: {SQUEEZE}"),
    ({"squeeze": -1}, f"squeeze = -1: {SQUEEZE}"),
    ({"squeeze": NAN}, f"squeeze = nan: {SQUEEZE}"),
    ({"squeeze": INF}, f"squeeze = inf: {SQUEEZE}"),
    ({"squeeze": None}, f"squeeze = None: {SQUEEZE}"),
    ({"squeeze": "5"}, f"squeeze = '5': {SQUEEZE}"),
    ({"squeeze": True}, f"squeeze = True: {SQUEEZE}"),
    ({"overload_N": NAN}, "overload_N = nan: expected a finite number > 0"),
    ({"overload_N": 0}, "overload_N = 0: expected a finite number > 0"),
    ({"overload_N": None}, "overload_N = None: expected a finite number > 0"),
    ({"reward_weights": {"grip": INF}}, "reward_weights['grip'] = inf: expected a finite number"),
    ({"reward_weights": {"": 1.0}}, "reward weight '' is unknown"),
    ({"reward_weights": "grip"}, "reward_weights = 'grip': expected a mapping"),
    ({"randomize": None}, "randomize = None: expected True or False"),
    ({"randomize": 1}, "randomize = 1: expected True or False"),
    ({"sensor": ""}, "sensor = '': expected a SensorSpec"),
    ({"sensor_placement": ""}, "sensor placement '' for region Thumb1 is unknown"),
    ({"sensor_placement": {"Index1": ""}}, "sensor placement '' for region Index1 is unknown"),
    ({"observe": ""}, "observe = '': allowed sensor, load, contact, both"),
    ({"observe": None}, "observe = None: allowed sensor, load, contact, both"),
    ({"render_mode": "human"}, "render_mode = 'human': allowed None or 'rgb_array'"),
    ({"render_mode": ""}, "render_mode = '': allowed None or 'rgb_array'"),
    ({"render_size": (32, 480)}, "width = 32: allowed 64-4096 pixels"),
    ({"render_size": (640, 480.5)}, "height = 480.5: allowed 64-4096 pixels"),
    ({"render_size": 640}, "render_size = 640: expected (width, height) in pixels"),
    ({"render_view": "front"}, "render_view = 'front': expected None or a softhand.envs."),
    ({"hand": ""}, "hand = '': allowed prosthetic, human"),
    ({"hand": None}, "hand = None: allowed prosthetic, human"),
    ({"frame_skip": 0}, "frame_skip = 0: expected an integer in [1, 50]"),
    ({"frame_skip": "5"}, "frame_skip = '5': expected an integer in [1, 50]"),
    ({"timestep_s": None}, "timestep_s = None: expected a finite number in [0.0001, 0.005] s"),
    ({"timestep_s": NAN}, "timestep_s = nan: expected a finite number in [0.0001, 0.005] s"),
    ({"partner_size": ""}, "partner_size = '': expected (length_mm, width_mm)"),
    ({"partner_size": (1e3, 88)}, "partner_size length = 1000.0 mm: allowed 159.075-215.925 mm"),
    ({"partner_size": (190, 72.5)}, "partner_size width = 72.5 mm: allowed 72.53-106.53 mm"),
    ({"timestep_s": 0.005, "frame_skip": 20},  # named by what the user set, not the sensor
     "frame_skip = 20 x timestep_s = 0.005 s makes an env step of 0.1 s, longer than the default "
     "sensor's sampling period 0.01 s"),
    ({"partner_size": (190, NAN)}, "partner_size = (190, nan): expected (length_mm, width_mm)"),
])
def test_every_bad_keyword_is_refused_before_any_model_is_built(monkeypatch, kwargs, needle):
    """One ValueError naming the keyword, the value and what is allowed; the scene builder is
    never reached (it would raise AssertionError here)."""
    def no_build(*args, **kw):
        raise AssertionError("a model was built before the arguments were checked")

    monkeypatch.setattr("softhand.envs.touch.skinned_scene_spec", no_build)
    with pytest.raises(ValueError) as info:
        HandshakeEnv(**kwargs)
    assert needle in str(info.value)


def test_squeeze_up_to_the_partners_hardest_grip_is_accepted():
    assert HandshakeScenario(squeeze=MAX_SQUEEZE).squeeze == 5.0
    assert HandshakeScenario(squeeze=1e-3).squeeze == 1e-3
    with pytest.raises(ValueError, match=re.escape("squeeze = 5.000000000000001: expected a "
                                                   "finite number in (0, 5] (above 5 the")):
        HandshakeScenario(squeeze=float(np.nextafter(5.0, 6.0)))


@pytest.mark.parametrize("options, needle", [
    ({"grip_N": 12.6}, "options['grip_N'] = 12.6: allowed [1e-06, 12.5]"),
    ({"grip_N": 0.0}, "options['grip_N'] = 0.0: allowed [1e-06, 12.5]"),
    ({"grip_N": None}, "options['grip_N'] = None: expected a number in [1e-06, 12.5]"),
    ({"duration_s": NAN}, "options['duration_s'] = nan: allowed [2, 6]"),
    ({"shake_phase_rad": 7.0}, "options['shake_phase_rad'] = 7.0: allowed [-6.28319, 6.28319]"),
    ({"shake_phase_rad": 1e6}, "options['shake_phase_rad'] = 1000000.0: allowed [-6.28319"),
    ({"": 1.0}, "options key '' is unknown; allowed: grip_N, duration_s, shake_phase_rad"),
    ("grip_N=2", "options = 'grip_N=2': expected None or a mapping"),
])
def test_bad_reset_options_are_refused(env, options, needle):
    with pytest.raises(ValueError) as info:
        env.reset(seed=0, options=options)
    assert needle in str(info.value)
    env.reset(seed=0, options={"grip_N": 12.5, "shake_phase_rad": -2 * np.pi})  # the bounds


@pytest.mark.parametrize("name, settings, needle", [
    ("open-loop", {"speed": NAN}, "speed = nan: expected a finite number in (0, 1]"),
    ("open-loop", {"speed": 0}, "speed = 0: expected a finite number in (0, 1]"),
    ("open-loop", {"close_s": INF}, "close_s = inf: expected a finite number in (0, 6] s"),
    ("open-loop", {"close_s": "1"}, "close_s = '1': expected a finite number in (0, 6] s"),
    ("force", {"target_N": 1e6}, "target_N = 1000000.0: expected a finite number in [0.05, 20] N"),
    ("force", {"target_N": None}, "target_N = None: expected a finite number in [0.05, 20] N"),
    ("force", {"gain_per_N": INF}, "gain_per_N = inf: expected a finite number in (0, 10] per N"),
    ("neutral", {"touch_N": 0.0}, "touch_N = 0.0: expected a finite number in [0.05, 20] N"),
    ("neutral", {"speed": None}, "speed = None: expected a finite number in (0, 1]"),
    ("neutral", {"target": 2.0}, "controller 'neutral': setting 'target' is unknown; allowed: "
                                 "speed, touch_N"),
    ("", {}, "controller '' is unknown; allowed: neutral, open-loop, force"),
])
def test_bad_controller_settings_are_refused(name, settings, needle):
    with pytest.raises(ValueError) as info:
        make_controller(name, **settings)
    assert needle in str(info.value)


def test_bad_signal_is_refused():
    with pytest.raises(ValueError, match="signal = '' is unknown; allowed: contact, sensor"):
        make_controller("force", signal="")


def test_masked_action_with_masked_entries_is_refused(env):
    """The data under a mask is arbitrary (here 0.5, inside the action space): refused, naming
    the masked entries; a masked array with nothing masked is an ordinary action."""
    env.reset(seed=0)
    action = ma.masked_array(np.zeros(6), mask=[False, True, False, False, False, True])
    action.data[1] = 0.5
    with pytest.raises(ValueError, match=re.escape("has masked entries (at [1, 5]): expected 6 "
                                                   "finite real values in [-1, 1], none masked")):
        env.step(action)
    obs, *_ = env.step(ma.masked_array(np.zeros(6), mask=False))
    assert np.all(np.isfinite(obs))


def test_step_and_reset_after_close_are_refused():
    for wrapped in (False, True):
        env = (gym.make("softhand/Handshake-v0", design="rigid") if wrapped
               else HandshakeEnv(design="rigid"))
        env.reset(seed=0)
        env.step(np.zeros(6))
        env.close()
        env.close()  # closing twice is harmless
        with pytest.raises(RuntimeError, match=r"the env is closed \(close\(\) was called\)"):
            env.step(np.zeros(6))
        with pytest.raises(RuntimeError, match=r"the env is closed"):
            env.reset(seed=0)


def _episode(env, controller: str, seed: int = 1) -> list[dict]:
    ctrl = make_controller(controller)
    obs, info = env.reset(seed=seed)
    infos = []
    while True:
        obs, _, term, trunc, info = env.step(ctrl(obs, info))
        infos.append(info)
        if term or trunc:
            return infos


@pytest.mark.parametrize("wrapped", [False, True])
def test_one_range_warning_per_episode_with_its_summary_at_the_callers_line(wrapped):
    """A 5x squeeze drives contacts past the 7-11.6 N the pair laws are calibrated to. Before, one
    warning per pair (11 here) attributed, under gymnasium.make, to Gymnasium's wrapper file;
    now one per episode, on its last step, summarising what ``info`` reported step by step,
    attributed to this file."""
    env = (gym.make("softhand/Handshake-v0", squeeze=5.0) if wrapped
           else HandshakeEnv(squeeze=5.0))
    for _ in range(2):  # one per episode, not one per env
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            infos = _episode(env, "open-loop")
        ranged = [w for w in caught if issubclass(w.category, CalibratedRangeWarning)]
        assert len(ranged) == 1, [str(w.message) for w in caught]
        assert ranged[0].filename == __file__, ranged[0].filename
        summary = infos[-1]["beyond_range_summary"]
        assert all("beyond_range_summary" not in i for i in infos[:-1])
        assert summary["contact_steps"] + summary["bone_steps"] == sum(
            i["contacts_beyond_range"] for i in infos)
        seen = {}
        for i in infos:
            for pair, f in i["pairs_beyond_range_N"].items():
                seen[pair] = max(f, seen.get(pair, 0.0))
        assert summary["pairs"] == len(seen) > 1
        assert summary["worst_force_N"] == seen[summary["worst_pair"]]
        worst = env.unwrapped.pair_laws[summary["worst_pair"]]
        assert summary["worst_limit_N"] == worst.calibrated_max_N and summary["steps"] == len(infos)
        # a tissue class's (its data's and its FE's): a finger-like contact's, an oblique
        # border's crossings, a flat's
        assert worst.calibrated_max_N in (pytest.approx(8.1, abs=0.1), pytest.approx(7.6, abs=0.1),
                                          pytest.approx(11.6, abs=0.1), 7.0)
        text = str(ranged[0].message)
        assert text.startswith(f"episode ended at t = {summary['time_s']:.2f} s after "
                               f"{summary['steps']} steps: {summary['contact_steps']} "
                               f"contact-steps on {summary['pairs']} pair(s)")
        assert (f"pair {summary['worst_pair']}, carried {summary['worst_force_N']:.2f} N" in text
                and f"{worst.calibrated_max_N:.2f} N its law (pocket2-sil in series with human "
                f"tissue, {worst.law} law)" in text)
    env.close()


def test_an_episode_cut_short_warns_on_reset_and_close_at_the_callers_line():
    env = gym.make("softhand/Handshake-v0", squeeze=5.0)
    ctrl = make_controller("open-loop")
    for end in ("reset", "close"):
        obs, info = env.reset(seed=1)
        while info["time_s"] < 1.6:  # past the grip: contacts beyond range
            obs, _, _, _, info = env.step(ctrl(obs, info))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            env.reset(seed=1) if end == "reset" else env.close()
        assert [w.filename for w in caught] == [__file__], [str(w.message) for w in caught]
        assert str(caught[0].message).startswith(f"episode cut short by {end}() at t = 1.6")


@pytest.mark.slow
def test_a_timestep_outside_the_calibrated_range_warns_once_at_the_callers_line():
    """5 ms: every skin pair is outside the checked timesteps and some oscillate faster than the
    step follows. Before, one SkinRangeWarning per pair (383) attributed to softhand's skins.py;
    now one for the model, with each kind's count and worst pair, attributed to this file."""
    for make in (lambda: HandshakeEnv(timestep_s=0.005),
                 lambda: gym.make("softhand/Handshake-v0", timestep_s=0.005)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            make()
        assert [(w.category, w.filename) for w in caught] == [(SkinRangeWarning, __file__)]
        text = str(caught[0].message)
        assert re.match(r"\d+ skin pairs are outside their calibrated range; timestep: \d+ "
                        r"pairs, the worst pair '\w+': timestep 5 ms is outside the calibrated "
                        r"range 0.5-2 ms; stiffness: \d+ pairs, the worst pair '\w+': ", text), text


def test_the_default_sensor_and_none_are_accepted():
    """None means the default for the keywords that have one (an empty string never does)."""
    env = HandshakeEnv(design=None, skins=None, representation=None, calibration_dir=None,
                       sensor=FLEXIFORCE_A101, sensor_placement=None, sensor_dir=None,
                       partner_size=None, frame_skip=None)
    assert env.skins["Index1"] == "pocket2-sil" and env.representations["Index1"] == "soft-contact"


@pytest.mark.parametrize("timestep_s, skip", [(0.002, 5), (0.001, 10), (0.0005, 20),
                                              (0.005, 2), (0.00275, 3), (0.0035, 2),
                                              (0.0045, 2), (0.003, 3), (0.0001, 100)])
def test_the_default_env_step_is_the_most_physics_steps_that_fit_in_ten_milliseconds(timestep_s,
                                                                                       skip):
    """2.75 ms used to round to 4 steps (an 11 ms env step), coarser than the sensors' default
    10 ms sampling: the env refused its own defaults (--timestep 0.00275, inside the help's
    range). Timesteps that divide 10 ms are unchanged."""
    from softhand.envs.touch import default_frame_skip

    assert default_frame_skip(timestep_s) == skip
    assert skip * timestep_s <= 0.01 + 1e-12 < (skip + 1) * timestep_s
