"""Embedded sensors of the 12 designs, and on the hand (``softhand bench sensors``).

1. **Design table** (from the shipped records and transfer laws, ``calibration/sensors``; no FE
   run): per design and placement the sensitivity (the patch's reading per newton on the plate at
   2 N), the pocket floor's dead band (the transfer law's F_0, inside the FE's bracket), how much
   the reading relaxes over the 10 s hold at 20 N (against the plate force's own relaxation), the
   transfer law's fit error, next to the design's lifelike distance from the human phalanx
   (``calibration/skins/index.json``). A placement is **useful** when its sensitivity is at least
   0.1 N/N (a 10-bit FlexiForce A101, 0.043 N per quantum, then resolves 0.43 N of load), its dead
   band at most 0.5 N (a fifth of the partner's 2.5 N grip) and its reading relaxes by at most
   10 % in the hold: named criteria, not the paper's.
2. **Transfer curves** (``bench-sensors.png``): reading against load on the 0.5 mm/s ramp, FE
   points and law, per placement.
3. **Handshake** (default scene, seed 0): per region the contact force beside the sensor's
   reading, under the outer layer and on the pocket floor.
4. **Controllers on sensor readings**: the neutral controller (each finger stops at a 0.3 N
   touch) and the force controller (2.5 N) fed the true contact forces or the sensors' calibrated
   read-out, under the outer layer and on the pocket floor, on pocket2-sil (dead band 0.32 N) and
   pocket2-pu (0.84 N); with the A101 electronics and with ideal ones (no threshold, latency,
   noise or quantization), which isolates the dead band.

Written to ``reports/bench-sensors.{json,md,png}``.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from softhand.bench.common import machine_info, machine_line
from softhand.fem import solver
from softhand.fem.solver import IndentationSettings
from softhand.io import atomic_open, atomic_write_json, atomic_write_text
from softhand.paths import REPORTS_DIR, SENSORS_DIR, SKINS_DIR
from softhand.sensors.criteria import AT_N, USEFUL
from softhand.sensors.transfer import SensorRecord, record_from_result

__all__ = ["record_row", "run_sensor_table", "sensor_row"]

PLACEMENT_ORDER = ("bone", "interface", "pocket-floor")
HANDSHAKE_DESIGN = "pocket2-sil"


def record_row(rec: SensorRecord) -> dict[str, Any]:
    """Per placement: sensitivity at 2 N of plate force, the FE's dead-band bracket (pocket
    floor), the reading's relaxation over the hold; the plate's own relaxation."""
    end = rec.peak_index
    ramp = slice(0, end + 1)
    f = rec.force_N[ramp]
    row: dict[str, Any] = {"plate_N": float(rec.force_N[end]),
                           "plate_relaxation_pct": float(100 * (1 - rec.force_N[-1] / rec.force_N[end])),
                           "sensors": {}}
    for name, reading in rec.readings_N.items():
        r = reading
        at = float(np.interp(AT_N, f, r[ramp])) if f[-1] >= AT_N else float(r[end])
        on = np.flatnonzero(r > 1e-9)
        dead = None
        if rec.placements[name] == "pocket-floor" and on.size:
            dead = [float(rec.force_N[on[0] - 1]), float(rec.force_N[on[0]])]
        row["sensors"][name] = {
            "placement": rec.placements[name], "area_mm2": rec.area_mm2[name],
            "sensitivity": at / min(AT_N, float(f[-1])), "dead_band_N": dead,
            "relaxation_pct": float(100 * (1 - r[-1] / r[end])) if r[end] > 0 else None}
    return row


def sensor_row(design: str, settings: IndentationSettings | None = None) -> dict[str, Any]:
    """`record_row` of one FE run of ``design`` (default: to 2 N, 10 s hold)."""
    r = solver.indent(design, settings or IndentationSettings(hold_s=10.0))
    return {**record_row(record_from_result(r)), "wall_s": r.wall_s}


def _lifelike() -> dict[str, float]:
    index = Path(SKINS_DIR) / "index.json"
    if not index.exists():
        return {}
    return {r["name"]: r["distance_pct"]
            for r in json.loads(index.read_text(encoding="utf-8"))["lifelike"]}


def design_table(root: str | Path = SENSORS_DIR, designs: tuple[str, ...] | None = None
                 ) -> dict[str, Any]:
    """The design table from the shipped records and transfer laws (module docstring, 1)."""
    from softhand.sensors.calibrate import load_transfer_laws, read_records

    laws = load_transfer_laws(Path(root) / "transfer.json")
    life = _lifelike()
    out = {}
    for design in designs or sorted({d for d, _ in laws}):
        fit, _ = read_records(root, design)
        row = record_row(fit[0])
        for s in row["sensors"].values():
            law = laws[(design, s["placement"])]
            s["law_dead_band_N"] = law.dead_band_N
            s["fit_rms_pct"] = law.fitted[0].rms_pct
            s["validation_rms_pct"] = law.validated[0].rms_pct if law.validated else None
            s["useful"] = bool(
                s["sensitivity"] >= USEFUL["sensitivity_min"]
                and law.dead_band_N <= USEFUL["dead_band_max_N"]
                and (s["relaxation_pct"] or 0.0) <= USEFUL["relaxation_max_pct"])
        out[design] = {**row, "lifelike_distance_pct": life.get(design)}
    return out


def plot_transfer_curves(root: str | Path, path: Path) -> None:
    """Reading against load on the 0.5 mm/s ramp: FE points and law, one panel per placement."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from softhand.sensors.calibrate import load_transfer_laws, read_records

    laws = load_transfer_laws(Path(root) / "transfer.json")
    fig, axes = plt.subplots(2, 3, figsize=(15, 9))
    designs = sorted({d for d, _ in laws})
    # one colour per material layout, one line style and marker per topology: 12 designs that
    # can be told apart (20 shades of one colour map could not)
    layout_colour = {"sil": "tab:blue", "pu": "tab:red", "sil-pu": "tab:green",
                     "pu-sil": "tab:orange"}
    topology_style = {"solid": ("-", "o"), "pocket1": ("--", "s"), "pocket2": (":", "^")}
    for col, placement in enumerate(PLACEMENT_ORDER):
        for design in designs:
            topology, _, materials = design.partition("-")
            c = layout_colour.get(materials, "k")
            line, marker = topology_style.get(topology, ("-", "o"))
            law = laws.get((design, placement))
            if law is None:
                continue
            rec = read_records(root, design)[0][0]
            name = next(n for n, p in rec.placements.items() if p == placement)
            ramp = ~rec.hold
            model = law.reading(rec.time_s, rec.force_N)
            for ax in axes[:, col]:
                ax.plot(rec.force_N[ramp], rec.readings_N[name][ramp], marker, ms=2.5, color=c)
                ax.plot(rec.force_N[ramp], model[ramp], line, color=c, lw=1.2, label=design)
        for row, (top, what) in enumerate(((20.0, "0-20 N"), (3.0, "0-3 N: the dead bands"))):
            ax = axes[row, col]
            ax.set_title(f"{placement} (4 x 4 mm patch), {what}")
            ax.set_xlabel("load on the skin (plate force), N")
            ax.set_ylabel("sensor reading, N on the patch")
            ax.set_xlim(0, top)
            if row:
                ax.set_ylim(-0.1, 1.2)
                ax.axhline(0.0, color="k", lw=0.5)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, ncol=2)
    fig.suptitle("Transfer curves of the embedded sensors: FE (points; the bone under an open "
                 "pocket is in tension) and fitted laws of a compression sensor (lines), "
                 "0.5 mm/s ramp")
    fig.tight_layout()
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110)
    plt.close(fig)


