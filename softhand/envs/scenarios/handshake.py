"""The handshake as a scenario: the partner reaches, slides its web space into the sensored
hand's, grips, shakes, lets go and leaves (softhand.envs.partner: the script and its sources),
in the grasp solved from the handshake's contacts (softhand.hands.grasp).

Reward (weights are constructor arguments, defaults in ``DEFAULT_REWARD_WEIGHTS``):

* ``grip`` = -w_grip ((F_mean - F_h) / F_h)^2 while the hands hold each other (grip, shake, hold), with F_mean the
  mean force over touched regions (> 0.05 N) and F_h the partner's grip per phalanx (2.5 N,
  Melnyk et al. 2014, times ``squeeze``): a human-like, matched grip;
* ``contact`` = +w_contact (touched regions / 18) in the same phases: a full-hand grip;
* ``overload`` = -w_overload sum_i max(0, F_i - overload_N)^2 at all times;
* ``effort`` = -w_effort |a|^2.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numba import njit

from softhand.compiled import pairwise_sum, row_sums
from softhand.envs.partner import (
    GRIP_FORCE_N,
    GRIP_PHALANGES,
    HOLDING,
    MAX_SQUEEZE,
    PHASES,
    RELEASING,
    PartnerScript,
    RelaxedHand,
    Timeline,
    partner_postures,
    phase_at,
    phase_index,
)
from softhand.envs.scenario import Scenario
from softhand.hands import partner_contact_pose, partner_start_pose, solve_grasp
from softhand.hands.grasp import PROSTHETIC_MOTOR_JOINTS
from softhand.hands.scene import press_offset
from softhand.validate import check_number, show

if TYPE_CHECKING:
    from softhand.envs.touch import TwoHandTouchEnv

__all__ = ["CONTACT_N", "DEFAULT_REWARD_WEIGHTS", "HandshakeScenario", "HandshakeWorlds",
           "handshake_reward"]

DEFAULT_REWARD_WEIGHTS = {"grip": 1.0, "contact": 0.5, "overload": 0.1, "effort": 0.01}
CONTACT_N = 0.05  # a region counts as touched above this force


class HandshakeScenario(Scenario):
    """The handshake (module docstring).

    Args:
        squeeze: multiplier of the partner's grip force, in (0, 5] (``MAX_SQUEEZE``, the hard
            case: above it the partner's grip effort is at its limit and the forces no longer
            follow the squeeze, see softhand.envs.partner.MAX_SQUEEZE).
        overload_N: region force (N) above which the overload penalty applies, finite and > 0.
        reward_weights: override of ``DEFAULT_REWARD_WEIGHTS`` entries, each finite and >= 0.
        randomize: vary the partner (timing +-5 %, grip +-10 %, shake phase) from the seed;
            True or False.
    """

    name: ClassVar[str] = "handshake"
    phases: ClassVar[tuple[str, ...]] = PHASES
    engaged: ClassVar[tuple[str, ...]] = HOLDING
    released: ClassVar[tuple[str, ...]] = RELEASING
    reward_keys: ClassVar[tuple[str, ...]] = tuple(DEFAULT_REWARD_WEIGHTS)

    def __init__(self, *, squeeze: float = 1.0, overload_N: float = 10.0,
                 reward_weights: Mapping[str, float] | None = None,
                 randomize: bool = True) -> None:
        self._phase_row = {p: np.array([i]) for i, p in enumerate(self.phases)}
        self.squeeze = check_number("squeeze", squeeze, lo=0.0, hi=MAX_SQUEEZE, lo_open=True,
                                    why=f"(above {MAX_SQUEEZE:g} the partner's grip is at its "
                                        "limit: softhand.envs.partner.MAX_SQUEEZE)")
        # no upper bound: a threshold above every force the scene makes switches the term off,
        # as a zero weight does
        self.overload_N = check_number("overload_N", overload_N, lo=0.0, lo_open=True)
        weights = dict(DEFAULT_REWARD_WEIGHTS)
        if reward_weights is not None and not isinstance(reward_weights, Mapping):
            raise ValueError(f"reward_weights = {show(reward_weights)}: expected a mapping of "
                             f"{', '.join(weights)} to numbers >= 0")
        for key, value in (reward_weights or {}).items():
            if key not in weights:
                raise ValueError(f"reward weight {key!r} is unknown; allowed: {', '.join(weights)}")
            weights[key] = check_number(f"reward_weights[{key!r}]", value, lo=0.0)
        if not isinstance(randomize, (bool, np.bool_)):
            raise ValueError(f"randomize = {show(randomize)}: expected True or False")
        self.weights = weights
        self.randomize = bool(randomize)
        self.timeline = Timeline()
        #: the episode's partner script (None before the first reset)
        self.script: PartnerScript | None = None

    def prepare(self, env: TwoHandTouchEnv) -> tuple[tuple[int, int, float], ...]:
        """Solve the grasp of the env's two hands; the sensored hand's thumb is pre-rotated to
        it (a user pre-shapes the hand for a handshake, and the partner's hand slides into the web
        space under it)."""
        m = env.model
        self._config = env.config
        #: the handshake's grasp, solved from its contacts for these two hands (cached)
        self.grasp = solve_grasp(env.config)
        self._range = m.actuator_ctrlrange[env.partner_servos].copy()
        self.thumb_rotation_rad = float(self.grasp.prosthetic_q[
            PROSTHETIC_MOTOR_JOINTS.index("thumb_rot")])
        rot_motor = m.actuator("pro_thumb_rot_motor").id
        return ((env.thumb_rotation_qpos, int(m.actuator_actadr[rot_motor]), self.thumb_rotation_rad),)

    def reset(self, env: TwoHandTouchEnv, rng: np.random.Generator,
              options: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        factor = float(rng.uniform(0.95, 1.05)) if self.randomize else 1.0
        grip = GRIP_FORCE_N * self.squeeze * (float(rng.uniform(0.9, 1.1)) if self.randomize
                                              else 1.0)
        phase = float(rng.uniform(0, 2 * np.pi)) if self.randomize else 0.0
        if "duration_s" in options:
            factor = options["duration_s"] / self.timeline.total_s
        grip = options.get("grip_N", grip)
        phase = options.get("shake_phase_rad", phase)
        start, quat = partner_start_pose(self._config)
        contact, _ = partner_contact_pose(self._config)
        # the partner's arm presses its palm onto the other's: its mount aims past the grasp
        contact = contact + press_offset(self._config.partner_arm, "hum_")
        # the grip: GRIP_FORCE_N per phalanx (Melnyk et al. 2014's average grip, read as per
        # phalanx: an assumption, softhand.envs.partner.GRIP_FORCE_N) on GRIP_PHALANGES, summed
        self.script = PartnerScript(self.timeline.scaled(factor), start, contact,
                                    grip_force_N=grip * GRIP_PHALANGES, shake_phase=phase,
                                    **partner_postures(self.grasp, *self._range.T))
        self._relaxed = RelaxedHand(self.script.timeline, self.grasp.prosthetic_q,
                                    PROSTHETIC_MOTOR_JOINTS.index("thumb_rot"))
        #: the episode's per-step computations (one world of HandshakeWorlds)
        self.world = HandshakeWorlds([self], share=True)
        return start, quat

    @property
    def duration_s(self) -> float:
        return (self.script.timeline if self.script else self.timeline).total_s

    def mount(self, t: float) -> np.ndarray:
        return self.script.mount(t)

    def mount_path(self, times: np.ndarray) -> np.ndarray:
        if type(self).mount is not HandshakeScenario.mount:  # a subclass moves the mount itself
            return super().mount_path(times)
        return self.script.mount_path(times)  # the same formula, over all times at once

    def partner_targets(self, t: float, feel_N: np.ndarray, dt: float) -> np.ndarray:
        return self.world.partner_targets(np.array([t], float), np.asarray(feel_N)[None], dt)[0]

    def sensored_targets(self, t: float) -> np.ndarray:
        return self.world.sensored_targets(np.array([t], float))[0]

    def phase(self, t: float) -> str:
        if self.script is None:
            return self.timeline.phase(t)
        return self.phases[phase_at(self.script.ends[0], float(t))]  # the one world's

    def reward_terms(self, forces_N: np.ndarray, action: np.ndarray,
                     phase: str) -> dict[str, float]:
        terms = self.world.reward_table(np.asarray(forces_N, float)[None],
                                        np.asarray(action, float)[None], self._phase_row[phase])
        return dict(zip(self.reward_keys, terms[0].tolist(), strict=True))

    def info(self) -> dict[str, Any]:
        return {"partner_grip_N": self.script.grip_force_N if self.script else None,
                "partner_grip_measured_N": float(self.world.grip_measured_N[0]) if self.script
                else 0.0,
                "partner_effort_rad": self.script.effort if self.script else 0.0,
                "grasp_thumb_rotation_rad": self.thumb_rotation_rad}


@njit(cache=True)
def handshake_reward(forces_N, action, phase, grip_N, weights, overload_N):
    """The reward's terms (module docstring) of W worlds, compiled: ``forces_N`` (W, regions),
    ``action`` (W, 6), ``phase`` (W,) each world's index in PHASES (the grip and contact terms
    count while the hands hold each other: HOLDING), ``grip_N`` (W,) the partner's summed
    grip target (its grip per phalanx times GRIP_PHALANGES), ``weights`` (W, 4) in
    DEFAULT_REWARD_WEIGHTS order, ``overload_N`` (W,). Returns the terms (W, 4) in that order.
    Sums go in numpy's order (pairwise_sum), as the numpy code this replaced, bit for bit."""
    worlds, regions = forces_N.shape
    out = np.zeros((worlds, 4))
    over2 = np.empty(regions)
    held = np.empty(regions)
    for w in range(worlds):
        count = 0
        for i in range(regions):
            f = forces_N[w, i]
            over = max(f - overload_N[w], 0.0)
            over2[i] = over * over
            touched = f > CONTACT_N
            count += touched
            held[i] = f if touched else 0.0
        if phase[w] == _GRIP or phase[w] == _SHAKE or phase[w] == _HOLD:  # HOLDING
            target = grip_N[w] / GRIP_PHALANGES  # per phalanx
            x = (pairwise_sum(held) / max(count, 1) - target) / target
            out[w, 0] = -weights[w, 0] * (x * x)
            out[w, 1] = weights[w, 1] * count / regions
        out[w, 2] = -weights[w, 2] * pairwise_sum(over2)
        out[w, 3] = -weights[w, 3] * pairwise_sum(action[w] * action[w])
    return out


