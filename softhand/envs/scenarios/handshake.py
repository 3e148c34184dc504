"""The handshake as a scenario: the partner reaches, slides its web space into the sensored
hand's, grips, shakes, lets go and leaves (softhand.envs.partner: the script and its sources),
in the grasp solved from the handshake's contacts (softhand.hands.grasp).

Reward (weights are constructor arguments, defaults in ``DEFAULT_REWARD_WEIGHTS``):

* ``grip`` = -w_grip ((F_mean - F_h) / F_h)^2 while the partner grips or shakes, with F_mean the
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

from softhand.envs.partner import (
    GRIP_FORCE_N,
    GRIP_PHALANGES,
    MAX_SQUEEZE,
    PHASES,
    PartnerScript,
    RelaxedHand,
    Timeline,
    partner_postures,
)
from softhand.envs.scenario import Scenario
from softhand.hands import partner_contact_pose, partner_start_pose, solve_grasp
from softhand.hands.grasp import PROSTHETIC_MOTOR_JOINTS
from softhand.validate import check_number, show

if TYPE_CHECKING:
    from softhand.envs.touch import TwoHandTouchEnv

__all__ = ["CONTACT_N", "DEFAULT_REWARD_WEIGHTS", "HandshakeScenario"]

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
    engaged: ClassVar[tuple[str, ...]] = ("grip", "shake")
    released: ClassVar[tuple[str, ...]] = ("release", "return", "done")
    reward_keys: ClassVar[tuple[str, ...]] = tuple(DEFAULT_REWARD_WEIGHTS)

    def __init__(self, *, squeeze: float = 1.0, overload_N: float = 10.0,
                 reward_weights: Mapping[str, float] | None = None,
                 randomize: bool = True) -> None:
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
        self._grip_measured = 0.0

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
        # the grip: GRIP_FORCE_N per phalanx (a data glove's mean per sensor, Melnyk et al. 2014)
        # on GRIP_PHALANGES phalanges, summed
        self.script = PartnerScript(self.timeline.scaled(factor), start, contact,
                                    grip_force_N=grip * GRIP_PHALANGES, shake_phase=phase,
                                    **partner_postures(self.grasp, *self._range.T))
        self._relaxed = RelaxedHand(self.script.timeline, self.grasp.prosthetic_q,
                                    PROSTHETIC_MOTOR_JOINTS.index("thumb_rot"))
        self._grip_measured = 0.0
        return start, quat

    @property
    def duration_s(self) -> float:
        return (self.script.timeline if self.script else self.timeline).total_s

    def mount(self, t: float) -> np.ndarray:
        return self.script.mount(t)

    def partner_targets(self, t: float, feel_N: np.ndarray, dt: float) -> np.ndarray:
        self._grip_measured = float(feel_N.sum())  # what the partner's digits press
        return self.script.grip(t, self._grip_measured, dt)

    def sensored_targets(self, t: float) -> np.ndarray:
        return self._relaxed.targets(t)

    def phase(self, t: float) -> str:
        return (self.script.timeline if self.script else self.timeline).phase(t)

    def reward_terms(self, forces_N: np.ndarray, action: np.ndarray,
                     phase: str) -> dict[str, float]:
        w, f = self.weights, forces_N
        over = f[f > self.overload_N] - self.overload_N
        terms = {"grip": 0.0, "contact": 0.0,
                 "overload": -w["overload"] * float(over @ over),
                 "effort": -w["effort"] * float(action @ action)}
        if phase in self.engaged:
            target = self.script.grip_force_N / GRIP_PHALANGES  # per phalanx
            touched = f[f > CONTACT_N]
            mean = float(touched.mean()) if touched.size else 0.0
            terms["grip"] = -w["grip"] * ((mean - target) / target) ** 2
            terms["contact"] = w["contact"] * touched.size / f.size
        return terms

    def info(self) -> dict[str, Any]:
        return {"partner_grip_N": self.script.grip_force_N if self.script else None,
                "partner_grip_measured_N": self._grip_measured,
                "partner_effort_rad": self.script.effort if self.script else 0.0,
                "grasp_thumb_rotation_rad": self.thumb_rotation_rad}
