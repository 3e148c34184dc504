"""Shipped skin calibration: one JSON file per skin in ``calibration/skins``, written atomically.

The hand and the handshake read these files (no FE run needed). Each file holds the law, every
calibrated representation with its errors, and provenance (FE curve hashes, MuJoCo and softhand
versions); ``index.json`` holds the summary table and the lifelike ranking.
"""

from __future__ import annotations

from pathlib import Path

from softhand.io import atomic_write_json, read_json
from softhand.paths import FE_DIR, SKINS_DIR
from softhand.skin.calibrate import SkinCalibration

__all__ = ["FE_DIR", "SKINS_DIR", "load_calibration", "save_calibration", "shipped_skins"]



def save_calibration(cal: SkinCalibration, out_dir: str | Path = SKINS_DIR) -> Path:
    """Write ``{design}.json`` atomically; return its path."""
    path = Path(out_dir) / f"{cal.design}.json"
    atomic_write_json(path, cal.to_dict())
    return path


def load_calibration(design: str, directory: str | Path = SKINS_DIR, *,
                     require: tuple[str, ...] = ()) -> SkinCalibration:
    """Read one skin's calibration, checking every value; clear errors for a bad file.

    Args:
        design: the skin (file ``{design}.json``).
        directory: folder of the calibration files.
        require: representations the caller needs (e.g. ``("soft-contact",)``).

    Raises:
        ValueError: a missing, unreadable, corrupt or foreign file, or a bad value:
            ``"{path}: skin {design}: {key path} = {value}: expected ..."``.
    """
    path = Path(directory) / f"{design}.json"
    if not path.exists():
        known = ", ".join(shipped_skins(directory)) or "none"
        raise ValueError(f"no calibration for skin {design!r} in {directory} (calibrated: {known});"
                         " run `softhand calibrate`")
    data = read_json(path, name=f"{path}: skin {design}: not a readable calibration file")
    if not isinstance(data, dict):
        raise ValueError(f"{path}: skin {design}: not a calibration file (top level is "
                         f"{type(data).__name__}, expected an object)")
    return SkinCalibration.from_dict(data, source=str(path), skin=design, require=require)


def shipped_skins(directory: str | Path = SKINS_DIR) -> list[str]:
    """Names of the skins calibrated in ``directory``."""
    d = Path(directory)
    return sorted(p.stem for p in d.glob("*.json") if p.stem != "index") if d.exists() else []
