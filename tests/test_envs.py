"""The handshake environment: Gymnasium contract, determinism, bad input (issue 4, in progress)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)
from softhand.envs import HandshakeEnv
from softhand.envs.skins import parse_skins


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
