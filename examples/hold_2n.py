"""Hold 2 N on each finger's middle phalanx: a controller written from the README quickstart alone.

Run: ``python examples/hold_2n.py [TARGET_N [OBSERVE]]``. The quickstart's env, ``observe="load"``:
the observation carries per region the load a calibrated read-out infers from its sensor patch
(``load_estimate/{region} [N]`` in ``env.unwrapped.observation_names``). While the partner grips
and shakes, each finger's motor speed is proportional to the error on its middle phalanx (Index2,
Middle2, Ring2, Little2); the fingers open when the partner lets go. Prints, per region, the true
load (``info["region_forces_N"]``) held during the shake, from 0.3 s in (the fingers closing).
``OBSERVE`` ``sensor`` regulates the sensor patches' readings instead, ``contact`` the true loads.
"""

from __future__ import annotations

import sys

import gymnasium as gym
import numpy as np

import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)

FINGERS = ("Index", "Middle", "Ring", "Little")
GAIN_PER_N = 1.0  # motor speed (1 = full closing) per N of error
SETTLE_S = 0.3  # the start of the shake left out: the fingers are still closing onto the partner
#: the observation entries each ``observe`` gives the regions (their names' first part)
REGION_VALUES = {"load": "load_estimate/", "sensor": "sensor_patch/", "contact": "region_load/"}


def main(target_N: float = 2.0, seed: int = 0,
         observe: str = "load") -> dict[str, dict[str, float]]:
    env = gym.make("softhand/Handshake-v0", design="pocket2-sil", observe=observe)
    names = env.unwrapped.observation_names
    loads = [i for i, name in enumerate(names) if name.startswith(REGION_VALUES[observe])]
    regions = env.unwrapped.region_names
    held: dict[str, list[float]] = {f"{finger}2": [] for finger in FINGERS}
    obs, info = env.reset(seed=seed)
    shake_start, done = None, False
    while not done:
        load = dict(zip(regions, obs[loads], strict=True))  # N, per region
        if info["phase"] in ("grip", "shake"):
            fingers = [float(np.clip(GAIN_PER_N * (target_N - load[f"{finger}2"]), -1.0, 1.0))
                       for finger in FINGERS]
        else:  # wait for the partner's hand; open when it lets go
            fingers = [-1.0 if info["phase"] in ("release", "return") else 0.0] * 4
        obs, _reward, terminated, truncated, info = env.step(np.array(fingers + [0, 0],
                                                                      np.float32))
        if info["phase"] == "shake":
            shake_start = info["time_s"] if shake_start is None else shake_start
            if info["time_s"] - shake_start > SETTLE_S:
                for region, values in held.items():
                    values.append(info["region_forces_N"][region])
        done = terminated or truncated
    env.close()
    out = {region: {"mean_N": float(np.mean(v)), "min_N": float(np.min(v)),
                    "max_N": float(np.max(v)),
                    "within_0.5N_pct": float(100 * np.mean(np.abs(np.array(v) - target_N) < 0.5))}
           for region, v in held.items()}
    print(f"target {target_N:.2f} N on {REGION_VALUES[observe][:-1]}; true load held during the "
          "shake:")
    for region, v in out.items():
        print(f"  {region:8s} mean {v['mean_N']:4.2f} N, {v['min_N']:4.2f}-{v['max_N']:4.2f} N, "
              f"{v['within_0.5N_pct']:3.0f} % of the time within 0.5 N of the target")
    return out


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 2.0,
         observe=sys.argv[2] if len(sys.argv) > 2 else "load")
