"""The scenario seam: one social touch (a handshake, a caress, a pat, a hand held still) on the
generic two-hand touch env (`softhand.envs.touch.TwoHandTouchEnv`).

The env owns what every touch shares: the two hands and their skins, the sensors, the physics
behind its seam, the prosthetic's action, the observation, the force accounting. A scenario owns
what makes one touch that touch:

- ``prepare(env)``: once, after the scene is built: what the touch needs of the two hands (the
  handshake solves its grasp); returns the sensored hand's pre-shaped drives as (qpos address, act
  address, value)
- ``reset(env, rng, opts)``: each episode: the partner's plan (its mount's start pose, timing, grip)
  from the episode's random stream and the reset options
- ``mount(t)``: the partner's mount position at time t (m, world frame); ``mount_path(times)`` at
  many (default: mount(t) for each)
- ``partner_targets(...)``: the partner's digit servo targets at time t, from what its digits feel
  (once per action step)
- ``sensored_targets(t)``: the relaxed human sensored hand's drive targets (``hand="human"``)
- ``phase(t)``: the phase's name at time t; ``duration_s`` the episode's length
- ``reward_terms(...)``: the reward's terms at a step
- ``info()``: the scenario's own ``info`` entries

Class attributes name the phases, the phases in which the hands hold each other (``engaged``;
controllers close, the reward counts a grip) and those in which the sensored hand lets go
(``released``). A new touch is a new module in ``softhand/envs/scenarios/`` with a Scenario
subclass, and an env that passes it to TwoHandTouchEnv (as ``softhand.envs.handshake`` does);
nothing in the env is copied.
"""

from __future__ import annotations

import abc
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

if TYPE_CHECKING:  # the env imports this module; only type hints go the other way
    from softhand.envs.touch import TwoHandTouchEnv

__all__ = ["Scenario"]


class Scenario(abc.ABC):
    """One social touch between the sensored hand and the partner (see the module docstring)."""

    #: the scenario's name (the env's ``spec`` and the CLI use it)
    name: ClassVar[str]
    #: phase names in time order
    phases: ClassVar[tuple[str, ...]]
    #: phases in which the hands hold each other
    engaged: ClassVar[tuple[str, ...]]
    #: phases in which the sensored hand lets go
    released: ClassVar[tuple[str, ...]]
    #: the keys of reward_terms(), for the reward's documentation and checks
    reward_keys: ClassVar[tuple[str, ...]]

    @abc.abstractmethod
    def prepare(self, env: TwoHandTouchEnv) -> tuple[tuple[int, int, float], ...]:
        """Once per env, after its scene is built."""

    @abc.abstractmethod
    def reset(self, env: TwoHandTouchEnv, rng: np.random.Generator,
              options: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """Plan an episode; return the partner mount's start position and quaternion."""

    @property
    @abc.abstractmethod
    def duration_s(self) -> float:
        """The planned episode's length (s)."""

    @abc.abstractmethod
    def mount(self, t: float) -> np.ndarray:
        """The partner's mount position at time ``t`` (m, world frame)."""

    def mount_path(self, times: np.ndarray) -> np.ndarray:
        """The mount's positions (m) at ``times`` (s), shape (len(times), 3)."""
        return np.array([self.mount(t) for t in times])

    @abc.abstractmethod
    def partner_targets(self, t: float, feel_N: np.ndarray, dt: float) -> np.ndarray:
        """The partner's digit servo targets at ``t`` from the net force on each of its
        phalanges (``feel_N``), for the next ``dt`` seconds."""

    @abc.abstractmethod
    def sensored_targets(self, t: float) -> np.ndarray:
        """The relaxed human sensored hand's 6 drive targets at ``t`` (rad)."""

    @abc.abstractmethod
    def phase(self, t: float) -> str:
        """The phase at time ``t``, one of `phases`."""

    @abc.abstractmethod
    def reward_terms(self, forces_N: np.ndarray, action: np.ndarray,
                     phase: str) -> dict[str, float]:
        """The reward's terms at a step, from the regions' true forces and the action."""

    def info(self) -> dict[str, Any]:
        """The scenario's own ``info`` entries (none by default)."""
        return {}
