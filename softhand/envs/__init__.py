"""The handshake environment (stage 4): Gymnasium env, partner script, skins on the hand, controllers.

Importing this package registers ``softhand/Handshake-v0``::

    import gymnasium as gym
    import softhand.envs  # noqa: F401  (registers the env)
    env = gym.make("softhand/Handshake-v0", design="pocket2-sil")
"""

import gymnasium as gym

from softhand.envs.handshake import DEFAULT_REWARD_WEIGHTS, HandshakeEnv

__all__ = ["DEFAULT_REWARD_WEIGHTS", "HandshakeEnv"]

if "softhand/Handshake-v0" not in gym.registry:
    gym.register(id="softhand/Handshake-v0", entry_point="softhand.envs.handshake:HandshakeEnv",
                 max_episode_steps=None)
