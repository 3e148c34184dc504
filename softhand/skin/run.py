"""Calibrate many skins at once (one process per skin), write them, and summarise.

``index.json`` next to the skin files holds the per-skin errors, the lifelike ranking of the
laws (Fig. 8) and how the set was produced.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from softhand import __version__
from softhand.io import atomic_write_json, interrupts_deferred
from softhand.parallel import run_tasks
from softhand.skin.calibrate import SkinCalibration, calibrate_skin
from softhand.skin.files import FE_DIR, SKINS_DIR, save_calibration

__all__ = ["METRICS", "CalibrationRun", "calibrate_many", "refit_class_laws_many",
           "summary_table"]

METRICS = ("rms_error_pct_of_2N", "max_error_pct_of_2N", "mass_sensitivity_pct",
           "relaxation_error_pct", "step_us")
EXTRA = ("posture_sensitivity_pct",)


def _one(name: str, reps: tuple[str, ...], fe_dir: str) -> SkinCalibration:
    return calibrate_skin(name, fe_dir=fe_dir, representations=reps)


def calibrate_many(names: list[str], representations: tuple[str, ...], *,
                   out_dir: str | Path | None = None, fe_dir: str | Path | None = None,
                   threads: int | None = None, cluster: str | None = None,
                   show_progress: bool = True) -> CalibrationRun:
    """Calibrate ``names``, write one file each and ``index.json``; return what happened.

    Every skin that finished is written (atomically) even when others failed or Ctrl-C stopped
    the batch; ``index.json`` then summarises every file in the folder and lists the skins of this
    run that are missing.

    Args:
        threads: skins calibrated at once, one single-threaded worker process each (None:
            `softhand.parallel.default_threads`).
        cluster: a Dask scheduler's address (``tcp://HOST:PORT``): the skins are calibrated on
            its workers; not with ``threads`` (`softhand.parallel.run_tasks`).
    """
    out = Path(out_dir) if out_dir else SKINS_DIR
    fe = str(Path(fe_dir).resolve()) if fe_dir else str(FE_DIR)  # workers may have another cwd
    return _skin_batch("calibrate", _one, [(n, (n, representations, fe)) for n in names], out,
                       lambda cal: _merged(cal, out), representations, threads=threads,
                       cluster=cluster, show_progress=show_progress)


def refit_class_laws_many(names: list[str], *, out_dir: str | Path | None = None,
                          fe_dir: str | Path | None = None, threads: int | None = None,
                          cluster: str | None = None, show_progress: bool = True
                          ) -> CalibrationRun:
    """Fit the laws per contact class of the calibration files of ``names`` in ``out_dir``
    again from the class folders of ``fe_dir`` (`refit_class_laws`), keeping the rest of each
    file; write each file and ``index.json`` as `calibrate_many` does (what finished is
    written, also after Ctrl-C)."""
    out = Path(out_dir) if out_dir else SKINS_DIR
    fe = str(Path(fe_dir).resolve()) if fe_dir else str(FE_DIR)
    skins = str(out.resolve())
    return _skin_batch("class laws", _refit_one, [(n, (n, skins, fe)) for n in names], out,
                       lambda cal: cal, None, threads=threads, cluster=cluster,
                       show_progress=show_progress)


def _skin_batch(desc: str, work, tasks: list, out: Path, to_write, representations, *,
                threads: int | None, cluster: str | None, show_progress: bool
                ) -> CalibrationRun:
    """Run ``work`` over ``tasks`` (`run_tasks`) with a progress bar, then write each finished
    skin (``to_write(cal)``) and ``index.json`` together (Ctrl-C held until both are written)."""
    from tqdm import tqdm

    bar = tqdm(total=len(tasks), desc=desc, unit="skin", disable=not show_progress)

    def done(name, ok: bool) -> None:
        bar.set_postfix_str(name if ok else f"{name} failed")
        bar.update()

    try:
        batch = run_tasks(work, tasks, threads=threads, cluster=cluster, on_done=done)
    finally:
        bar.close()
    missing = {n: "interrupted" for n in batch.missing}
    missing.update({n: str(e) for n, e in batch.errors.items()})
    index = None
    with interrupts_deferred():  # the files and their index are written together
        for cal in batch.results.values():
            save_calibration(to_write(cal), out)
        if batch.results:
            index = rebuild_index(out, representations, missing=missing)
    return CalibrationRun(index, list(batch.results), missing, batch.interrupted)


def _refit_one(name: str, skins_dir: str, fe_dir: str):
    from softhand.skin.calibrate import refit_class_laws
    from softhand.skin.files import load_calibration

    return refit_class_laws(load_calibration(name, skins_dir), fe_dir)


@dataclass(frozen=True)
class CalibrationRun:
    """What `calibrate_many` did.

    Attributes:
        index: the rewritten ``index.json`` (None when no skin finished; nothing was written).
        written: skins written in this run.
        missing: skins asked for that were not written, with why ("interrupted" or the error).
        interrupted: True when Ctrl-C stopped the batch.
    """

    index: dict[str, Any] | None
    written: list[str]
    missing: dict[str, str]
    interrupted: bool


def rebuild_index(out: str | Path = SKINS_DIR,
                  representations: tuple[str, ...] | None = None, *,
                  missing: dict[str, str] | None = None) -> dict[str, Any]:
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
                       "last_representations": list(representations or ()),
                       "last_missing": dict(missing or {})},
    }
    atomic_write_json(out / "index.json", summary)
    return summary


def _merged(cal: SkinCalibration, out: Path) -> SkinCalibration:
    """Keep representations (and the pair law) of an existing file that were not recalibrated
    this time."""
    from softhand.skin.files import load_calibration

    try:
        old = load_calibration(cal.design, out)
    except ValueError:
        return cal
    reps = {k: v for k, v in old.representations.items() if k not in cal.representations}
    reps.update(cal.representations)
    pair = cal.pair_law if cal.pair_law is not None else old.pair_law
    classes = cal.pair_laws or old.pair_laws
    return SkinCalibration(cal.design, cal.law, reps, cal.provenance, pair, classes)


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