DIGITS = ("Index", "Middle", "Ring", "Little")


def _handshake(placement: str, controller: str = "neutral", signal: str = "contact",
               design: str = HANDSHAKE_DESIGN, ideal: bool = False, **settings) -> dict[str, Any]:
    from dataclasses import replace

    from softhand.envs.partner import HOLDING
    from softhand.envs.run import run_handshake
    from softhand.sensors.device import FLEXIFORCE_A101

    spec = (replace(FLEXIFORCE_A101, name="ideal", noise_N=0.0, threshold_N=0.0, latency_s=0.0,
                    resolution_N=0.0) if ideal else FLEXIFORCE_A101)
    run = run_handshake(design=design, controller=controller, signal=signal,
                        sensor_placement=placement, controller_settings=settings, sensor=spec)
    grip = np.array([p in HOLDING for p in run.phase])
    digit = {d: np.max([run.region_force_N[:, i] for i, r in enumerate(run.region_names)
                        if r.startswith(d)], axis=0) for d in DIGITS}
    return {"regions": run.table(),
            "digit_mean_held_N": {d: float(f[grip].mean()) for d, f in digit.items()},
            "digit_peak_N": {d: float(f.max()) for d, f in digit.items()},
            "flexion_deg": run.kinematics()["prosthetic_flexion_deg"],
            "steps_per_s": run.steps / run.wall_s}


