"""Hold a grip force with the region forces: the force-regulating controller in Handshake-v0.

Run: ``python examples/handshake_force_regulating.py [TARGET_N]``. Each digit closes until its
most loaded region reads TARGET_N (default 2.5 N, the human handshake grip of Melnyk et al. 2014)
and opens a little when over it. Prints, per digit, the force held during the shake.
"""

from __future__ import annotations

import sys

import gymnasium as gym
import numpy as np

import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)
from softhand.envs.controllers import ForceRegulating

DIGITS = ("Index", "Middle", "Ring", "Little", "Thumb")


def main(target_N: float = 2.5, seed: int = 0) -> dict[str, float]:
    print(f"one handshake (partner seed {seed}, pocket2-sil skins), each digit holding "
          f"{target_N:g} N; a few seconds ...", flush=True)
    env = gym.make("softhand/Handshake-v0", design="pocket2-sil")
    controller = ForceRegulating(target_N=target_N)
    obs, info = env.reset(seed=seed)
    held: dict[str, list[float]] = {d: [] for d in DIGITS}
    while True:
        obs, _reward, terminated, truncated, info = env.step(controller(obs, info))
        if info["phase"] == "shake":
            for d in DIGITS:
                held[d].append(max(v for k, v in info["region_forces_N"].items()
                                   if k.startswith(d)))
        if terminated or truncated:
            break
    env.close()
    out = {d: float(np.median(v)) for d, v in held.items()}
    print(f"target {target_N:.2f} N on each digit's most loaded region; held during the shake:")
    for d, v in out.items():
        print(f"  {d:7s} median {v:5.2f} N")
    return out


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 2.5)
