"""What a pocket's dead band does to a controller that feels through embedded sensors.

Run: ``python examples/handshake_sensors.py``. The neutral controller (the paper's sensored hand:
each finger closes until it touches the partner, then holds) runs three times on pocket2-sil
skins: fed the true contact forces, fed sensors under the outer layer, and fed sensors on the
pocket floor, which feel nothing until the 2 mm pocket closes (about 0.32 N of load). Prints, per
finger, the force it held during the shake, and per run what the sensors read on the palm.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)
from softhand.envs.controllers import Neutral

FINGERS = ("Index", "Middle", "Ring", "Little")
RUNS = {"contact": ("contact", "interface"), "sensor under the outer layer": ("sensor", "interface"),
        "sensor on the pocket floor": ("sensor", "pocket-floor")}


def held_forces(signal: str, placement: str, seed: int = 0) -> dict[str, float]:
    """Per finger the mean true force of its most loaded region over the shake, and the peak
    Palm1 reading (N on the sensor patch)."""
    env = gym.make("softhand/Handshake-v0", design="pocket2-sil", sensor_placement=placement)
    controller = Neutral(signal=signal)
    obs, info = env.reset(seed=seed)
    held: dict[str, list[float]] = {f: [] for f in FINGERS}
    palm = 0.0
    while True:
        obs, _reward, terminated, truncated, info = env.step(controller(obs, info))
        palm = max(palm, info["sensor_readings_N"]["Palm1"])
        if info["phase"] == "shake":
            for f in FINGERS:
                held[f].append(max(v for k, v in info["region_forces_N"].items()
                                   if k.startswith(f)))
        if terminated or truncated:
            break
    env.close()
    return {**{f: float(np.mean(v)) for f, v in held.items()}, "Palm1 reading": palm}


def main(seed: int = 0) -> dict[str, dict[str, float]]:
    print(f"{len(RUNS)} handshakes on pocket2-sil, the neutral controller fed: "
          f"{'; '.join(RUNS)}; a few seconds ...", flush=True)
    out = {label: held_forces(*how, seed=seed) for label, how in RUNS.items()}
    print("force held during the shake per finger (N, true contact force), neutral controller:")
    print(f"{'fed':32s}" + "".join(f"{f:>9s}" for f in FINGERS) + "  Palm1 reading N")
    for label, v in out.items():
        print(f"{label:32s}" + "".join(f"{v[f]:9.2f}" for f in FINGERS)
              + f"  {v['Palm1 reading']:.2f}")
    return out


if __name__ == "__main__":
    main()
