"""Run many designs, compare them with the paper, and write curves with provenance.

Output folder layout (``calibration/fe`` by default):

    {design}.csv        time_s, displacement_mm, force_N, hold (0 ramp / 1 hold)
    summary.json        per-design results, paper numbers, errors, settings and provenance
    curves.png          force-displacement curves against the paper's numbers (like Fig. 7)
"""

from __future__ import annotations

import csv
import hashlib
import io
import subprocess
from collections.abc import Iterable
from dataclasses import asdict, replace
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

from softhand import __version__
from softhand.fem.geometry import DESIGNS, parse_design
from softhand.fem.solver import SOLVER_VERSION, IndentationResult, IndentationSettings, indent
from softhand.io import atomic_open, atomic_write_json, atomic_write_text, read_json
from softhand.paper import paper
from softhand.parallel import BatchOutcome, check_threads, run_tasks

__all__ = ["compare_with_paper", "curve_csv", "folder_conflict", "git_revision", "read_summary",
           "run_sweep", "write_results"]


def git_revision() -> str:
    """The current git commit of the source tree (with ``+dirty``), or ``"unknown"``."""
    root = Path(__file__).resolve().parents[2]
    try:
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True,
                             text=True, timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=root, capture_output=True, text=True, timeout=10).stdout
        return rev + ("+dirty" if dirty.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def curve_csv(result: IndentationResult) -> str:
    """The curve of one run as CSV text."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["time_s", "displacement_mm", "force_N", "hold"])
    for t, d, f, h in zip(result.time_s, result.displacement_mm, result.force_N, result.hold,
                          strict=True):
        w.writerow([f"{t:.6g}", f"{d:.8g}", f"{f:.8g}", int(h)])
    return buf.getvalue()


def compare_with_paper(summaries: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Per-design errors against the paper, and the layered-design changes."""
    P = paper()
    rows: dict[str, Any] = {}
    for name, s in summaries.items():
        row: dict[str, Any] = {}
        ref = P["displacement_at_2N_mm"].get(name)
        got = s.get("displacement_at_2N_mm")
        if ref is not None and got is not None:
            row["displacement_at_2N"] = {"paper": ref, "softhand": got,
                                         "error_pct": 100 * (got - ref) / ref}
        ref = P["force_at_2mm_N"].get(name)
        got = s.get("force_at_2mm_N")
        if ref is not None and got is not None:
            row["force_at_2mm"] = {"paper": ref, "softhand": got,
                                   "error_pct": 100 * (got - ref) / ref}
        ref = P["rising_slope_mm_per_N"].get(name)
        got = s.get("rising_slope_mm_per_N")
        if ref is not None and got is not None:
            row["rising_slope"] = {"paper": ref, "softhand": got,
                                   "error_pct": 100 * (got - ref) / ref}
        d = parse_design(name)
        homog = f"{d.topology}-{d.inner}"
        if not d.homogeneous and homog in summaries:
            base = summaries[homog].get("displacement_at_2N_mm")
            if base and s.get("displacement_at_2N_mm") is not None:
                change = 100 * (s["displacement_at_2N_mm"] - base) / base
                layered = {"softhand_pct": change}
                paper_change = P["layered_change_pct"].get(name)
                if paper_change is not None:
                    layered["paper_pct"] = paper_change
                    layered["difference_pp"] = change - paper_change
                else:
                    layered["paper_within_abs_pct"] = P["layered_change_pct"]["others_within_abs"]
                row["layered_change"] = layered
        rows[name] = row
    return rows


def run_sweep(designs: Iterable[str] = DESIGNS, settings: IndentationSettings | None = None,
              *, show_progress: bool = True, threads: int | None = None,
              cluster: str | None = None) -> BatchOutcome:
    """Indent every design with the same settings; a progress bar counts designs.

    Args:
        threads: cores to use (None: `softhand.parallel.default_threads`): that many
            designs at once, one single-threaded worker process each; for a single design (or
            ``threads=1``) it runs in this process with ``threads`` element threads. The results
            do not depend on it.
        cluster: a Dask scheduler's address (``tcp://HOST:PORT``): the designs run on its
            workers, one single-threaded task each, whatever their number; not with ``threads``
            (`softhand.parallel.run_tasks`). The results are those of a local run.

    Returns:
        The batch outcome: finished results in ``designs`` order, failed designs (their
        `ConvergenceError` text) and, after Ctrl-C, the designs that did not finish.

    Raises:
        ValueError: an unknown design, ``threads`` with ``cluster``, or a cluster that is
            malformed or not answering (before any run).
    """
    from tqdm import tqdm

    designs = [parse_design(d).name for d in designs]  # validate all names first
    settings = settings or IndentationSettings()
    if cluster is None:
        jobs: int | None = min(len(designs), check_threads(threads))
        # one design at a time: its element threads use the cores; else one thread per design
        each = replace(settings, threads=check_threads(threads) if jobs == 1 else 1)
    else:
        jobs, each = threads, replace(settings, threads=1)  # run_tasks refuses threads here
    bar = tqdm(total=len(designs), desc="fe sweep", unit="design", disable=not show_progress)

    def done(name, ok: bool) -> None:
        bar.set_postfix_str(name if ok else f"{name} failed")
        bar.update()

    # slowest first (pocket designs take longest) so that the workers finish together
    order = sorted(designs, key=lambda n: parse_design(n).topology != "pocket2")
    tasks = [(name, (name, each)) for name in order]
    try:
        out = run_tasks(indent, tasks, threads=jobs, cluster=cluster, on_done=done)
    finally:
        bar.close()
    results = {name: replace(out.results[name], settings=settings)
               for name in designs if name in out.results}
    return replace(out, results=results, missing=[n for n in designs if n in out.missing])


def read_summary(folder: str | Path) -> dict[str, Any] | None:
    """The ``summary.json`` of an FE folder, checked; None when the folder has none.

    Raises:
        ValueError: naming the file, when it is not JSON or not a summary that
            `write_results` wrote (no provenance settings, designs or curve hashes).
    """
    path = Path(folder) / "summary.json"
    if not path.exists():
        return None
    data = read_json(path)
    try:
        ok = (isinstance(data["provenance"]["settings"], dict)
              and isinstance(data["provenance"]["curve_sha256"], dict)
              and isinstance(data["designs"], dict))
    except (KeyError, TypeError):
        ok = False
    if not ok:
        raise ValueError(f"{path}: not an FE summary written by `softhand fe sweep` (expected "
                         "provenance.settings, provenance.curve_sha256 and designs)")
    return data


def _body_geometry(body: str) -> dict[str, Any]:
    """The geometry of a body other than the phalanx (its defaults: the FE runs it)."""
    from softhand.fem.palm import PalmGeometry

    return asdict(PalmGeometry()) if body == "palm" else {}


def _settings_of(settings: IndentationSettings | dict[str, Any]) -> dict[str, Any]:
    """The settings that make a curve what it is (threads, the engine and the solver do not),
    as JSON values."""
    import json

    data = settings if isinstance(settings, dict) else asdict(settings)
    # folders written before indenters, bodies and the pocket contact's choice hold plate
    # curves on the phalanx with the paired pocket
    data = {"indenter": "plate", "body": "phalanx", "pocket_contact": "paired", **data}
    return {k: v for k, v in json.loads(json.dumps(data, default=str)).items()
            if k not in ("threads", "engine", "solver")}


def folder_conflict(summary: dict[str, Any] | None, settings: IndentationSettings,
                    designs: Iterable[str]) -> str | None:
    """Why writing ``designs`` run with ``settings`` into the folder of ``summary`` would mix two
    sets of curves (None: it would not).

    A folder holds curves of one setting (2D or 3D, mesh, speed, force, hold, materials...):
    adding designs with other settings is refused, naming each difference; replacing every
    design the folder holds is not a mix.
    """
    if summary is None:
        return None
    old, new = _settings_of(summary["provenance"]["settings"]), _settings_of(settings)
    diff = [f"{k} {old[k]!r} (the folder) vs {new[k]!r} (this run)" for k in sorted(new)
            if k in old and old[k] != new[k]]
    if not diff or set(summary["designs"]) <= set(designs):
        return None
    return "; ".join(diff)


def write_results(results: dict[str, IndentationResult], out_dir: str | Path,
                  *, plot: bool = True, missing: dict[str, str] | None = None) -> dict[str, Any]:
    """Write curves, the summary with provenance and the plot into ``out_dir`` (atomically).

    A folder that already holds curves of the same settings is extended: its other designs stay
    in the summary (their curves are not touched) and the plot shows every design; a folder of
    other settings is refused (`folder_conflict`) unless this run replaces all it holds.

    Args:
        results: the finished designs (at least one).
        plot: draw ``curves.png``; when False for an incomplete set (``missing``), an older
            ``curves.png`` is removed so that nothing in the folder disagrees with the summary.
        missing: designs asked for that have no result, with why (interrupted, failed); the
            summary lists those the folder has no curve of under ``missing``, with
            ``complete: false``.

    Raises:
        ValueError: a corrupt summary.json in ``out_dir``, or curves of other settings there.
    """
    if not results:
        raise ValueError("no finished design to write")
    out = Path(out_dir)
    first = next(iter(results.values()))
    old = read_summary(out)
    conflict = folder_conflict(old, first.settings, [*results, *(missing or {})])
    if conflict:
        raise ValueError(f"{out / 'summary.json'}: the folder holds curves of other settings "
                         f"({conflict}); write them into another folder")
    same = old is not None and (_settings_of(old["provenance"]["settings"])
                                == _settings_of(first.settings))
    keep = ({n: v for n, v in old["designs"].items()
             if n not in results and (out / f"{n}.csv").is_file()} if same else {})
    if old is not None and not same:  # a run of other settings replaces all the folder held
        for name in old["designs"]:
            if name not in results:
                (out / f"{name}.csv").unlink(missing_ok=True)
    summaries = {n: keep[n] for n in DESIGNS if n in keep}
    hashes = {n: old["provenance"]["curve_sha256"].get(n) for n in summaries}
    sizes = {n: old["provenance"].get("mesh_sizes", {}).get(n) for n in summaries}
    for name, r in results.items():
        text = curve_csv(r)
        atomic_write_text(out / f"{name}.csv", text)
        hashes[name] = hashlib.sha256(text.encode()).hexdigest()
        sizes[name] = {"n_elements": r.n_elements, "n_dofs": r.n_dofs}
        summaries[name] = {k: v for k, v in r.summary().items()
                           if k not in ("time_s", "displacement_mm", "force_N",
                                        "contact_area_mm2")}
    order = [n for n in DESIGNS if n in summaries]
    summaries = {n: summaries[n] for n in order}
    missing = {n: why for n, why in (missing or {}).items() if n not in summaries}
    settings = asdict(first.settings)
    summary = {
        "provenance": {
            "softhand_version": __version__,
            "solver_version": SOLVER_VERSION,
            "git_revision": git_revision(),
            "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            "settings": settings,
            "mesh_spec": asdict(first.settings.mesh_spec),
            "mesh_sizes": {n: sizes[n] for n in order},
            "curve_sha256": {n: hashes[n] for n in order},
            "paper": paper()["source"],
            **({"body_geometry": _body_geometry(first.settings.body)}
               if first.settings.body != "phalanx" else {}),
        },
        "complete": not missing,
        "missing": missing,
        "designs": summaries,
        "comparison": compare_with_paper(summaries),
        "total_wall_s": float(sum(v.get("wall_s", 0.0) for v in summaries.values())),
    }
    atomic_write_json(out / "summary.json", summary)
    if plot:
        curves = {n: results[n] if n in results else _curve_of(out / f"{n}.csv") for n in order}
        plot_curves(curves, out / "curves.png")
    elif missing or keep:  # no plot that would disagree with the summary
        (out / "curves.png").unlink(missing_ok=True)
    return summary


def _curve_of(path: Path):
    """A curve CSV as the arrays `plot_curves` draws."""
    from types import SimpleNamespace

    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return SimpleNamespace(time_s=data[:, 0], displacement_mm=data[:, 1], force_N=data[:, 2],
                           hold=data[:, 3] > 0.5)


def plot_curves(results: dict[str, IndentationResult], path: str | Path) -> None:
    """Force against displacement for every design, with the paper's points (like Fig. 7)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    P = paper()
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 5.5))
    colors = {"solid": "tab:blue", "pocket1": "tab:orange", "pocket2": "tab:green"}
    styles = {("sil", "sil"): "-", ("pu", "pu"): "--", ("sil", "pu"): "-.", ("pu", "sil"): ":"}
    for name, r in results.items():
        d = parse_design(name)
        ramp = ~r.hold
        lw = 2.2 if d.homogeneous else 1.1
        ax.plot(r.displacement_mm[ramp], r.force_N[ramp], styles[(d.inner, d.outer)],
                color=colors[d.topology], lw=lw, label=name)
        if r.hold.any():
            t0 = r.time_s[~r.hold][-1]
            ax2.plot(r.time_s[r.hold] - t0, r.force_N[r.hold] / r.force_N[~r.hold][-1],
                     styles[(d.inner, d.outer)], color=colors[d.topology], lw=lw, label=name)
    for name, v in P["displacement_at_2N_mm"].items():
        if name.startswith("_"):
            continue
        d = parse_design(name)
        ax.plot(v, 2.0, "o", color=colors[d.topology], mfc="white", ms=7)
    for name, v in P["force_at_2mm_N"].items():
        if name.startswith("_"):
            continue
        ax.plot(2.0, v, "s", color=colors["pocket2"], mfc="white", ms=7)
    ax.set_xlabel("plate displacement (mm)")
    ax.set_ylabel("force (N)")
    ax.set_title("Ramp at 0.5 mm/s (lines: softhand; o: paper at 2 N; s: paper at 2 mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    ax2.set_xlabel("hold time (s)")
    ax2.set_ylabel("force / force at end of ramp")
    ax2.set_title("Relaxation during the hold")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110)
    plt.close(fig)


def paper_error_table(summary: dict[str, Any]) -> str:
    """A Markdown table of softhand against the paper (used by the README and the CLI)."""
    lines = ["| design | paper d(2 N) mm | softhand d(2 N) mm | error | paper F(2 mm) N | "
             "softhand F(2 mm) N | error |", "|---|---|---|---|---|---|---|"]
    for name in summary["designs"]:
        s = summary["designs"][name]
        c = summary["comparison"].get(name, {})
        dp = c.get("displacement_at_2N", {})
        fp = c.get("force_at_2mm", {})
        d2 = s.get("displacement_at_2N_mm")
        f2 = s.get("force_at_2mm_N")
        lines.append(
            f"| {name} | {dp.get('paper', '')} | {'' if d2 is None else f'{d2:.3f}'} | "
            f"{_pct(dp.get('error_pct'))} | {fp.get('paper', '')} | "
            f"{'' if f2 is None or name.split('-')[0] != 'pocket2' else f'{f2:.3f}'} | "
            f"{_pct(fp.get('error_pct'))} |")
    return "\n".join(lines)


def _pct(v: float | None) -> str:
    return "" if v is None or not np.isfinite(v) else f"{v:+.1f} %"
