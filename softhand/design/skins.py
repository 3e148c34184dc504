"""A calibrated skin of a searched design: its FE curves, then `softhand calibrate`'s own fit.

A winner of the design search is a phalanx defined by its variables and two library materials
(`softhand.design.space.Candidate`). It is calibrated the way the shipped designs are
(`softhand.skin.calibrate.calibrate_design`), from FE curves in the folders that calibration reads:

* ``{fe}/``: the plate at 0.5 mm/s, then a 10 s hold (the law's elastic part and relaxation);
* ``{fe}/speed-5``, ``{fe}/speed-2``: the same at 5 mm/s (fitted) and 2 mm/s (validation);
* ``{fe}/finger``, ``{fe}/palm-plate``, ``{fe}/palm-finger``: the contact classes' curves
  (`softhand.skin.contact_classes`), no hold. Not the palm border's (``border-finger``: the
  phalanx widened to 20 x 8 mm, where a searched pocket and roof need not fit): a winner's
  border pairs carry its palm/finger law (`softhand.envs.skins.pair_choices`).

Each is the shipped folders' 3D setting (`FE_SETTINGS`) with the candidate's geometry and its
library constants in the FE's material slots (`softhand.design.evaluate.fe_design`), written by
`softhand.fem.sweep.write_results` under the slot layout's design name (``pocket2-sil-pu``).

**The range.** The shipped curves run to 20 N. A soft winner's FE stops earlier: past about 4 mm of
plate travel, half the phalanx's height, Newton finds no equilibrium. Each folder then runs
again to `DEPTH_MARGIN` of the travel where the FE stopped (a depth limit, ``max_depth_mm``; the
three speeds share the 0.5 mm/s one), so its curve ends on an equilibrium. The law and the pair
law are then calibrated to the force that curve reaches, which the file records
(``provenance.design.calibrated_max_N``, and the pair law's ``calibrated_max_N``): the handshake
flags every contact beyond it, as it flags any law's range.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from softhand.design.evaluate import fe_design, fe_materials
from softhand.design.space import Candidate
from softhand.fem.library import library
from softhand.fem.solver import ConvergenceError, IndentationSettings, indent
from softhand.fem.sweep import read_summary, write_results
from softhand.paths import FE_DIR
from softhand.skin.calibrate import SkinCalibration, calibrate_design

__all__ = ["DEPTH_MARGIN", "FE_FOLDERS", "FE_SETTINGS", "calibrate_candidate", "fe_folders_match",
           "run_fe_folders", "skin_name"]

#: the shipped calibration's FE setting (calibration/fe/summary.json): 3D, default mesh, to 20 N
FE_SETTINGS = IndentationSettings(mode="3d", mesh="default", speed_mm_s=0.5, max_force_N=20.0,
                                  max_depth_mm=7.0, hold_s=10.0, threads=1)
#: per folder of calibration/fe, what differs from `FE_SETTINGS`
FE_FOLDERS: dict[str, dict[str, Any]] = {
    ".": {},
    "speed-5": {"speed_mm_s": 5.0},
    "speed-2": {"speed_mm_s": 2.0},
    "finger": {"hold_s": 0.0, "indenter": "cylinder:9@90"},
    "palm-plate": {"hold_s": 0.0, "body": "palm"},
    "palm-finger": {"hold_s": 0.0, "indenter": "cylinder:9@90", "body": "palm"},
}
#: a folder whose FE stops runs again to this fraction of the travel where it stopped
DEPTH_MARGIN = 0.95
_SPEEDS = (".", "speed-5", "speed-2")


def _stopped_at(exc: ConvergenceError) -> float:
    """The plate travel (mm) at which a run found no equilibrium."""
    d = exc.diagnostics.get("displacement_mm") if exc.diagnostics else None
    return float(d)


def _run(design, settings: IndentationSettings, depth_mm: float | None, log: dict):
    """One folder's run, to ``depth_mm`` if given, else to 20 N or to `DEPTH_MARGIN` of where the
    FE stops; its record goes into ``log``."""
    s = settings if depth_mm is None else replace(settings, max_depth_mm=depth_mm)
    t0 = time.perf_counter()
    try:
        r = indent(design, s)
    except ConvergenceError as exc:
        if depth_mm is not None:
            raise
        stop = _stopped_at(exc)
        log["stopped"] = {"travel_mm": stop,
                          "force_N": float(exc.diagnostics.get("force_N", math.nan)),
                          "error": str(exc)[:200]}
        depth_mm = math.floor(DEPTH_MARGIN * stop * 100.0) / 100.0
        s = replace(settings, max_depth_mm=depth_mm)
        r = indent(design, s)
    log.update({"max_depth_mm": s.max_depth_mm, "reached_N": float(r.force_N.max()),
                "travel_mm": float(r.displacement_mm.max()), "status": r.status.value,
                "wall_s": time.perf_counter() - t0})
    return r


def run_fe_folders(candidate: Candidate, out_dir: str | Path, *,
                   folders: tuple[str, ...] = tuple(FE_FOLDERS),
                   progress=None) -> dict[str, Any]:
    """Run ``candidate``'s FE folders (module docstring) into ``out_dir``; return a record per
    folder (the depth limit, the force and travel reached, where the FE stopped, wall time) or
    the error of a folder that failed (a class folder that fails is left out: its class keeps
    the plate law in the handshake)."""
    candidate.check()
    out = Path(out_dir)
    design, base = fe_design(candidate, FE_SETTINGS)
    record: dict[str, Any] = {"design": design.name, "materials": fe_materials(candidate)}
    plate_depth: float | None = None
    for sub in folders:
        settings = replace(base, **FE_FOLDERS[sub])
        log: dict[str, Any] = {}
        if progress:
            progress(f"{sub}: {settings.indenter} on {settings.body}, {settings.speed_mm_s} mm/s")
        try:
            r = _run(design, settings, plate_depth if sub in _SPEEDS[1:] else None, log)
        except (ConvergenceError, ValueError) as exc:
            record[sub] = {**log, "error": str(exc)}
            if sub == ".":
                raise
            continue
        if sub == "." and "stopped" in log:
            plate_depth = log["max_depth_mm"]
        (out / sub).mkdir(parents=True, exist_ok=True)
        write_results({design.name: r}, out / sub, plot=False)
        record[sub] = log
        if progress:
            progress(f"{sub}: {log}")
    return record


def fe_folders_match(candidate: Candidate, fe_dir: str | Path) -> bool:
    """True when ``fe_dir``'s three plate folders hold ``candidate``'s curves (their summaries
    record its geometry and materials in `FE_SETTINGS`' setting), so that they can be reused."""
    import json

    design, base = fe_design(candidate, FE_SETTINGS)
    want = json.loads(json.dumps({"geometry": base.geometry, "materials": base.materials}))
    for sub in _SPEEDS:
        summary = read_summary(Path(fe_dir) / sub)
        if summary is None or design.name not in summary["designs"]:
            return False
        got = summary["provenance"]["settings"]
        if {k: got.get(k) for k in want} != want or got.get("mode") != FE_SETTINGS.mode:
            return False
    return True


def skin_name(trial: int) -> str:
    """The skin name of a search's trial (its calibration file is ``{name}.json``)."""
    return f"design-trial{int(trial)}"


def calibrate_candidate(candidate: Candidate, name: str, fe_dir: str | Path, *,
                        provenance: dict[str, Any] | None = None,
                        tissue_fe_dir: str | Path = FE_DIR) -> SkinCalibration:
    """``candidate``'s skin, calibrated from the folders `run_fe_folders` wrote into ``fe_dir``
    by `softhand.skin.calibrate.calibrate_design` (the shipped designs' path: law, rigid,
    soft contact, relaxation pad, the pair law against human tissue, the laws per contact class
    whose folder is there). The tissue's class laws come from ``tissue_fe_dir``'s tissue FE
    curves (`softhand.skin.contact_classes.TISSUE_FE_FOLDER`, shipped in calibration/fe).

    The provenance gains ``design``: the variables, the library materials (names, constants,
    sources), the FE folders' depth limits and reach, ``fe_max_N`` (the largest force of the
    0.5 mm/s curve), ``calibrated_max_N`` (the plate pair law's range: that force, or just
    under what the fitted law's ramp reaches where that is less) and the caller's
    ``provenance`` (search seed, trial, command).

    Raises:
        FileNotFoundError, ValueError: as `calibrate_design`, for missing or mixed curves.
    """
    design, _ = fe_design(candidate, FE_SETTINGS)
    root = Path(fe_dir)
    cal = calibrate_design(name, fe_dir=root, fe_design=design.name,
                           tissue_fe_dir=tissue_fe_dir)
    lib = library()
    folders = {}
    for sub in FE_FOLDERS:
        summary = read_summary(root / sub)
        if summary is None:
            continue
        row = summary["designs"].get(design.name, {})
        folders[sub] = {"max_depth_mm": summary["provenance"]["settings"]["max_depth_mm"],
                        "peak_force_N": row.get("peak_force_N"), "status": row.get("status")}
    fe_top = float(_plate_curve(root, design.name).force_N.max())
    # the law's range: the pair law's (the curve's end, or just under what the law's ramp
    # reaches where it ends flat: softhand.skin.calibrate._law_top)
    top = cal.pair_law.calibrated_max_N if cal.pair_law is not None else fe_top
    info = {
        "variables": candidate.to_dict(),
        "label": candidate.label,
        "materials": {layer: {"name": m, "sources": lib[m].sources,
                              "constants": fe_materials(candidate)[slot]}
                      for layer, m, slot in (("inner", candidate.inner, "sil"),
                                             ("outer", candidate.outer,
                                              "sil" if candidate.inner == candidate.outer
                                              else "pu"))},
        "fe_design": design.name,
        "fe_folders": folders,
        "fe_max_N": fe_top,
        "calibrated_max_N": top,
        "range_note": (f"the FE of this design stops short of 20 N; its law and pair law are "
                       f"calibrated to {top:.3g} N (its 0.5 mm/s curve ends at {fe_top:.3g} "
                       "N), and the handshake flags contacts beyond the pair law's "
                       "calibrated_max_N")
        if top < FE_SETTINGS.max_force_N * 0.99 else None,
        **(provenance or {}),
    }
    return replace(cal, provenance={**cal.provenance, "design": info})


def _plate_curve(root: Path, design: str):
    from softhand.laws.fit import load_curve

    return load_curve(root / f"{design}.csv", design)
