"""The default folders of every softhand command, defined once.

Every command that reads or writes calibration data or reports takes its default folder from here,
so ``softhand fe sweep`` writes where ``softhand calibrate`` reads, whatever the working directory:

| name | folder | written by / read by |
|---|---|---|
| ``FE_DIR`` | ``calibration/fe`` (+ ``speed-5``, ``-2``) | ``fe sweep`` / ``calibrate`` |
| ``SKINS_DIR`` | ``calibration/skins`` | ``calibrate`` / hands, envs |
| ``SENSORS_DIR`` | ``calibration/sensors`` (+ ``fe``) | ``sensors calibrate`` / envs |
| ``REPORTS_DIR`` | ``reports`` | ``bench *`` |
| ``cache_dir()`` | ``~/.cache/softhand`` (``SOFTHAND_CACHE_DIR``) | solved grasps / hands |

The shipped data is the package ``softhand.calibration`` (``calibration/`` of the repository, read
through importlib.resources), so a regular (non-editable) install finds it as a checkout does.
Reports go to ``reports/`` of the checkout, or of the working directory for an installed wheel.
Folders under ``CALIBRATION_DIR`` hold shipped data: `is_shipped` tells whether a path lies there, so that a
command can refuse to overwrite shipped data with an incomplete set unless told to (``--force``).
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

__all__ = ["CACHE_ENV", "CALIBRATION_DIR", "FE_DIR", "IN_CHECKOUT", "REPORTS_DIR", "REPO_ROOT",
           "SENSORS_DIR", "SKINS_DIR", "cache_dir", "is_shipped"]

def _calibration_dir() -> Path:
    """The folder of the package ``softhand.calibration`` (``calibration/`` of a checkout)."""
    return Path(str(resources.files("softhand.calibration"))).resolve()


REPO_ROOT = Path(__file__).resolve().parents[1]
#: True when running from a source checkout (editable install or PYTHONPATH), not a wheel
IN_CHECKOUT = (REPO_ROOT / "pyproject.toml").is_file()
CALIBRATION_DIR = _calibration_dir()
FE_DIR = CALIBRATION_DIR / "fe"
SKINS_DIR = CALIBRATION_DIR / "skins"
SENSORS_DIR = CALIBRATION_DIR / "sensors"
REPORTS_DIR = REPO_ROOT / "reports" if IN_CHECKOUT else Path("reports")


#: Environment variable naming the folder of softhand's caches (solved grasps); ``off``: none.
CACHE_ENV = "SOFTHAND_CACHE_DIR"


def cache_dir() -> Path | None:
    """The folder of softhand's caches of derived results (never shipped data): ``$SOFTHAND_CACHE_DIR``,
    else ``$XDG_CACHE_HOME/softhand``, else ``~/.cache/softhand``; None when
    ``SOFTHAND_CACHE_DIR`` is ``off``. A cache entry is keyed by everything its result depends on,
    so a stale entry is never read; deleting the folder only costs the time to recompute."""
    value = os.environ.get(CACHE_ENV)
    if value is not None and value.strip().lower() == "off":
        return None
    if value:
        return Path(value).expanduser()
    base = os.environ.get("XDG_CACHE_HOME")
    if not base:
        try:
            base = str(Path.home() / ".cache")
        except RuntimeError:  # no home directory to find: no cache
            return None
    return Path(base).expanduser() / "softhand"


def is_shipped(path: str | os.PathLike) -> bool:
    """True when ``path`` is the shipped calibration folder or lies inside it."""
    target = Path(path).resolve()
    root = CALIBRATION_DIR.resolve()
    return target == root or root in target.parents
