"""Embedded sensors of the 12 designs side by side (``softhand bench sensors``): a table a skin
designer can act on.

For each design, one FE ramp to 2 N at 0.5 mm/s and a 10 s hold (3D, default mesh, the default
4 x 4 mm patches of :mod:`softhand.fem.sensors`) gives, per placement: the sensitivity (the
patch's reading per newton on the plate at 2 N), the pocket floor's dead band (the plate force
between the last step the floor read 0 and the first it read more, bounded by the FE's steps),
and how much the reading relaxes over the hold (against the plate force's own relaxation); next to
the design's lifelike distance from the human phalanx (``calibration/skins/index.json``).
Written to ``reports/bench-sensors.{json,md}``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from softhand.bench.common import machine_info, machine_line
from softhand.fem import solver
from softhand.fem.geometry import DESIGNS
from softhand.fem.solver import IndentationSettings
from softhand.io import atomic_write_json, atomic_write_text
from softhand.paths import REPORTS_DIR, SKINS_DIR

__all__ = ["run_sensor_table", "sensor_row"]

HOLD_S = 10.0


def sensor_row(design: str, settings: IndentationSettings | None = None) -> dict[str, Any]:
    """One design's sensors: per placement sensitivity, dead band (pocket floor) and relaxation."""
    r = solver.indent(design, settings or IndentationSettings(hold_s=HOLD_S))
    end = int(np.flatnonzero(~r.hold)[-1])
    row: dict[str, Any] = {"plate_N": float(r.force_N[end]),
                           "plate_relaxation_pct": float(100 * (1 - r.force_N[-1] / r.force_N[end])),
                           "wall_s": r.wall_s, "sensors": {}}
    for name, v in r.embedded_sensors.items():
        f = np.asarray(v["force_N"])
        on = np.flatnonzero(f > 0)
        dead = None
        if v["placement"] == "pocket-floor" and on.size:
            dead = [float(r.force_N[on[0] - 1]), float(r.force_N[on[0]])]
        row["sensors"][name] = {
            "placement": v["placement"], "area_mm2": v["area_mm2"], "at_2N": float(f[end]),
            "sensitivity": float(f[end] / r.force_N[end]), "dead_band_N": dead,
            "relaxation_pct": float(100 * (1 - f[-1] / f[end])) if f[end] > 0 else None}
    return row


def run_sensor_table(out_dir: str | Path = REPORTS_DIR, *,
                     designs: tuple[str, ...] = tuple(DESIGNS)) -> str:
    """Run every design, write ``bench-sensors.json`` and ``.md``, return the Markdown."""
    life = {}
    index = Path(SKINS_DIR) / "index.json"
    if index.exists():
        life = {r["name"]: r["distance_pct"]
                for r in json.loads(index.read_text(encoding="utf-8"))["lifelike"]}
    data = {"machine": machine_info(), "hold_s": HOLD_S,
            "designs": {d: {**sensor_row(d), "lifelike_distance_pct": life.get(d)}
                        for d in designs}}
    out = Path(out_dir)
    atomic_write_json(out / "bench-sensors.json", data)
    md = _markdown(data)
    atomic_write_text(out / "bench-sensors.md", md)
    return md


def _markdown(d: dict[str, Any]) -> str:
    lines = ["# Embedded sensors of the designs (`softhand bench sensors`)", "",
             f"{machine_line(d['machine'])} 3D FE, default mesh, 0.5 mm/s to 2 N, "
             f"{d['hold_s']:g} s hold; 4 x 4 mm patches under the indenter (reading per newton on "
             "the plate at 2 N; relaxation of the reading over the hold, the plate's in the "
             "third column).", "",
             "| design | lifelike distance % | plate relaxes % | bone N/N | under the outer layer "
             "N/N | pocket floor N/N | floor dead band N | reading relaxes, bone / layer / floor % |",
             "|---|---|---|---|---|---|---|---|"]
    rows = sorted(d["designs"].items(),
                  key=lambda kv: (kv[1]["lifelike_distance_pct"] is None,
                                  kv[1]["lifelike_distance_pct"] or 0.0))
    for name, r in rows:
        s = r["sensors"]
        floor = s.get("pocket-floor")
        life = r["lifelike_distance_pct"]
        dead = (f"{floor['dead_band_N'][0]:.2f}-{floor['dead_band_N'][1]:.2f}"
                if floor and floor["dead_band_N"] else "-")
        fs = "-" if floor is None else f"{floor['sensitivity']:.2f}"
        relax = " / ".join("-" if s.get(k) is None or s[k]["relaxation_pct"] is None
                           else f"{s[k]['relaxation_pct']:.1f}"
                           for k in ("bone", "interface", "pocket-floor"))
        lines.append(f"| {name} | {'-' if life is None else f'{life:.0f}'} | "
                     f"{r['plate_relaxation_pct']:.1f} | {s['bone']['sensitivity']:.3f} | "
                     f"{s['interface']['sensitivity']:.2f} | "
                     f"{fs} | {dead} | {relax} |")
    return "\n".join(lines) + "\n"
