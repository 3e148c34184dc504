"""``softhand sensors calibrate``: FE sensor records of the 12 designs and their transfer laws.

Folder layout (``calibration/sensors`` by default):

    fe/{design}.csv            time_s, force_N (plate), hold, {sensor}_N per patch: 0.5 mm/s
    fe/speed-2/{design}.csv    the same at 2 mm/s (validation)
    fe/summary.json            provenance (git revision, solver version, settings), per design
                               the patches' placements and areas, and sha256 of each record
    transfer.json              per design and placement the transfer law
                               (TransferLaw) with its errors,
                               and the provenance of the records it was fitted to

The FE runs are the shipped skin curves' protocol (`FE_SETTINGS`)
with the default 4 x 4 mm patches (`softhand.fem.sensors.default_patches`).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import asdict, replace
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from softhand import __version__
from softhand.fem.solver import SOLVER_VERSION
from softhand.fem.sweep import git_revision, run_sweep
from softhand.io import atomic_write_json, atomic_write_text
from softhand.sensors.transfer import (
    FE_SETTINGS,
    SPEEDS_MM_S,
    SensorRecord,
    TransferLaw,
    fit_transfer,
    load_records,
    record_from_result,
    records_csv,
)

__all__ = ["fit_all", "load_transfer_laws", "run_sensor_fe", "speed_dir"]


def speed_dir(root: str | Path, speed_mm_s: float) -> Path:
    """``fe`` for the fitted speed, ``fe/speed-{v}`` for the others."""
    base = Path(root) / "fe"
    return base if speed_mm_s == SPEEDS_MM_S[0] else base / f"speed-{speed_mm_s:g}"


def run_sensor_fe(designs: list[str], out_dir: str | Path, *, threads: int | None = None,
                  cluster: str | None = None, show_progress: bool = True,
                  progress: Callable[[str], None] | None = None
                  ) -> tuple[dict[str, Any], list[str], bool]:
    """Run the FE records of ``designs`` at every speed and write them (each file atomically).

    ``threads`` and ``cluster`` are `softhand.fem.sweep.run_sweep`'s; ``progress`` gets a
    line before each speed's sweep (whose bar, with ``show_progress``, counts the designs).

    Returns:
        (the summary written, the designs x speeds that did not finish: interrupted or failed,
        whether Ctrl-C stopped it).
    """
    say = progress or (lambda line: None)
    out = Path(out_dir)
    summary_path = out / "fe" / "summary.json"
    try:
        summary = json.loads(summary_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        summary = {"designs": {}}
    summary["provenance"] = {
        "softhand_version": __version__, "solver_version": SOLVER_VERSION,
        "git_revision": git_revision(),
        "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "settings": json.loads(json.dumps(asdict(FE_SETTINGS), default=str)),
        "speeds_mm_s": list(SPEEDS_MM_S)}
    missing: list[str] = []
    for i, speed in enumerate(SPEEDS_MM_S, 1):
        say(f"FE records at {speed:g} mm/s ({i} of {len(SPEEDS_MM_S)} speeds)")
        batch = run_sweep(designs, replace(FE_SETTINGS, speed_mm_s=speed), threads=threads,
                          cluster=cluster, show_progress=show_progress)
        for name, r in batch.results.items():
            rec = record_from_result(r)
            text = records_csv(rec)
            atomic_write_text(speed_dir(out, speed) / f"{name}.csv", text)
            entry = summary["designs"].setdefault(name, {})
            entry.update({"placements": rec.placements, "area_mm2": rec.area_mm2})
            entry.setdefault("sha256", {})[f"{speed:g}"] = hashlib.sha256(text.encode()).hexdigest()
            entry.setdefault("wall_s", {})[f"{speed:g}"] = r.wall_s
        missing += [f"{n}@{speed:g}mm/s" for n in [*batch.missing, *batch.errors]]
        atomic_write_json(summary_path, summary)
        if batch.interrupted:
            rest = SPEEDS_MM_S[SPEEDS_MM_S.index(speed) + 1:]
            missing += [f"{n}@{v:g}mm/s" for v in rest for n in designs]
            return summary, missing, True
    return summary, missing, False


def read_records(root: str | Path, design: str) -> tuple[list[SensorRecord], list[SensorRecord]]:
    """(fitted, validation) records of one design from ``root/fe``."""
    summary = json.loads((Path(root) / "fe" / "summary.json").read_text(encoding="utf-8"))
    meta = summary["designs"].get(design)
    if meta is None:
        raise ValueError(f"{Path(root) / 'fe' / 'summary.json'}: no records of {design}")
    recs = [load_records(speed_dir(root, v), design, v, meta) for v in SPEEDS_MM_S
            if (speed_dir(root, v) / f"{design}.csv").is_file()]
    if not recs or recs[0].speed_mm_s != SPEEDS_MM_S[0]:
        raise ValueError(f"{speed_dir(root, SPEEDS_MM_S[0]) / (design + '.csv')}: missing")
    return recs[:1], recs[1:]


def fit_all(designs: list[str], root: str | Path, *,
            progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Fit every design's transfer laws from ``root/fe`` and write ``root/transfer.json``;
    ``progress`` gets a line before each design."""
    say = progress or (lambda line: None)
    root = Path(root)
    fe_summary = json.loads((root / "fe" / "summary.json").read_text(encoding="utf-8"))
    try:  # a subset refits those designs and keeps the others
        old = json.loads((root / "transfer.json").read_text(encoding="utf-8"))
        laws = dict(old["laws"])
        sha = dict(old["provenance"]["fe_sha256"])
    except (OSError, ValueError, KeyError, TypeError):
        laws, sha = {}, {}
    sha.update({d: fe_summary["designs"][d].get("sha256") for d in designs})
    for i, design in enumerate(designs, 1):
        say(f"transfer laws of {design} ({i} of {len(designs)})")
        fit, val = read_records(root, design)
        laws[design] = {name: fit_transfer(name, fit, val).to_dict()
                        for name in fit[0].readings_N}
    data = {"provenance": {"softhand_version": __version__, "git_revision": git_revision(),
                           "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
                           "fe_records": fe_summary["provenance"],
                           "fe_sha256": sha,
                           "law": "softhand.sensors.transfer.TransferLaw"},
            "laws": dict(sorted(laws.items()))}
    atomic_write_json(root / "transfer.json", data)
    return data


def load_transfer_laws(path: str | Path) -> dict[tuple[str, str], TransferLaw]:
    """Every law of a ``transfer.json``, keyed (design, placement); ValueError names the key."""
    from softhand.io import read_json

    p = Path(path)
    data = read_json(p)
    from softhand.validate import check_mapping

    try:
        check_mapping("", data, required=("provenance", "laws"))
        check_mapping("laws", data["laws"], optional=None)
    except ValueError as exc:
        raise ValueError(f"{p}: {exc}") from None
    out = {}
    for design, per in data["laws"].items():
        if not isinstance(per, dict):
            raise ValueError(f"{p}: laws.{design}: expected an object of placements")
        for name, d in per.items():
            try:
                law = TransferLaw.from_dict(d, key=f"laws.{design}.{name}")
            except ValueError as exc:
                raise ValueError(f"{p}: {exc}") from None
            out[(law.design, law.placement)] = law
    return out
