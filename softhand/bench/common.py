"""What every benchmark report says about where it ran."""

from __future__ import annotations

import os
import platform
from typing import Any

import mujoco

from softhand.fem.sweep import git_revision
from softhand.parallel import available_cpus, default_threads

__all__ = ["machine_info", "machine_line"]


def machine_info() -> dict[str, Any]:
    """Platform, CPUs (all, and those this process may use), default threads, Python, MuJoCo, git,
    and the load average when the benchmark started (other work on the machine slows it)."""
    return {"platform": platform.platform(), "cpus": os.cpu_count(),
            "available_cpus": available_cpus(), "default_threads": default_threads(),
            "python": platform.python_version(), "mujoco": mujoco.__version__,
            "git_revision": git_revision(), "load_1min": _load()}


def _load() -> float | None:
    """The 1-minute load average (None where the platform has none)."""
    try:
        return round(os.getloadavg()[0], 2)
    except (AttributeError, OSError):
        return None


def machine_line(machine: dict[str, Any]) -> str:
    """One Markdown line naming the machine of a report (``machine_info()``)."""
    load = machine.get("load_1min")
    return (f"Machine: {machine['platform']}, {machine['cpus']} CPUs, Python "
            f"{machine['python']}, MuJoCo {machine.get('mujoco', '?')}; git "
            f"{machine.get('git_revision', '?')}"
            + ("" if load is None else f"; load average {load:g} at the start") + ".")
