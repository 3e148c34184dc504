"""Calibrate many skins at once (one process per skin), write them, and summarise.

``index.json`` next to the skin files holds the per-skin errors, the lifelike ranking of the
laws (Fig. 8) and how the set was produced.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from softhand import __version__
from softhand.io import atomic_write_json
from softhand.skin.calibrate import SkinCalibration, calibrate_skin
from softhand.skin.files import FE_DIR, SHIPPED_DIR, save_calibration

__all__ = ["METRICS", "calibrate_many", "summary_table"]

METRICS = ("rms_error_pct_of_2N", "max_error_pct_of_2N", "mass_sensitivity_pct",
           "relaxation_error_pct", "step_us")
EXTRA = ("posture_sensitivity_pct",)


def _one(name: str, reps: tuple[str, ...], fe_dir: str) -> SkinCalibration:
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        return calibrate_skin(name, fe_dir=fe_dir, representations=reps)


def calibrate_many(names: list[str], representations: tuple[str, ...], *,
                   out_dir: str | Path | None = None, fe_dir: str | Path | None = None,
                   jobs: int | None = None, show_progress: bool = True) -> dict[str, Any]:
    """Calibrate ``names``, write one file each and ``index.json``; return the summary."""
    from tqdm import tqdm

    from softhand.fem.sweep import git_revision
    from softhand.laws.lifelike import lifelike_ranking

    out = Path(out_dir) if out_dir else SHIPPED_DIR
    fe = str(fe_dir) if fe_dir else str(FE_DIR)
    jobs = min(len(names), jobs or os.cpu_count() or 1)
    cals: dict[str, SkinCalibration] = {}
    bar = tqdm(total=len(names), desc="calibrate", unit="skin", disable=not show_progress)
    if jobs == 1:
        for n in names:
            bar.set_postfix_str(n)
            cals[n] = _one(n, representations, fe)
            bar.update()
    else:
        with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
            futures = {pool.submit(_one, n, representations, fe): n for n in names}
            for fut in as_completed(futures):
                cals[futures[fut]] = fut.result()
                bar.set_postfix_str(futures[fut])
                bar.update()
    bar.close()
    for n in names:
        save_calibration(cals[n], out)
    summary: dict[str, Any] = {
        "skins": {n: {r: {m: v.to_dict()[m] for m in METRICS + EXTRA if m in v.to_dict()}
                      for r, v in cals[n].representations.items()} for n in names},
        "laws": {n: {"fitted": [e.to_dict() for e in cals[n].law.fitted],
                     "validated": [e.to_dict() for e in cals[n].law.validated],
                     "prony": cals[n].law.prony.to_dict()} for n in names},
        "lifelike": [r.to_dict() for r in lifelike_ranking({n: c.law for n, c in cals.items()})],
        "provenance": {"softhand_version": __version__, "git_revision": git_revision(),
                       "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
                       "representations": list(representations)},
    }
    index = out / "index.json"
    atomic_write_json(index, _merge_index(index, summary))
    return summary


def _merge_index(path: Path, new: dict[str, Any]) -> dict[str, Any]:
    """Keep entries of skins not recalibrated this time (calibrating one skin keeps the others)."""
    import json

    if not path.exists():
        return new
    try:
        old = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError):
        return new
    for key in ("skins", "laws"):
        merged = dict(old.get(key, {}))
        merged.update(new[key])
        new[key] = merged
    return new


def summary_table(summary: dict[str, Any]) -> str:
    """Markdown table: skin, representation and the errors (None shown as blank)."""
    lines = ["| skin | representation | RMS % of 2 N | max % of 2 N | mass sens. % | "
             "hold error % | us/step |", "|---|---|---|---|---|---|---|"]
    for name, reps in summary["skins"].items():
        for rep, m in reps.items():
            cells = [("" if m[k] is None else f"{m[k]:.2f}") for k in METRICS]
            lines.append(f"| {name} | {rep} | " + " | ".join(cells) + " |")
    lines += ["", "Lifelike ranking (distance from the human middle phalanx at 1 N and 2 N):", "",
              "| rank | skin | d(1 N) mm | d(2 N) mm | distance % |", "|---|---|---|---|---|"]
    for i, r in enumerate(summary["lifelike"], 1):
        d1, d2 = r["displacement_mm"]
        lines.append(f"| {i} | {r['name']} | {d1:.2f} | {d2:.2f} | {r['distance_pct']:.1f} |")
    return "\n".join(lines)
