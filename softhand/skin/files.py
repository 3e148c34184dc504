"""Shipped skin calibration: one JSON file per skin in ``calibration/skins``, written atomically.

The hand and the handshake read these files (no FE run needed). Each file holds the law, every
calibrated representation with its errors, and provenance (FE curve hashes, MuJoCo and softhand
versions); ``index.json`` holds the summary table and the lifelike ranking.
"""

from __future__ import annotations

import hashlib
import tempfile
from pathlib import Path

from softhand.io import atomic_write_json, read_json
from softhand.paths import FE_DIR, SKINS_DIR, cache_dir
from softhand.skin.calibrate import SkinCalibration

__all__ = ["FE_DIR", "SKINS_DIR", "is_skin_path", "load_calibration", "save_calibration",
           "shipped_skins", "skin_file_folder"]



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


def is_skin_path(value: str) -> bool:
    """True when ``value`` names a calibration file (ends with ``.json`` or holds a path
    separator), not a skin name."""
    return value.endswith(".json") or "/" in value or "\\" in value


def skin_file_folder(path: str | Path, directory: str | Path = SKINS_DIR
                     ) -> tuple[str, Path]:
    """The skin of the calibration file at ``path`` (e.g. a searched design's, written by
    ``softhand design calibrate``) and a folder that holds it beside the skins of ``directory``
    (the partner's tissue and the other skins a scene may name): the handshake reads every law
    from one folder. The file is read and checked whole first (with a soft contact and a pair
    law, which the handshake needs). The folder is in softhand's cache (a temporary folder
    without one), keyed by the file's bytes, the other skins linked; the file in ``directory`` itself needs no copy.

    Raises:
        ValueError: a missing or unreadable file, not a calibration, a bad value, no pair law,
            or a skin name of ``directory`` with other contents (it would shadow that skin).
    """
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"{path}: no such file (expected a skin calibration file, *.json)")
    raw = p.read_bytes()
    data = read_json(p, name=f"{path}: not a readable calibration file")
    if not isinstance(data, dict):
        raise ValueError(f"{path}: not a calibration file (top level is {type(data).__name__}, "
                         "expected an object)")
    cal = SkinCalibration.from_dict(data, source=str(path), require=("soft-contact",))
    if cal.pair_law is None:
        raise ValueError(f"{path}: skin {cal.design}: no pair_law (the law against human "
                         "tissue that the handshake needs)")
    name, home = cal.design, Path(directory)
    shipped = home / f"{name}.json"
    if shipped.is_file():
        if shipped.resolve() == p.resolve():
            return name, home
        if shipped.read_bytes() != raw:
            raise ValueError(f"{path}: its skin {name!r} is a skin of {home} with other "
                             "contents; give the file's skin another design name")
        return name, home
    base = cache_dir()
    key = hashlib.sha256(raw).hexdigest()[:16]
    folder = (base / "skin-files" / key) if base is not None else Path(
        tempfile.mkdtemp(prefix="softhand-skin-"))
    folder.mkdir(parents=True, exist_ok=True)
    for other in home.glob("*.json"):  # linked: the folder reads the skins as they are now
        link = folder / other.name
        if not link.exists() and other.name != f"{name}.json":
            link.unlink(missing_ok=True)  # a link to a file that is gone
            link.symlink_to(other.resolve())
    if not (folder / f"{name}.json").is_file():
        tmp = folder / f".{name}.json.tmp"
        tmp.write_bytes(raw)
        tmp.replace(folder / f"{name}.json")  # last: its presence marks a complete folder
    return name, folder
