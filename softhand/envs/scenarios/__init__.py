"""Social touches on the two-hand touch env, one module each (softhand.envs.scenario: the seam).

- handshake: the paper's handshake (Cabibihan et al.): reach, grip, shake, hold, release, return.

A new touch (a caress, a pat, a hand held still) is a new module here with a
`Scenario` subclass: its phases, the partner's plan (mount path and
digit targets), the relaxed human hand's targets, the reward; an env passes it to
`TwoHandTouchEnv`, as softhand.envs.handshake does.
"""

from softhand.envs.scenarios.handshake import DEFAULT_REWARD_WEIGHTS, HandshakeScenario

__all__ = ["DEFAULT_REWARD_WEIGHTS", "HandshakeScenario"]