def run_sensor_table(out_dir: str | Path = REPORTS_DIR, *, root: str | Path = SENSORS_DIR,
                     designs: tuple[str, ...] | None = None, handshakes: bool = True,
                     progress: Callable[[str], None] | None = None) -> str:
    """Write ``bench-sensors.json``, ``.md`` and ``.png``; return the Markdown; ``progress``
    gets a line before each part and handshake."""
    from softhand.paper import paper

    say = progress or (lambda line: None)
    out = Path(out_dir)
    say("the design table")
    data: dict[str, Any] = {"machine": machine_info(), "useful": USEFUL,
                            "designs": design_table(root, designs)}
    say("the transfer curves")
    plot_transfer_curves(root, out / "bench-sensors.png")
    if handshakes:
        data["fig4_regions"] = list(paper()["handshake"]["over_2N"])
        data["handshake"] = {}
        for placement in ("interface", "pocket-floor"):
            say(f"handshake, sensors at {placement}")
            data["handshake"][placement] = _handshake(placement)
        runs = {}
        feeds = (("contact", "contact", "interface", False),
                 ("sensor under the outer layer", "sensor", "interface", False),
                 ("sensor on the pocket floor", "sensor", "pocket-floor", False),
                 ("ideal sensor under the outer layer", "sensor", "interface", True),
                 ("ideal sensor on the pocket floor", "sensor", "pocket-floor", True))
        for design in ("pocket2-sil", "pocket2-pu"):
            for ctrl in ("neutral", "force"):
                for label, signal, placement, ideal in feeds:
                    if ctrl == "force" and ideal:
                        continue
                    say(f"controllers on sensor readings: {design}, {ctrl}, fed {label}")
                    runs[f"{design}, {ctrl}, {label}"] = {
                        "design": design, "controller": ctrl, "signal": signal,
                        "placement": placement, "ideal_electronics": ideal,
                        **_handshake(placement, ctrl, signal, design, ideal)}
        data["controllers"] = runs
    atomic_write_json(out / "bench-sensors.json", data)
    md = _markdown(data)
    atomic_write_text(out / "bench-sensors.md", md)
    return md


def _f(v, fmt: str = ".2f") -> str:
    return "-" if v is None else format(v, fmt)


