import gymnasium as gym
import numpy as np

import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)

env = gym.make("softhand/Handshake-v0", design="pocket2-sil", observe="load")
names = env.unwrapped.observation_names  # "qpos/pro_index_mcp [rad]", ..., "episode_fraction [-]"
loads = [i for i, name in enumerate(names) if name.startswith("load_estimate/")]  # 18 regions
regions = env.unwrapped.region_names  # Thumb1-2, Index1-3, ..., Little1-3, Palm1-2, Back1-2
obs, info = env.reset(seed=0)
peak, done = dict.fromkeys(regions, 0.0), False
while not done:
    load = dict(zip(regions, obs[loads], strict=True))  # N, read out from each sensor patch
    closing = [0.0 if max(load[f"{d}{i}"] for i in (1, 2, 3)) > 0.1 else 0.3
               for d in ("Index", "Middle", "Ring", "Little")]  # motor speed, 1 = full closing
    fingers = [-1.0] * 4 if info.get("phase") in ("release", "return") else closing
    obs, reward, terminated, truncated, info = env.step(np.array(fingers + [0, 0], np.float32))
    peak = {r: max(peak[r], f) for r, f in info["region_forces_N"].items()}
    done = terminated or truncated
print({r: round(f, 2) for r, f in peak.items() if f > 0.05})  # peak true load per region, N
