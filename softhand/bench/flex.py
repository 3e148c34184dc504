"""A flex region on the hand against the flex rig and the FE (``softhand bench flex``).

For each design and posture (`softhand.hands.flex_region`, region Index3): the shipped flex
pad on the prosthetic index fingertip pressed at 0.5 mm/s to 2 N. Reported:

* the loading curve against the same pad on the rig's world-fixed base (RMS, % of 2 N): whether
  the calibration survives the articulated attachment and the posture;
* against the design's FE loading curve (RMS up to 2 N, % of 2 N): the flex calibration's own
  error, which the hand inherits;
* the contact area at 0.5, 1 and 2 N (the pad's lower and upper bounds,
  `softhand.skin.flex.ContactPatch`) against the FE's (contact Gauss points,
  `softhand.fem.solver.IndentationResult.contact_area_mm2`), and the peak pressure at the
  largest common force;
* the cost: ``mj_step`` wall time per step of the hand scene and of the rig, and their dofs.

A pad that softens before 2 N (the SVK flex of a pocketed design buckles under the plate) is
reported up to its peak. Written to ``reports/bench-flex.{json,md,png}``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from softhand.bench.common import machine_info, machine_line
from softhand.fem.solver import IndentationSettings, indent
from softhand.hands.flex_region import press_flex_region
from softhand.io import atomic_open, atomic_write_json, atomic_write_text
from softhand.laws.fit import REFERENCE_FORCE_N
from softhand.paths import FE_DIR, REPORTS_DIR
from softhand.skin.calibrate import fe_curves
from softhand.skin.files import load_calibration
from softhand.skin.flex import simulate_flex_indentation
from softhand.skin.representations import loading_ramp

__all__ = ["DESIGNS", "flex_row", "run_flex_bench"]

DESIGNS = ("solid-pu", "solid-sil", "pocket2-sil")
FORCES_N = (0.5, 1.0, 2.0)
REGION = "Index3"
SPEED_MM_S = 0.5


def _rms_pct(a: np.ndarray, b: np.ndarray) -> float:
    return float(100 * np.sqrt(np.mean((a - b) ** 2)) / REFERENCE_FORCE_N)


def flex_row(design: str, postures: tuple[str, ...] = ("extended", "flexed"),
             speed_mm_s: float = SPEED_MM_S) -> dict[str, Any]:
    """One design: the rig, the FE contact and each posture's press (module docstring)."""
    params = load_calibration(design).params("flex")
    top = REFERENCE_FORCE_N
    rig = simulate_flex_indentation(params, speed_mm_s=speed_mm_s,
                                    depth_mm=0.6 * params.height_mm, max_force_N=top)
    _, d_fe, f_fe = loading_ramp(fe_curves(design, FE_DIR)[0][0], top)
    fe = indent(design, IndentationSettings(max_force_N=top, hold_s=0.0, speed_mm_s=speed_mm_s))
    fe_area = {f"{f:g}": float(np.interp(f, fe.force_N, fe.contact_area_mm2)) for f in FORCES_N}
    p = fe.plate_pressure
    row: dict[str, Any] = {
        "design": design, "young_Pa": params.young_Pa,
        "rig": {"step_us": 1e6 * rig.stats["step_wall_s"] / rig.stats["steps"],
                "peak_N": float(rig.force_N.max()),
                "depth_at_peak_mm": float(rig.displacement_mm[np.argmax(rig.force_N)])},
        "fe": {"area_mm2": fe_area, "depth_at_2N_mm": fe.displacement_at(top),
               "peak_pressure_kPa": float(1e3 * p["pressure_MPa"].max()),
               "pressure_points_mm": p["points_mm"][p["pressure_MPa"] > 0][:, [0, 2]].tolist(),
               "pressure_kPa": (1e3 * p["pressure_MPa"][p["pressure_MPa"] > 0]).tolist()},
        "postures": {},
    }
    for posture in postures:
        press = press_flex_region(params, REGION, posture, speed_mm_s=speed_mm_s, max_force_N=top)
        c = press.curve
        on = (c.displacement_mm > 0) & (c.displacement_mm <= rig.displacement_mm.max())
        vs_rig = _rms_pct(c.force_N[on], rig.force_at(c.displacement_mm[on]))
        in_fe = on & (c.displacement_mm <= d_fe[-1])
        vs_fe = _rms_pct(c.force_N[in_fe], np.interp(c.displacement_mm[in_fe], d_fe, f_fe))
        peak = float(c.force_N.max())
        areas = {f"{f:g}": press.area_at(f) for f in FORCES_N if f <= peak}
        row["postures"][posture] = {
            "vs_rig_rms_pct_of_2N": vs_rig, "vs_fe_rms_pct_of_2N": vs_fe, "peak_N": peak,
            "depth_at_peak_mm": float(c.displacement_mm[np.argmax(c.force_N)]),
            "area_mm2": areas, "peak_pressure_kPa": float(press.patch.pressure_kPa.max()),
            "step_us": c.stats["step_us"], "nv": c.stats["nv"],
            "pressure_points_mm": press.patch.points_mm.tolist(),
            "pressure_kPa": press.patch.pressure_kPa.tolist(),
        }
    return row