_GRIP, _SHAKE, _HOLD = (PHASES.index(p) for p in HOLDING)


class HandshakeWorlds:
    """The per-step part of the handshake for W worlds at once, over arrays with a leading world
    axis: the partner's script and grip regulator, the relaxed sensored hand, the phases and the
    reward. The vector env (softhand.envs.vector) steps its worlds with it; a single
    `HandshakeScenario` is one world of it (W = 1), so the logic exists once.

    Args:
        scenarios: planned scenarios (after their reset), one per world.
        share: with one scenario, step its own script and relaxed hand (the single env) instead
            of copies.
    """

    def __init__(self, scenarios: list[HandshakeScenario], share: bool = False) -> None:
        if share and len(scenarios) == 1:
            self.script, self.relaxed = scenarios[0].script, scenarios[0]._relaxed
        else:
            self.script = PartnerScript.stack([s.script for s in scenarios])
            self.relaxed = RelaxedHand.stack([s._relaxed for s in scenarios])
        self.weights = np.array([[s.weights[k] for k in DEFAULT_REWARD_WEIGHTS]
                                 for s in scenarios])
        self.overload_N = np.array([s.overload_N for s in scenarios], float)
        #: what each world's partner digits pressed at its last action step (N)
        self.grip_measured_N = np.zeros(len(scenarios))

    def set_world(self, i: int, scenario: HandshakeScenario) -> None:
        """World ``i`` starts ``scenario``'s planned episode."""
        self.script.set_world(i, scenario.script)
        self.relaxed.set_world(i, scenario._relaxed)
        self.weights[i] = [scenario.weights[k] for k in DEFAULT_REWARD_WEIGHTS]
        self.overload_N[i] = scenario.overload_N
        self.grip_measured_N[i] = 0.0

    def partner_targets(self, t: np.ndarray, feel_N: np.ndarray, dt: float) -> np.ndarray:
        """The partner's digit targets (W, servos) from the net force on each of its phalanges
        (``feel_N``, (W, phalanges))."""
        self.grip_measured_N = row_sums(feel_N)  # what the partner's digits press
        return self.script.grips(t, self.grip_measured_N, dt)

    def sensored_targets(self, t: np.ndarray) -> np.ndarray:
        return self.relaxed.targets_at(t)

    def phase_index(self, t: np.ndarray) -> np.ndarray:
        """Each world's phase at its time ``t`` (W,), as an index into PHASES."""
        return phase_index(self.script.ends, t)

    def reward_terms(self, forces_N: np.ndarray, action: np.ndarray,
                     phase: np.ndarray) -> dict[str, np.ndarray]:
        """Each world's reward terms (term -> (W,)) at its ``phase`` (W,) index in PHASES."""
        terms = self.reward_table(forces_N, action, phase)
        return {k: terms[:, i] for i, k in enumerate(DEFAULT_REWARD_WEIGHTS)}

    def reward_table(self, forces_N: np.ndarray, action: np.ndarray,
                     phase: np.ndarray) -> np.ndarray:
        """`reward_terms` as one (W, 4) array, in DEFAULT_REWARD_WEIGHTS order."""
        return handshake_reward(forces_N, action, phase, self.script.grip_forces_N,
                                self.weights, self.overload_N)
