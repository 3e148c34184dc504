"""Record any policy's handshake to rerun: one episode of an env, written as a ``.rrd``.

`record` runs the episode with `softhand.envs.run.run_policy` (what the built-in
controllers' runs collect: the state, region forces, sensor readings and contacts at every env
step) and writes it with `softhand.viz.recording.record_handshake` (its entity paths):

    import gymnasium as gym
    import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)
    from softhand.viz import record

    env = gym.make("softhand/Handshake-v0", observe="load")
    run = record(env, lambda obs, info: [0.3, 0.3, 0.3, 0.3, 0, 0], "mine.rrd", seed=0)
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from softhand.io import check_writable_file
from softhand.viz.recording import HandshakeFrames, record_handshake

if TYPE_CHECKING:
    from softhand.envs.run import HandshakeRun

__all__ = ["record"]


def record(env: Any, policy: Callable[[Any, dict], Any], path: str | os.PathLike, *,
           seed: int = 0, options: Mapping[str, float] | None = None) -> HandshakeRun:
    """Run one episode of ``env`` with ``policy(obs, info) -> action`` and write its rerun
    recording to ``path`` (atomically); return the run (its ``table()``, ``summary()``, ...).

    Args:
        env: a `HandshakeEnv`, or a Gymnasium wrapper of one
            (``gymnasium.make("softhand/Handshake-v0", ...)``): the episode steps through the
            wrappers, so the policy gets their observation.
        policy: called every env step with the observation and ``info``; returns the action.
        path: the ``.rrd`` file to write (its folder is made if missing); replaced if present.
        seed: the episode's seed (an integer >= 0), as ``env.reset(seed=...)``.
        options: the episode's reset options (the partner's grip, duration, shake phase).

    Raises:
        ValueError: ``env`` is not a HandshakeEnv or a wrapper of one, ``policy`` is not
            callable, or ``path`` is not a writable ``.rrd`` path, before any work; a bad seed,
            option or action, as the env's reset and step say (no file is written).
        DivergenceError: the physics diverged (no file is written).
    """
    from softhand.envs.run import check_policy, run_policy

    check_policy(env, policy)
    target = check_writable_file(path, suffix=".rrd")
    run = run_policy(env, policy, seed=seed, options=options)
    record_handshake(target, run.model, HandshakeFrames.from_run(run))
    return run
