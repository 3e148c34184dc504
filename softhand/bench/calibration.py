"""Benchmark of the MuJoCo representations: error against FE and cost per step, in one run.

For each shipped skin and each representation, the rig (timestep 1 ms, calibration mass) replays
the skin's 0.5 mm/s ramp-and-hold FE record; the error is measured against that record and the cost
is the time spent in ``mj_step`` per step (best of three replays), divided by the cost of ``rigid``
in the same run. Writes ``bench-calibration.{md,json,png}``; timings are reported, never asserted.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from softhand.bench.common import machine_info, machine_line
from softhand.io import atomic_open, atomic_write_json, atomic_write_text
from softhand.paths import REPORTS_DIR
from softhand.skin.calibrate import (
    CALIBRATION_MASS_KG,
    fe_curves,
    hold_error,
    law_curve,
    loading_error,
)
from softhand.skin.files import FE_DIR, SKINS_DIR, load_calibration, shipped_skins
from softhand.skin.rig import RigSettings, build_rig, run_rig

__all__ = ["run_calibration_benchmark"]

REPEATS = 3


def _record(name: str, cal):
    try:
        return fe_curves(name, FE_DIR)[0][0]
    except FileNotFoundError:
        return law_curve(cal.law)


def run_calibration_benchmark(out_dir: str | Path = REPORTS_DIR, *, skins: list[str] | None = None,
                              skin_dir: str | Path = SKINS_DIR,
                              progress: Callable[[str], None] | None = None) -> str:
    """Run the benchmark, write the report files, return the Markdown; ``progress`` gets a line
    before each skin and representation."""
    say = progress or (lambda line: None)
    names = skins or shipped_skins(skin_dir)
    if not names:
        raise ValueError(f"no calibrated skins in {skin_dir}: run `softhand calibrate` first")
    settings = RigSettings(mass_kg=CALIBRATION_MASS_KG)
    rows: dict[str, dict[str, Any]] = {}
    for i, name in enumerate(names, 1):
        cal = load_calibration(name, skin_dir)
        curve = _record(name, cal)
        row: dict[str, Any] = {}
        for rep in cal.representations:
            say(f"skin {name} ({i} of {len(names)}), {rep}")
            if rep == "flex":
                row[rep] = _flex_row(cal.representations[rep].params, curve)
                continue
            model = build_rig(rep, cal.params(rep), settings=settings)
            outs = [run_rig(model, curve.time_s, curve.displacement_mm, settings=settings)
                    for _ in range(REPEATS)]
            best = min(outs, key=lambda o: o.stats["step_us"])
            rms, mx = loading_error(best, curve)
            row[rep] = {"rms_pct": rms, "max_pct": mx, "hold_pct": hold_error(best, curve),
                        "step_us": best.stats["step_us"], "nv": int(model.nv)}
        base = row.get("rigid", {}).get("step_us")
        for r in row.values():
            r["cost_vs_rigid"] = None if not base else r["step_us"] / base
        rows[name] = row
    data = {"machine": machine_info(),
            "rig": {"timestep_s": settings.timestep, "mass_kg": settings.mass_kg},
            "skins": rows, "by_representation": _aggregate(rows)}
    out = Path(out_dir)
    atomic_write_json(out / "bench-calibration.json", data)
    md = _markdown(data)
    atomic_write_text(out / "bench-calibration.md", md)
    _plot(data, out / "bench-calibration.png")
    return md


def _flex_row(params: dict[str, Any], curve) -> dict[str, Any]:
    """Replay the flex pad's 0.5 mm/s ramp (it has no hold: SVK has no memory)."""
    from softhand.skin.flex import FlexPadParams, simulate_flex_indentation

    i = curve.peak_index
    d, f = curve.displacement_mm[:i + 1], curve.force_N[:i + 1]
    sim = simulate_flex_indentation(FlexPadParams(**params), speed_mm_s=curve.speed_mm_s,
                                    depth_mm=float(d[-1]))
    err = sim.force_at(d) - f
    return {"rms_pct": float(100 * np.sqrt(np.mean(err**2)) / 2),
            "max_pct": float(100 * np.abs(err).max() / 2), "hold_pct": None,
            "step_us": 1e6 * sim.stats["step_wall_s"] / sim.stats["steps"]}


def _aggregate(rows: dict[str, dict[str, Any]]) -> dict[str, Any]:
    reps: dict[str, list[dict[str, Any]]] = {}
    for row in rows.values():
        for rep, r in row.items():
            reps.setdefault(rep, []).append(r)
    def stat(rs: list[dict[str, Any]], key: str, fn) -> float | None:
        vals = [r[key] for r in rs if r.get(key) is not None and np.isfinite(r[key])]
        return float(fn(vals)) if vals else None

    return {rep: {"worst_rms_pct": stat(rs, "rms_pct", np.max),
                  "median_rms_pct": stat(rs, "rms_pct", np.median),
                  "worst_hold_pct": stat(rs, "hold_pct", np.max),
                  "median_cost_vs_rigid": stat(rs, "cost_vs_rigid", np.median),
                  "median_step_us": stat(rs, "step_us", np.median), "skins": len(rs)}
            for rep, rs in reps.items()}


def _fmt(v, spec=".2f") -> str:
    return "" if v is None else format(v, spec)


def _markdown(d: dict[str, Any]) -> str:
    m = d["machine"]
    lines = ["# MuJoCo skin representations (`softhand bench calibration`)", "",
             f"{machine_line(m)} Rig: timestep {d['rig']['timestep_s'] * 1e3:g} ms, mass "
             f"{d['rig']['mass_kg']} kg; errors against the 0.5 mm/s FE ramp-and-hold.", "",
             "| representation | worst RMS % of 2 N | median RMS % | worst hold error % | "
             "cost / rigid (median) | us per step |", "|---|---|---|---|---|---|"]
    for rep, a in d["by_representation"].items():
        lines.append(f"| {rep} | {_fmt(a['worst_rms_pct'])} | {_fmt(a['median_rms_pct'])} | "
                     f"{_fmt(a['worst_hold_pct'])} | {_fmt(a['median_cost_vs_rigid'])} | "
                     f"{_fmt(a['median_step_us'], '.1f')} |")
    lines += ["", "| skin | representation | RMS % of 2 N | max % | hold error % | cost / rigid |",
              "|---|---|---|---|---|---|"]
    for name, row in d["skins"].items():
        for rep, r in row.items():
            lines.append(f"| {name} | {rep} | {_fmt(r['rms_pct'])} | {_fmt(r['max_pct'])} | "
                         f"{_fmt(r['hold_pct'])} | {_fmt(r['cost_vs_rigid'])} |")
    return "\n".join(lines) + "\n"


def _plot(d: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    for rep in d["by_representation"]:
        pts = [(r["cost_vs_rigid"], r["rms_pct"]) for row in d["skins"].values()
               for k, r in row.items() if k == rep and r.get("cost_vs_rigid") and r["rms_pct"]]
        if pts:
            x, y = zip(*pts, strict=True)
            ax.scatter(x, y, label=rep, s=25)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("cost per step / rigid contact")
    ax.set_ylabel("loading error, RMS % of 2 N")
    ax.set_title("Speed against error, one point per skin")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    fig.tight_layout()
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110)
    plt.close(fig)
