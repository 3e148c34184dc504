"""Benchmark of the handshake: speed with recording off and on, and the skins side by side.

Measures, in one process on this machine (``softhand bench handshake``):

* speed of the default handshake (pocket2-sil everywhere, neutral controller, 1 ms step, all 18
  touch sensors and the partner's 19): steps per second and real-time factor of ``env.step`` with
  the rerun recording off, and with it on (the recording's write time added), best of REPEATS runs;
  the same for timesteps 0.5 and 2 ms;
* sensitivity: the same handshake (same partner, seed and controller) with the prosthetic hand
  wearing rigid shells, the commercial skin (prosthetic-102l) and the paper's designs: per skin and
  region the peak force and the peak contact area, the regions over 2 N and their overlap with the
  paper's Fig. 4 set.

Timings are wall-clock seconds of this machine; they are reported, never asserted by tests.
Lives in the last stage because it times the recording too.
"""

from __future__ import annotations

import os
import platform
import tempfile
import time
from pathlib import Path
from typing import Any

import mujoco

from softhand.envs.run import OVER_N, HandshakeRun, run_handshake
from softhand.fem.sweep import git_revision
from softhand.io import atomic_write_json, atomic_write_text
from softhand.paper import paper
from softhand.viz.recording import HandshakeFrames, record_handshake

__all__ = ["SENSITIVITY_SKINS", "frames_of", "run_handshake_benchmark"]

REPEATS = 3
SENSITIVITY_SKINS = ("rigid", "prosthetic-102l", "solid-sil", "solid-pu", "pocket1-sil",
                     "pocket2-sil", "pocket2-pu")


def frames_of(run: HandshakeRun) -> HandshakeFrames:
    """What a recording of ``run`` holds."""
    return HandshakeFrames(run.time_s, run.qpos, run.mocap_pos, run.mocap_quat, run.region_force_N,
                           run.region_names, run.skins, run.contacts, run.phase)


def _speed(timestep_s: float, *, record: bool) -> dict[str, float]:
    best: dict[str, float] | None = None
    for _ in range(REPEATS):
        run = run_handshake(timestep_s=timestep_s, frame_skip=round(0.01 / timestep_s))
        sim = float(run.time_s[-1])
        wall = run.wall_s
        if record:
            with tempfile.TemporaryDirectory() as tmp:
                t0 = time.perf_counter()
                record_handshake(Path(tmp) / "bench.rrd", run.model, frames_of(run))
                wall += time.perf_counter() - t0
        row = {"steps": run.steps, "wall_s": wall, "steps_per_s": run.steps / wall,
               "realtime_factor": sim / wall}
        if best is None or row["wall_s"] < best["wall_s"]:
            best = row
    return best


def _sensitivity(skins: tuple[str, ...], controller: str) -> dict[str, Any]:
    ref = set(paper()["handshake"]["over_2N"])
    out: dict[str, Any] = {}
    for skin in skins:
        run = run_handshake(design=skin, controller=controller, seed=0)
        table = run.table()
        over = run.over_2n
        out[skin] = {
            "regions": table,
            "over_2N": over,
            "fig4_overlap": sorted(ref & set(over)),
            "max_peak_N": max(v["peak_N"] for v in table.values()),
            "sum_mean_N": sum(v["mean_N"] for v in table.values()),
            "sum_mean_area_mm2": sum(v["mean_area_mm2"] for v in table.values()),
            "max_peak_area_mm2": max(v["peak_area_mm2"] for v in table.values()),
            "rigid_contact_peak_N": run.summary()["rigid_contact_peak_N"],
        }
    return out


def run_handshake_benchmark(out_dir: str | Path = "reports", *,
                            skins: tuple[str, ...] = SENSITIVITY_SKINS) -> str:
    """Run the benchmark, write ``bench-handshake.json`` and ``bench-handshake.md``, return the
    Markdown."""
    out = Path(out_dir)
    data: dict[str, Any] = {"machine": {"platform": platform.platform(), "cpus": os.cpu_count(),
                                        "python": platform.python_version(),
                                        "mujoco": mujoco.__version__},
                            "git_revision": git_revision()}
    data["speed"] = {f"{ts * 1000:g} ms": {"recording_off": _speed(ts, record=False),
                                          "recording_on": _speed(ts, record=True)}
                     for ts in (0.001, 0.0005, 0.002)}
    data["sensitivity"] = {c: _sensitivity(skins, c) for c in ("neutral", "open-loop")}
    atomic_write_json(out / "bench-handshake.json", data)
    md = _markdown(data)
    atomic_write_text(out / "bench-handshake.md", md)
    return md


def _markdown(d: dict[str, Any]) -> str:
    m = d["machine"]
    lines = [
        "# Handshake benchmark (`softhand bench handshake`)", "",
        f"Machine: {m['platform']}, {m['cpus']} CPUs, Python {m['python']}, MuJoCo {m['mujoco']}; "
        f"git {d['git_revision']}. One process, one core for the simulation.", "",
        "Speed of one 3.63 s handshake (pocket2-sil, neutral controller, 37 touch sensors), best of "
        f"{REPEATS}; recording on adds the time to write the rerun file:", "",
        "| timestep | recording | steps/s | real-time factor |", "|---|---|---|---|",
    ]
    for ts, rows in d["speed"].items():
        for label, key in (("off", "recording_off"), ("on", "recording_on")):
            r = rows[key]
            lines.append(f"| {ts} | {label} | {r['steps_per_s']:.0f} | {r['realtime_factor']:.1f}x |")
    lines.append("")
    for controller, table in d["sensitivity"].items():
        skins = list(table)
        lines += [f"## Skins side by side, controller `{controller}` (seed 0)", "",
                  "| skin | max peak N | sum of mean N | regions > 2 N | in Fig. 4 set | "
                  "sum of mean area mm^2 | max peak area mm^2 | bone-on-bone peak N |",
                  "|---|---|---|---|---|---|---|---|"]
        for skin, r in table.items():
            lines.append(f"| {skin} | {r['max_peak_N']:.2f} | {r['sum_mean_N']:.2f} | "
                         f"{len(r['over_2N'])} | {len(r['fig4_overlap'])} of "
                         f"{len(paper()['handshake']['over_2N'])} | {r['sum_mean_area_mm2']:.0f} | "
                         f"{r['max_peak_area_mm2']:.0f} | {r['rigid_contact_peak_N']:.1f} |")
        lines += ["", "Peak force (N) per region; **bold** over 2 N:", "",
                  "| region | " + " | ".join(skins) + " |", "|---|" + "---|" * len(skins)]
        for region in table[skins[0]]["regions"]:
            cells = []
            for skin in skins:
                v = table[skin]["regions"][region]["peak_N"]
                cells.append(f"**{v:.2f}**" if v > OVER_N else f"{v:.2f}")
            lines.append(f"| {region} | " + " | ".join(cells) + " |")
        lines += ["", "Mean contact area (mm^2) per region:", "",
                  "| region | " + " | ".join(skins) + " |", "|---|" + "---|" * len(skins)]
        for region in table[skins[0]]["regions"]:
            cells = [f"{table[s]['regions'][region]['mean_area_mm2']:.0f}" for s in skins]
            lines.append(f"| {region} | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines) + "\n"

