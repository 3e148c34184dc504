import gymnasium as gym
import numpy as np

import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)

env = gym.make("softhand/Handshake-v0", design="pocket2-sil")
obs, info = env.reset(seed=0)
regions = env.unwrapped.region_names  # Thumb1-2, Index1-3, ..., Little1-3, Palm1-2, Back1-2
peak, done = dict.fromkeys(regions, 0.0), False
while not done:
    patch = dict(zip(regions, obs[32:50], strict=True))  # N; obs[:32]: 16 joint angles, speeds
    closing = [0.0 if max(patch[f"{d}{i}"] for i in (1, 2, 3)) > 0.1 else 0.3
               for d in ("Index", "Middle", "Ring", "Little")]  # motor speed, 1 = full closing
    fingers = [-1.0] * 4 if info.get("phase") in ("release", "return") else closing
    obs, reward, terminated, truncated, info = env.step(np.array(fingers + [0, 0], np.float32))
    peak = {r: max(peak[r], f) for r, f in info["region_forces_N"].items()}
    done = terminated or truncated
print({r: round(f, 2) for r, f in peak.items() if f > 0.05})  # peak load per region, N
