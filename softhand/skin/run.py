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
        save_calibration(_merged(cals[n], out), out)
    return rebuild_index(out, representations)


def rebuild_index(out: str | Path = SHIPPED_DIR,
                  representations: tuple[str, ...] | None = None) -> dict[str, Any]:
    """Write ``index.json`` from every calibration file in ``out``; return it."""
    from softhand.fem.sweep import git_revision
    from softhand.laws.lifelike import lifelike_ranking
    from softhand.skin.files import load_calibration, shipped_skins

    out = Path(out)
    cals = {n: load_calibration(n, out) for n in shipped_skins(out)}
    summary: dict[str, Any] = {
        "skins": {n: {r: {m: v.to_dict()[m] for m in METRICS + EXTRA if m in v.to_dict()}
                      for r, v in c.representations.items()} for n, c in cals.items()},
        "laws": {n: {"fitted": [e.to_dict() for e in c.law.fitted],
                     "validated": [e.to_dict() for e in c.law.validated],
                     "prony": c.law.prony.to_dict()} for n, c in cals.items()},
        "lifelike": [r.to_dict() for r in lifelike_ranking({n: c.law for n, c in cals.items()})],
        "provenance": {"softhand_version": __version__, "git_revision": git_revision(),
                       "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
                       "last_representations": list(representations or ())},
    }
    atomic_write_json(out / "index.json", summary)
    return summary


def _merged(cal: SkinCalibration, out: Path) -> SkinCalibration:
    """Keep representations of an existing file that were not recalibrated this time."""
    from softhand.skin.files import load_calibration

    try:
        old = load_calibration(cal.design, out)
    except ValueError:
        return cal
    reps = {k: v for k, v in old.representations.items() if k not in cal.representations}
    reps.update(cal.representations)
    return SkinCalibration(cal.design, cal.law, reps, cal.provenance)


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
