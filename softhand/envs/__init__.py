"""The handshake environment (stage 4): Gymnasium env, partner script, skins on the hand, controllers.

- touch: the generic two-hand touch env (hands, skins, sensors, physics, action, observation);
- scenario: the seam a social touch implements; scenarios/: one module per touch (handshake);
- handshake: ``HandshakeEnv``, the touch env with the handshake scenario;
- partner: the partner's script and population bounds; population: partners like the paper's 30;
- vector: ``HandshakeVectorEnv``, W handshakes stepped together (mujoco.batch, softhand.envs.batch);
- spaces: the name and unit of every action and observation entry, and the docstring's tables;
- picture: the scene's offscreen picture (``render_mode="rgb_array"``, ``softhand render``);
- physics, sensing, skins, models, controllers, run: the pieces the env and its runs use.

Importing this package registers ``softhand/Handshake-v0``:

    import gymnasium as gym
    import softhand.envs  # noqa: F401  (registers the env)
    env = gym.make("softhand/Handshake-v0", design="pocket2-sil")
"""

import gymnasium as gym

from softhand.envs.handshake import DEFAULT_REWARD_WEIGHTS, HandshakeEnv

__all__ = ["DEFAULT_REWARD_WEIGHTS", "HandshakeEnv"]

if "softhand/Handshake-v0" not in gym.registry:
    # vector_entry_point: gymnasium.make_vec(..., vectorization_mode="vector_entry_point") makes
    # the batched vector env (mujoco.batch), not N copies of the env
    gym.register(id="softhand/Handshake-v0", entry_point="softhand.envs.handshake:HandshakeEnv",
                 vector_entry_point="softhand.envs.vector:HandshakeVectorEnv",
                 max_episode_steps=None)
