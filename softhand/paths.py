"""The default folders of every softhand command, defined once.

Every command that reads or writes calibration data or reports takes its default folder from here,
so ``softhand fe sweep`` writes where ``softhand calibrate`` reads, whatever the working directory:

=================  ==========================================  ============================
name               folder                                      written by / read by
=================  ==========================================  ============================
``FE_DIR``         ``calibration/fe`` (+ ``speed-5``, ``-2``)  ``fe sweep`` / ``calibrate``
``SKINS_DIR``      ``calibration/skins``                       ``calibrate`` / hands, envs
``REPORTS_DIR``    ``reports``                                 ``bench *``
=================  ==========================================  ============================

The folders are those of the source tree that holds the package (the repository). Folders under
``CALIBRATION_DIR`` hold shipped data: :func:`is_shipped` tells whether a path lies there, so that a
command can refuse to overwrite shipped data with an incomplete set unless told to (``--force``).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["CALIBRATION_DIR", "FE_DIR", "REPORTS_DIR", "REPO_ROOT", "SKINS_DIR", "is_shipped"]

REPO_ROOT = Path(__file__).resolve().parents[1]
CALIBRATION_DIR = REPO_ROOT / "calibration"
FE_DIR = CALIBRATION_DIR / "fe"
SKINS_DIR = CALIBRATION_DIR / "skins"
REPORTS_DIR = REPO_ROOT / "reports"


def is_shipped(path: str | os.PathLike) -> bool:
    """True when ``path`` is the shipped calibration folder or lies inside it."""
    target = Path(path).resolve()
    root = CALIBRATION_DIR.resolve()
    return target == root or root in target.parents