def _markdown(d: dict[str, Any]) -> str:
    lines = ["# Embedded sensors (`softhand bench sensors`)", "",
             f"{machine_line(d['machine'])}", "",
             "## The designs", "",
             "Shipped records (3D FE, default mesh, 0.5 mm/s to 20 N, 10 s hold; 4 x 4 mm patches "
             "under the indenter) and transfer laws (`calibration/sensors`). Sensitivity: reading "
             "per newton on the plate at 2 N. Relaxation: of the reading over the hold at 20 N "
             "(the plate's own in the third column). Useful (u): sensitivity >= "
             f"{d['useful']['sensitivity_min']} N/N, dead band <= "
             f"{d['useful']['dead_band_max_N']} N, reading relaxes <= "
             f"{d['useful']['relaxation_max_pct']:g} %.", "",
             "| design | lifelike distance % | plate relaxes % | bone N/N | under the outer layer "
             "N/N | pocket floor N/N | dead band N: bone / floor (floor's FE bracket) | reading "
             "relaxes, bone / layer / floor % | law RMS error, fit / 2 mm/s, % of span (worst "
             "placement) | useful placements |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    rows = sorted(d["designs"].items(),
                  key=lambda kv: (kv[1]["lifelike_distance_pct"] is None,
                                  kv[1]["lifelike_distance_pct"] or 0.0))
    for name, r in rows:
        s = {v["placement"]: v for v in r["sensors"].values()}
        floor = s.get("pocket-floor")
        dead = f"{s['bone']['law_dead_band_N']:.2f} / " + (
            f"{floor['law_dead_band_N']:.2f} ({floor['dead_band_N'][0]:.2f}-"
            f"{floor['dead_band_N'][1]:.2f})" if floor and floor["dead_band_N"] else "-")
        relax = " / ".join("-" if k not in s or s[k]["relaxation_pct"] is None
                           else f"{s[k]['relaxation_pct']:.1f}" for k in PLACEMENT_ORDER)
        fit = max(v["fit_rms_pct"] for v in s.values())
        val = max((v["validation_rms_pct"] or 0.0) for v in s.values())
        useful = ", ".join(k for k in PLACEMENT_ORDER if k in s and s[k]["useful"]) or "none"
        lines.append(f"| {name} | {_f(r['lifelike_distance_pct'], '.0f')} | "
                     f"{r['plate_relaxation_pct']:.1f} | {s['bone']['sensitivity']:.3f} | "
                     f"{s['interface']['sensitivity']:.2f} | "
                     f"{_f(floor['sensitivity'] if floor else None)} | {dead} | {relax} | "
                     f"{fit:.2f} / {val:.2f} | {useful} |")
    lines += ["", "Transfer curves: `bench-sensors.png`.", ""]
    if "handshake" in d:
        regions = d["fig4_regions"]
        lines += ["## Handshake with the sensor model", "",
                  f"Default scene ({HANDSHAKE_DESIGN} everywhere, neutral controller, seed 0), "
                  "FlexiForce A101 electronics; the paper's regions over 2 N (Fig. 4). Contact: "
                  "the true normal force; sensor: the reading, N on the patch.", "",
                  "| region | contact peak / mean N | interface sensor peak / mean N | "
                  "pocket-floor sensor peak / mean N |", "|---|---|---|---|"]
        hs = d["handshake"]
        for r in regions:
            c = hs["interface"]["regions"][r]
            f = hs["pocket-floor"]["regions"][r]
            lines.append(f"| {r} | {c['peak_N']:.2f} / {c['mean_N']:.2f} | "
                         f"{c['sensor_peak']:.2f} / {c['sensor_mean']:.2f} | "
                         f"{f['sensor_peak']:.2f} / {f['sensor_mean']:.2f} |")
        lines += ["", "## Controllers on sensor readings", "",
                  "One design everywhere, seed 0. Neutral: each finger closes until the force it "
                  "feels passes 0.3 N, then holds; force: each finger holds 2.5 N. The feedback "
                  "is the true contact force, or the sensors' calibrated read-out (the transfer "
                  "law inverted; nothing inside a dead band), with the A101 electronics or ideal "
                  "ones (no threshold, latency, noise, quantization). Forces are true contact "
                  "forces of each finger's most loaded region: held = mean over the grip and "
                  "shake, peak = over the handshake.", "",
                  "| design, controller, feedback | held index / middle / ring / little N | "
                  "peak index / middle / ring / little N | flexion index / middle deg |",
                  "|---|---|---|---|"]
        for label, v in d["controllers"].items():
            held = " / ".join(f"{x:.2f}" for x in v["digit_mean_held_N"].values())
            peak = " / ".join(f"{x:.2f}" for x in v["digit_peak_N"].values())
            flex = v["flexion_deg"]
            lines.append(f"| {label} | {held} | {peak} | {flex['index']:.0f} / "
                         f"{flex['middle']:.0f} |")
    return "\n".join(lines) + "\n"
