"""The oldest versions of the libraries softhand builds on that it runs with, and a check that
refuses an older one in one line instead of failing deep inside.

The minimums are softhand's own declared requirements (``pyproject.toml``'s ``dependencies``,
read back from the installed package's metadata), so there is one place that states them; a
slow test installs exactly those minimums in a fresh virtual environment and runs the main job
(tests/test_minimum_versions.py). Checked: `CHECKED`. Imports no stage of softhand.
"""

from __future__ import annotations

import functools
import re
from importlib import metadata

__all__ = ["CHECKED", "RequirementError", "check", "minimums"]

#: the libraries whose old versions fail in ways that name no version (an AttributeError, "No
#: module named 'rerun.chunk'"), so their version is checked when softhand is imported
CHECKED = ("numpy", "scipy", "mujoco", "rerun-sdk", "gymnasium")


class RequirementError(ImportError):
    """An installed library older than softhand's declared minimum."""


def _release(version: str) -> tuple[int, ...]:
    """The release numbers of a version string (``"2.0.0rc1"`` -> (2, 0, 0))."""
    m = re.match(r"\d+(\.\d+)*", version.strip())
    return tuple(int(p) for p in m.group(0).split(".")) if m else ()


@functools.lru_cache(maxsize=1)
def minimums() -> dict[str, str]:
    """Name -> the lowest version softhand declares (``>=``) for each of `CHECKED`; empty when
    softhand runs from a source tree that was not installed (no metadata to read)."""
    try:
        declared = metadata.requires("softhand") or []
    except metadata.PackageNotFoundError:
        return {}
    out = {}
    for line in declared:
        if ";" in line:  # an extra's requirement
            continue
        m = re.match(r"\s*([A-Za-z0-9_.-]+)\s*>=\s*([0-9][0-9A-Za-z.]*)", line)
        if m and m.group(1).lower() in CHECKED:
            out[m.group(1).lower()] = m.group(2)
    return out


def check(*names: str) -> None:
    """Raise `RequirementError` (one line: the library, the version installed, the minimum and
    the command that installs it) if an installed library of ``names`` is older than declared.

    Raises:
        RequirementError: an older version is installed.
    """
    need = minimums()
    for name in names:
        if name not in need:
            continue
        try:
            have = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue  # not installed: its import fails with its own clear message
        if _release(have) < _release(need[name]):
            raise RequirementError(f"{name} {have} is installed, and softhand needs "
                                   f"{name}>={need[name]}: pip install -U '{name}>={need[name]}'")