def plot_pressure(rows: list[dict[str, Any]], path: Path) -> None:
    """Pressure at the peak force: the pad's contact vertices and the FE's contact points
    (quarter model mirrored), one panel per design; contact area against force below."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(rows), figsize=(5 * len(rows), 8.5), squeeze=False)
    for col, row in enumerate(rows):
        ax = axes[0, col]
        fe_xy = np.array(row["fe"]["pressure_points_mm"]).reshape(-1, 2)
        fe_p = np.array(row["fe"]["pressure_kPa"])
        sx = np.concatenate([fe_xy[:, 0], -fe_xy[:, 0], fe_xy[:, 0], -fe_xy[:, 0]])
        sy = np.concatenate([fe_xy[:, 1], fe_xy[:, 1], -fe_xy[:, 1], -fe_xy[:, 1]])
        vmax = max(fe_p.max(initial=1.0), *(max(v["pressure_kPa"], default=1.0)
                                              for v in row["postures"].values()))
        ax.scatter(sx, sy, c=np.tile(fe_p, 4), s=6, marker="s", cmap="viridis", vmin=0,
                   vmax=vmax, label="FE contact points")
        ext = row["postures"].get("extended")
        if ext:
            xy = np.array(ext["pressure_points_mm"]).reshape(-1, 2)
            sc = ax.scatter(xy[:, 0], xy[:, 1], c=ext["pressure_kPa"], s=70, cmap="viridis",
                            vmin=0, vmax=vmax, edgecolors="k", label="flex pad vertices")
            fig.colorbar(sc, ax=ax, label="pressure, kPa")
        ax.set_xlim(-8.5, 8.5)
        ax.set_ylim(-5.5, 5.5)
        ax.set_aspect("equal")
        ax.set_xlabel("across the finger, mm")
        ax.set_ylabel("along the finger, mm")
        ax.set_title(f"{row['design']}: pressure at the peak (extended)")
        ax.legend(fontsize=7, loc="lower right")
        ax = axes[1, col]
        forces = [float(f) for f in row["fe"]["area_mm2"]]
        ax.plot(forces, list(row["fe"]["area_mm2"].values()), "k-o", label="FE")
        for posture, v in row["postures"].items():
            fs = [float(f) for f in v["area_mm2"]]
            lo = [a[0] for a in v["area_mm2"].values()]
            hi = [a[1] for a in v["area_mm2"].values()]
            ax.fill_between(fs, lo, hi, alpha=0.3, label=f"flex on the hand, {posture}")
        ax.set_xlabel("plate force, N")
        ax.set_ylabel("contact area, mm^2")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"Flex pad on the prosthetic {REGION} against the FE, {SPEED_MM_S} mm/s")
    fig.tight_layout()
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=100)
    plt.close(fig)


def run_flex_bench(out_dir: str | Path = REPORTS_DIR, designs: tuple[str, ...] = DESIGNS,
                   progress=None) -> dict[str, Any]:
    """Every design's row, written to ``out_dir/bench-flex.{json,md,png}``."""
    out = Path(out_dir)
    rows = []
    for i, design in enumerate(designs):
        rows.append(flex_row(design))
        if progress:
            progress((i + 1) / len(designs))
    data = {"machine": machine_info(), "region": REGION, "speed_mm_s": SPEED_MM_S,
            "rows": rows}
    atomic_write_json(out / "bench-flex.json", data)
    atomic_write_text(out / "bench-flex.md", markdown(data))
    plot_pressure(rows, out / "bench-flex.png")
    return data


def _a(v) -> str:
    return "-" if v is None else f"{v[0]:.0f}-{v[1]:.0f}"


def markdown(data: dict[str, Any]) -> str:
    """The report's table."""
    lines = [f"# Flex pad on the prosthetic hand ({data['region']}, {data['speed_mm_s']} mm/s)",
             "", machine_line(data["machine"]), "",
             "| design | posture | vs the rig, RMS % of 2 N | vs the FE, RMS % of 2 N | peak N "
             "(at mm) | area at 0.5 / 1 / 2 N mm^2 (pad bounds; FE) | peak pressure kPa (FE) | "
             "us per step (rig) | dofs |",
             "|---|---|---|---|---|---|---|---|---|"]
    for row in data["rows"]:
        fe = row["fe"]
        for posture, v in row["postures"].items():
            areas = " / ".join(f"{_a(v['area_mm2'].get(k))} ({fe['area_mm2'][k]:.0f})"
                               for k in fe["area_mm2"])
            lines.append(
                f"| {row['design']} | {posture} | {v['vs_rig_rms_pct_of_2N']:.2f} | "
                f"{v['vs_fe_rms_pct_of_2N']:.1f} | {v['peak_N']:.2f} ({v['depth_at_peak_mm']:.2f}) "
                f"| {areas} | {v['peak_pressure_kPa']:.0f} ({fe['peak_pressure_kPa']:.0f}) | "
                f"{v['step_us']:.0f} ({row['rig']['step_us']:.0f}) | {v['nv']} |")
    lines += ["", "Pad bounds: the surface triangles wholly in contact, and the tributary area "
              "of every touching vertex (softhand.skin.flex.ContactPatch). FE: the contact "
              "Gauss points' share of the undeformed surface, at the FE's own 2 N step."]
    return "\n".join(lines) + "\n"
