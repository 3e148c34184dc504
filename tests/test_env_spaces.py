"""The env explains itself (issue 24 item 3): every action and observation entry named with its
unit from one place (softhand.envs.spaces), the docstring's tables made from it, ``observe="load"``
giving the calibrated read-out, ``render_mode="rgb_array"`` and any policy recorded to rerun."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import warnings

import gymnasium as gym
import numpy as np
import pytest

import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)
from softhand.envs import HandshakeEnv
from softhand.envs.controllers import make_controller
from softhand.envs.picture import RENDER_VIEW
from softhand.envs.run import run_handshake
from softhand.envs.spaces import (
    OBSERVE,
    action_names,
    action_table,
    observation_names,
    observation_table,
)
from softhand.envs.vector import HandshakeVectorEnv
from softhand.viz import read_recording_summary, record


@pytest.fixture(scope="module")
def env():
    """A handshake observing the load estimates."""
    env = HandshakeEnv(observe="load")
    yield env
    env.close()


def _into_the_grip(env, steps: int = 150):
    obs, info = env.reset(seed=1)
    for _ in range(steps):
        obs, *_, info = env.step(np.zeros(6))
    return obs, info


def test_every_entry_is_named_with_its_unit(env):
    names = env.observation_names
    assert len(names) == env.observation_space.shape[0] == 2 * 16 + 19
    assert names[0] == "qpos/pro_index_mcp [rad]" and names[16] == "qvel/pro_index_mcp [rad/s]"
    assert names[32:50] == tuple(f"load_estimate/{r} [N]" for r in env.region_names)
    assert names[-1] == "episode_fraction [-]" and len(set(names)) == len(names)
    assert env.action_names == action_names() and len(env.action_names) == 6
    assert env.action_names[0] == "speed/pro_index_motor [fraction of max]"
    assert env.action_names[5] == "speed/pro_thumb_rot_motor [fraction of max]"
    # the other observe values, from the same joints and regions
    joints = [(n.split("/")[1].split()[0], "hinge") for n in names[:16]]
    blocks = {"sensor": ["sensor_patch"], "contact": ["region_load"],
              "both": ["sensor_patch", "region_load"]}
    for observe, want in blocks.items():
        got = observation_names(joints, env.region_names, observe)
        assert len(got) == 2 * 16 + 1 + 18 * len(want)
        assert got[32:-1] == tuple(f"{b}/{r} [N]" for b in want for r in env.region_names)
    # a relaxation pad's slide joint is in metres
    assert observation_names([("pro_skin_Index1_pad", "slide")], ["Index1"], "sensor")[:2] == (
        "qpos/pro_skin_Index1_pad [m]", "qvel/pro_skin_Index1_pad [m/s]")


def test_the_docstring_tables_are_made_from_the_names():
    """HandshakeEnv's docstring holds the tables softhand.envs.spaces makes (paste them from
    ``python -c "from softhand.envs.spaces import *; print(observation_table())"`` when they
    change), and each table row names one kind of entry the env gives."""
    doc = HandshakeEnv.__doc__
    for table in (action_table(), observation_table()):
        assert textwrap.indent(table, "    ") in doc, table
    rows = observation_table()
    for block in ("qpos", "qvel", *(b for blocks in OBSERVE.values() for b in blocks)):
        assert f"{block}/<" in rows, block
    assert all(name in action_table() for name in action_names())


def test_load_observation_is_the_calibrated_read_out(env):
    obs, info = _into_the_grip(env)
    estimate = [info["sensor_load_estimate_N"][r] for r in env.region_names]
    np.testing.assert_array_equal(obs[32:50], estimate)
    assert max(estimate) > 0.5  # the hands touch by then
    # the read-out's load, not the patch's reading: larger where the patch reads a fraction
    readings = [info["sensor_readings_N"][r] for r in env.region_names]
    assert sum(estimate) > 1.5 * sum(readings)


def test_vector_env_names_and_load_observation_are_the_single_envs(env):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        vec = HandshakeVectorEnv(envs=[env])
        assert vec.single_observation_names == env.observation_names
        assert vec.single_action_names == env.action_names
        obs, info = vec.reset(seed=1)
        for _ in range(150):
            obs, *_, info = vec.step(np.zeros((1, 6)))
        np.testing.assert_array_equal(obs[0, 32:50], info["sensor_load_estimate_N"][0])
        single, _ = _into_the_grip(env)
        np.testing.assert_allclose(obs[0], single, atol=1e-9)
        # not closed: closing the vector env closes its worlds, the module's env


def test_worlds_observing_differently_are_refused(env):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        other = HandshakeEnv()  # observe="sensor": the same shape, other entries
    with pytest.raises(ValueError, match=r"world 1: observation of 51 entries differs from "
                                         r"world 0's \(51\) at entry 32: 'sensor_patch/Thumb1"):
        HandshakeVectorEnv(envs=[env, other])


@pytest.mark.parametrize("observe", ["taxels", "", None, ["load"], "LOAD"])
def test_bad_observe_is_one_error_naming_the_allowed_values(observe):
    with pytest.raises(ValueError, match="allowed sensor, load, contact, both") as info:
        HandshakeEnv(observe=observe, design="no-such-skin")  # observe is checked first
    assert str(info.value).startswith("observe = ")


def test_render_needs_a_render_mode_and_fps_follows_the_env_step(env):
    assert env.render_mode is None and env.metadata["render_modes"] == ["rgb_array"]
    assert env.metadata["render_fps"] == 100  # one picture per 10 ms env step
    with pytest.raises(RuntimeError, match="render_mode='rgb_array'"):
        env.render()
    fast = HandshakeEnv(frame_skip=2)  # 4 ms env steps
    assert fast.metadata["render_fps"] == 250 and HandshakeEnv.metadata["render_fps"] == 100
    fast.close()
    # before the first reset there is no episode to draw: one clear line, not AttributeError
    fresh = HandshakeEnv(render_mode="rgb_array")
    with pytest.raises(RuntimeError, match=r"call reset\(\) before render\(\)"):
        fresh.render()
    fresh.close()


def test_the_env_renders_from_softhand_renders_view():
    """The env's default camera is ``softhand render``'s default (its options' defaults)."""
    from softhand.cli import main

    options = {p.name: p.default for p in main.commands["render"].params}
    assert (options["azimuth"], options["elevation"], options["distance"]) == (
        RENDER_VIEW.azimuth_deg, RENDER_VIEW.elevation_deg, RENDER_VIEW.distance_m)


_RENDER_SCRIPT = """
import sys
import warnings

import matplotlib.pyplot as plt
import mujoco
import numpy as np

try:
    with mujoco.Renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 64, 64):
        pass
except Exception as exc:  # no OpenGL here: the test is skipped
    print(exc)
    sys.exit(77)

import gymnasium as gym
from gymnasium.wrappers import RenderCollection

import softhand.envs  # noqa: F401
from softhand.envs.picture import RENDER_VIEW, skin_forces
from softhand.viz.render import render_state

warnings.simplefilter("ignore")
env = RenderCollection(gym.make("softhand/Handshake-v0", render_mode="rgb_array",
                                render_size=(320, 240)))
plain = gym.make("softhand/Handshake-v0")
obs, info = env.reset(seed=0)
same, _ = plain.reset(seed=0)
for _ in range(150):  # rendering every step: the episode is the same (into the grip)
    obs, _, _, _, info = env.step(np.full(6, 0.2, np.float32))
    same, *_ = plain.step(np.full(6, 0.2, np.float32))
    assert np.array_equal(obs, same)
frames = env.render()
assert len(frames) == 151, len(frames)
picture = frames[-1]
assert picture.shape == (240, 320, 3) and picture.dtype == np.uint8, picture.shape
assert len({tuple(p) for p in picture.reshape(-1, 3)[::97]}) > 20  # a picture, not a blank
base = env.unwrapped
d = base.data
path = sys.argv[1]
# skin geom -> force as the env colours it: a skin of several zones (the palm) by its largest
forces = skin_forces(base.model, base.region_names,
                     [info["region_forces_N"][r] for r in base.region_names])
assert max(forces.values()) > 0.0  # the skin is coloured by a force
render_state(base.model, d.qpos, d.mocap_pos, d.mocap_quat, path, width=320, height=240,
             view=RENDER_VIEW, region_force_N=forces)
png = np.round(plt.imread(path)[..., :3] * 255).astype(np.uint8)
assert np.array_equal(png, picture), np.abs(png.astype(int) - picture).max()
env.close()
assert base._picture.closed
print("ok")
"""


@pytest.mark.slow
def test_rgb_array_is_softhand_renders_picture_and_wrappers_take_it(tmp_path):
    """Offscreen, in a process of its own (MUJOCO_GL is read when mujoco is imported):
    RenderCollection gathers a picture per step without changing the episode; the last is
    pixel for pixel the PNG ``softhand render``'s code writes of the same state, the skin
    coloured by the same region forces; close() frees the renderer."""
    script = tmp_path / "render.py"
    script.write_text(_RENDER_SCRIPT)
    res = subprocess.run([sys.executable, str(script), str(tmp_path / "state.png")],
                         env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")},
                         capture_output=True, text=True, timeout=300)
    if res.returncode == 77:
        pytest.skip(f"no offscreen OpenGL: {res.stdout.strip()}")
    assert res.returncode == 0 and "ok" in res.stdout, res.stdout + res.stderr


def test_record_writes_any_policys_episode_as_the_built_in_runs_collect_it(env, tmp_path):
    """A built-in controller recorded through record() gives the run run_handshake gives; a
    policy of one's own, through gym.make's wrappers, gives a recording with every region."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = record(env, make_controller("neutral"), tmp_path / "neutral.rrd", seed=0)
        ref = run_handshake(env=env, seed=0)
        np.testing.assert_array_equal(run.region_force_N, ref.region_force_N)
        np.testing.assert_array_equal(run.qpos, ref.qpos)
        assert run.phase == ref.phase and run.controller == {"name": "Neutral"}
        wrapped = gym.make("softhand/Handshake-v0", observe="load")
        mine = record(wrapped, lambda obs, info: np.full(6, 0.3 if obs[-1] > 0.3 else 0.0),
                      tmp_path / "mine.rrd", seed=2)
    assert mine.episode["seed"] == 2 and mine.controller == {"name": "<lambda>"}
    assert mine.table()["Palm1"]["peak_N"] > 0.5
    entities = read_recording_summary(tmp_path / "mine.rrd")["entities"]
    assert all(f"forces/{r}" in entities and f"sensors/{r}" in entities
               for r in env.region_names)


@pytest.mark.parametrize("args, needle", [
    (("env", lambda o, i: np.zeros(6), "x.rrd"), "env = 'env': expected a softhand HandshakeEnv"),
    ((None, None, "x.rrd"), "env = None: expected a softhand HandshakeEnv"),
    (("ENV", 3, "x.rrd"), "policy = 3: expected a callable policy(obs, info) -> action"),
    (("ENV", lambda o, i: np.zeros(6), "x.png"), "expected a file name ending in .rrd"),
    (("ENV", lambda o, i: np.zeros(6), "TMP"), "is a folder, not a file"),
])
def test_record_refuses_bad_input_before_any_work(env, tmp_path, monkeypatch, args, needle):
    def no_run(*a, **kw):
        raise AssertionError("the episode ran before the inputs were checked")

    monkeypatch.setattr("softhand.envs.run.run_policy", no_run)
    folder = tmp_path / "out.rrd"
    folder.mkdir()
    args = tuple(env if a == "ENV" else str(folder) if a == "TMP" else
                 str(tmp_path / a) if isinstance(a, str) and a.startswith("x.") else a
                 for a in args)
    with pytest.raises(ValueError) as info:
        record(*args)
    assert needle in str(info.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.rrd"]
