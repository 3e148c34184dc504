"""The partner's scripted handshake: reach, grip, shake, release and return.

Timeline (Cabibihan et al., "Handshake timing", Front. Robot. AI 2022: a handshake lasts
3.63 +/- 0.45 s: reach 0.92 s, contact 1.96 s with a 1.31 s main shake, return 0.75 s):

========== ============================================================================
phase      what the partner does
========== ============================================================================
reach      mount moves from its start pose to the contact pose (minimum-jerk), 0.92 s
grip       fingers and thumb close until the grip force reaches its target, 0.30 s
shake      mount oscillates at 4 Hz (Melnyk et al., IEEE AIM 2014), 1.31 s
release    fingers open, 0.35 s (the rest of the 1.96 s contact)
return     mount goes back to its start pose, 0.75 s
========== ============================================================================

Grip: the partner regulates the mean force its digits feel over the phalanges that touch the
prosthesis (contact sensors ``hum_feel_*`` on the phalanx tissues, as the data-glove sensors on
the subjects' fingers did; the palm and thenar are left out, so that a push on the palm does not
open the fingers) to 2.5 N (the average
grip force measured with data gloves, Melnyk et al. 2014) times ``squeeze``; an integral
controller moves the finger and thumb flexion targets. Shake amplitude: +-5 mm
vertically (assumption: only the *relative* motion of the two hands is modelled; the arm's gross
shake moves both hands together and is left out, "a scene models only what it needs").
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass
from functools import cached_property

import numpy as np

__all__ = ["PHASES", "PartnerScript", "Timeline"]

PHASES = ("reach", "grip", "shake", "release", "return", "done")
GRIP_FORCE_N = 2.5  # Melnyk et al. 2014: average grip force near 2.5 N
SHAKE_HZ = 4.0  # Melnyk et al. 2014
SHAKE_AMPLITUDE_M = 0.005  # assumption, see the module docstring


@dataclass(frozen=True)
class Timeline:
    """Phase durations (s) after Cabibihan et al. 2022."""

    reach_s: float = 0.92
    grip_s: float = 0.30
    shake_s: float = 1.31
    release_s: float = 0.35
    return_s: float = 0.75

    def __post_init__(self) -> None:
        for name in ("reach_s", "grip_s", "shake_s", "release_s", "return_s"):
            v = getattr(self, name)
            if not (np.isfinite(v) and 0 < v <= 10):
                raise ValueError(f"{name} = {v!r} s must be in (0, 10]")

    @cached_property
    def ends(self) -> tuple[float, ...]:
        """End time (s) of each phase but ``done``; computed once (the env asks every step)."""
        return tuple(float(x) for x in np.cumsum([self.reach_s, self.grip_s, self.shake_s,
                                                  self.release_s, self.return_s]))

    @property
    def total_s(self) -> float:
        return self.ends[-1]

    def phase(self, t: float) -> str:
        return PHASES[min(bisect_right(self.ends, t), len(PHASES) - 1)]

    def scaled(self, factor: float) -> Timeline:
        return Timeline(*(factor * v for v in (self.reach_s, self.grip_s, self.shake_s,
                                                self.release_s, self.return_s)))


def _min_jerk(s: float) -> float:
    s = min(max(s, 0.0), 1.0)
    return s**3 * (10 - 15 * s + 6 * s * s)


class PartnerScript:
    """Mount pose and grip targets of the partner at time t, with a grip-force regulator.

    Args:
        timeline: phase durations.
        start_pos, contact_pos: mount positions (m); the orientation stays fixed.
        grip_force_N: target mean force over the touched regions, > 0.
        shake_phase: shake phase offset (rad).
        flex_range: (open, closed) flexion targets of the partner's digit servos (rad).
    """

    def __init__(self, timeline: Timeline, start_pos: np.ndarray, contact_pos: np.ndarray, *,
                 grip_force_N: float = GRIP_FORCE_N, shake_phase: float = 0.0,
                 flex_range: tuple[np.ndarray, np.ndarray]) -> None:
        if not (np.isfinite(grip_force_N) and grip_force_N > 0):
            raise ValueError(f"grip_force_N = {grip_force_N!r} must be finite and > 0")
        self.timeline = timeline
        self.start = np.asarray(start_pos, float)
        self.contact = np.asarray(contact_pos, float)
        self.grip_force_N = float(grip_force_N)
        self.shake_phase = float(shake_phase)
        self.open, self.closed = (np.asarray(x, float) for x in flex_range)
        self.flex = self.open.copy()

    def mount(self, t: float) -> np.ndarray:
        tl = self.timeline
        e = tl.ends
        if t < e[0]:
            return self.start + _min_jerk(t / tl.reach_s) * (self.contact - self.start)
        if t < e[3]:
            pos = self.contact.copy()
            if e[1] <= t < e[2]:
                ramp = min(1.0, (t - e[1]) / 0.1, (e[2] - t) / 0.1)  # 0.1 s fade in and out
                pos[2] += ramp * SHAKE_AMPLITUDE_M * np.sin(2 * np.pi * SHAKE_HZ * (t - e[1])
                                                              + self.shake_phase)
            return pos
        return self.contact + _min_jerk((t - e[3]) / tl.return_s) * (self.start - self.contact)

    def grip(self, t: float, mean_contact_force_N: float, dt: float) -> np.ndarray:
        """Digit flexion targets: close until the grip force is reached, hold, then open."""
        phase = self.timeline.phase(t)
        span = self.closed - self.open
        if phase in ("grip", "shake"):
            error = (self.grip_force_N - mean_contact_force_N) / self.grip_force_N
            # integral action: full range in about 0.3 s at 100 % force error
            self.flex = np.clip(self.flex + span * np.clip(error, -1.0, 1.0) * dt / 0.3,
                                self.open, self.closed)
        elif phase in ("release", "return", "done"):
            self.flex = np.maximum(self.open, self.flex - span * dt / 0.2)
        return self.flex
