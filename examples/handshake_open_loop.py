"""Close the prosthetic hand with one signal: the open-loop controller in Handshake-v0.

Run: ``python examples/handshake_open_loop.py [SPEED]``. Every digit closes at SPEED (fraction of
the motors' maximum, default 0.6) for 0.8 s once the partner grips, holds, and opens when it lets
go, as a myoelectric user does with one short "close" signal. Prints the peak force per region and which
regions pass 2 N, with rigid shells and with the most lifelike skin side by side.
"""

from __future__ import annotations

import sys

import gymnasium as gym

import softhand.envs  # noqa: F401  (registers softhand/Handshake-v0)
from softhand.envs.controllers import OpenLoopClose


def peaks(design: str, speed: float, seed: int = 0) -> dict[str, float]:
    env = gym.make("softhand/Handshake-v0", design=design)
    controller = OpenLoopClose(speed=speed)
    obs, info = env.reset(seed=seed)
    peak = dict.fromkeys(info["region_forces_N"], 0.0)
    while True:
        obs, _reward, terminated, truncated, info = env.step(controller(obs, info))
        for k, v in info["region_forces_N"].items():
            peak[k] = max(peak[k], v)
        if terminated or truncated:
            break
    env.close()
    return peak


def main(speed: float = 0.6) -> dict[str, dict[str, float]]:
    print("two handshakes, the hand closing open-loop: with rigid shells, then with pocket2-sil "
          "skins; a few seconds ...", flush=True)
    out = {design: peaks(design, speed) for design in ("rigid", "pocket2-sil")}
    print(f"open-loop closing at {speed:.0%} of full speed; peak force per region (N):")
    print(f"  {'region':8s} {'rigid':>7s} {'pocket2-sil':>12s}")
    for region in out["rigid"]:
        a, b = out["rigid"][region], out["pocket2-sil"][region]
        print(f"  {region:8s} {a:7.2f} {b:12.2f}" + ("   > 2 N" if max(a, b) > 2 else ""))
    return out


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 0.6)
