"""The pocket's two contacts side by side: paired (the shipped curves') against sliding.

    python tools/pocket_contact.py [--out reports/pocket-contact] [--no-ccx]

Writes ``reports/pocket-contact.{md,json}``:

1. every pocketed design of the paper and the design search's three winners, 2D default mesh,
   to 2 N: d(1 N) and d(2 N) with each contact, and how far the floor lies inside the roof at
   2 N (`softhand.fem.contact.floor_through_roof_mm`, from the geometry alone);
2. the same designs to 20 N: the force each contact reaches (or where Newton stops), and the
   floor inside the roof at the end;
3. pocket2-sil and pocket2-pu in 3D (default mesh, CHOLMOD, 2 threads) to 2 N: d(2 N), Newton
   iterations and wall time of each contact; and to 20 N, where each stops;
4. where the sliding contact stops on pocket2-sil's 2D meshes (coarse, default, fine) to 20 N;
5. with CalculiX (``ccx`` on PATH, unless ``--no-ccx``): the coarse 3D elastic deck of
   pocket2-sil (face-to-face roof/floor contact, large sliding) to 2.4 mm against both.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from softhand.bench.common import machine_info, machine_line
from softhand.design.evaluate import fe_design, screen_settings
from softhand.design.search import candidate_of
from softhand.fem.contact import floor_through_roof_mm
from softhand.fem.geometry import parse_design
from softhand.fem.mesh import MESH_LEVELS, build_mesh
from softhand.fem.solver import ConvergenceError, IndentationSettings, _Model, indent
from softhand.io import atomic_write_json, atomic_write_text
from softhand.paths import REPORTS_DIR

POCKETED = ("pocket1-sil", "pocket1-sil-pu", "pocket1-pu-sil", "pocket1-pu",
            "pocket2-sil", "pocket2-sil-pu", "pocket2-pu-sil", "pocket2-pu")
KINDS = ("paired", "sliding")
CCX_DEPTH_MM = 2.4


def _designs() -> list[tuple[str, object, IndentationSettings]]:
    """(label, design, settings of the 2D screen) for the paper's pocketed designs and the
    design search's winners (reports/design-search.json)."""
    out = [(name, name, IndentationSettings(mode="2d", hold_s=0.0, threads=1))
           for name in POCKETED]
    path = Path(REPORTS_DIR) / "design-search.json"
    if path.exists():
        for i, w in enumerate(json.loads(path.read_text(encoding="utf-8"))["winners"], 1):
            design, s = fe_design(candidate_of(w), screen_settings(contact_points=4))
            out.append((f"winner {i} (trial {w['trial']})", design, s))
    return out


def _last_state(design, s: IndentationSettings):
    """The run (or its failure) and the last converged state, whatever stopped it."""
    seen: dict = {}
    orig = _Model.newton

    def newton(model, *args, **kw):
        out = orig(model, *args, **kw)
        seen["u"], seen["mesh"] = out[0], model.mesh
        return out

    _Model.newton = newton
    try:
        try:
            r = indent(design, s)
            return r, None, seen
        except ConvergenceError as exc:
            return None, exc, seen
    finally:
        _Model.newton = orig


def _row(label, design, s, force: float) -> dict:
    row: dict = {"design": label}
    for kind in KINDS:
        r, exc, seen = _last_state(design, dataclasses.replace(s, max_force_N=force,
                                                               pocket_contact=kind))
        inside = floor_through_roof_mm(seen["mesh"], seen["u"]) if "u" in seen else None
        if r is not None:
            row[kind] = {"reached_N": float(r.force_N[-1]), "depth_mm": float(r.displacement_mm[-1]),
                         "d1_mm": r.displacement_at(1.0), "d2_mm": r.displacement_at(2.0),
                         "floor_inside_roof_mm": inside, "stopped": None}
        else:
            row[kind] = {"reached_N": exc.diagnostics.get("force_N"),
                         "depth_mm": exc.diagnostics.get("displacement_mm"),
                         "floor_inside_roof_mm": inside,
                         "stopped": str(exc).split(": ", 1)[-1][:160]}
    return row


def _three_d() -> list[dict]:
    rows = []
    for name in ("pocket2-sil", "pocket2-pu"):
        row = {"design": name}
        for kind in KINDS:
            s = IndentationSettings(hold_s=0.0, threads=2, solver="cholmod", pocket_contact=kind)
            t0 = time.perf_counter()
            r = indent(name, s)
            row[kind] = {"d2_mm": r.displacement_at(2.0), "wall_s": time.perf_counter() - t0,
                         "newton_iterations": int(sum(e["iterations"] for e in r.log))}
            t0 = time.perf_counter()
            r20, exc, _ = _last_state(name, dataclasses.replace(s, max_force_N=20.0))
            row[kind]["to_20N"] = {
                "reached_N": float(r20.force_N[-1]) if r20 else exc.diagnostics.get("force_N"),
                "depth_mm": float(r20.displacement_mm[-1]) if r20
                else exc.diagnostics.get("displacement_mm"),
                "stopped": None if r20 else str(exc).split(": ", 1)[-1][:160],
                "wall_s": time.perf_counter() - t0}
        rows.append(row)
    return rows


def _meshes() -> list[dict]:
    rows = []
    for level in ("coarse", "default", "fine"):
        s = IndentationSettings(mode="2d", mesh=level, hold_s=0.0, threads=1, max_force_N=20.0,
                                pocket_contact="sliding")
        r, exc, _ = _last_state("pocket2-sil", s)
        mesh = build_mesh(parse_design("pocket2-sil").geometry(), MESH_LEVELS[level], dim=2)
        rows.append({"mesh": level, "dofs": int(mesh.n_dofs),
                     "reached_N": float(r.force_N[-1]) if r else exc.diagnostics.get("force_N"),
                     "depth_mm": float(r.displacement_mm[-1]) if r
                     else exc.diagnostics.get("displacement_mm"),
                     "stopped": None if r else str(exc).split(": ", 1)[-1][:160]})
    return rows


def _calculix() -> dict | None:
    """CalculiX's coarse elastic pocket2-sil to CCX_DEPTH_MM against softhand's two contacts."""
    if shutil.which("ccx") is None:
        return None
    from softhand.fem.abaqus import write_deck
    from softhand.fem.calculix import read_ccx_dat

    base = IndentationSettings(mesh="coarse")
    with tempfile.TemporaryDirectory() as tmp:
        write_deck("pocket2-sil", Path(tmp) / "job.inp", base, fmt="ccx", depth_mm=CCX_DEPTH_MM)
        t0 = time.perf_counter()
        run = subprocess.run(["ccx", "-i", "job"], cwd=tmp, capture_output=True, text=True,
                             env={**os.environ, "OMP_NUM_THREADS": "1"}, timeout=1800,
                             check=False)
        wall = time.perf_counter() - t0
        if run.returncode != 0 or "Job finished" not in run.stdout:
            return {"error": run.stdout[-500:]}
        d, f = read_ccx_dat(Path(tmp) / "job.dat")
    marks = (1.0, 2.0, 2.2, 2.4)
    out = {"depths_mm": list(marks), "ccx_wall_s": wall,
           "ccx_N": [float(np.interp(x, d, f)) for x in marks]}
    for kind in KINDS:
        r = indent("pocket2-sil", IndentationSettings(
            mesh="coarse", elastic_only=True, max_step_mm=0.025, max_depth_mm=CCX_DEPTH_MM,
            max_force_N=50.0, threads=1, pocket_contact=kind))
        out[f"{kind}_N"] = [r.force_at(x) for x in marks]
    return out


def _f(v, spec: str = ".3f") -> str:
    return "n/a" if v is None else format(v, spec)


def _pct(a, b) -> str:
    return "n/a" if a is None or b is None else f"{100 * (a / b - 1):+.1f} %"


def _markdown(d: dict) -> str:
    lines = ["# The pocket's contact: paired against sliding", "",
             "`python tools/pocket_contact.py --out reports/pocket-contact`. The paired contact "
             "(the shipped FE curves' and the default) presses each floor Gauss point on the "
             "roof point at the same place on its face, along the floor's normal at rest; the "
             "sliding one (`IndentationSettings(pocket_contact=\"sliding\")`) projects each floor "
             "and side-wall point on the deformed roof. \"Floor inside the roof\" is measured "
             "from the deformed geometry alone (2D), not from either contact's gaps.", "",
             machine_line(d["machine"]), "",
             "To 2 N, 2D, default mesh (the design search's screen):", "",
             "| design | d(1 N) paired | d(1 N) sliding | d(2 N) paired | d(2 N) sliding | "
             "paired vs sliding at 2 N | floor inside the roof at 2 N, paired / sliding (mm) |",
             "|---|---|---|---|---|---|---|"]
    for r in d["two_newton"]:
        p, s = r["paired"], r["sliding"]
        lines.append(f"| {r['design']} | {_f(p.get('d1_mm'))} | {_f(s.get('d1_mm'))} | "
                     f"{_f(p.get('d2_mm'))} | {_f(s.get('d2_mm'))} | "
                     f"{_pct(p.get('d2_mm'), s.get('d2_mm'))} | "
                     f"{_f(p['floor_inside_roof_mm'], '.4f')} / "
                     f"{_f(s['floor_inside_roof_mm'], '.4f')} |")
    lines += ["", "To 20 N, 2D, default mesh: the force each contact reaches (where Newton stops, "
              "the last converged point) and the floor inside the roof there:", "",
              "| design | paired: N at mm | floor inside roof, paired (mm) | sliding: N at mm | "
              "floor inside roof, sliding (mm) |", "|---|---|---|---|---|"]
    for r in d["twenty_newton"]:
        p, s = r["paired"], r["sliding"]

        def reach(x):
            return (f"{_f(x['reached_N'], '.2f')} at {_f(x['depth_mm'], '.3f')}"
                    + (" (stops)" if x["stopped"] else ""))
        lines.append(f"| {r['design']} | {reach(p)} | {_f(p['floor_inside_roof_mm'], '.3f')} | "
                     f"{reach(s)} | {_f(s['floor_inside_roof_mm'], '.3f')} |")
    lines += ["", "3D quarter model, default mesh, to 2 N (CHOLMOD, 2 threads):", "",
              "| design | d(2 N) paired | d(2 N) sliding | paired vs sliding | Newton iterations "
              "paired / sliding | wall paired / sliding (s) |", "|---|---|---|---|---|---|"]
    for r in d["three_d"]:
        p, s = r["paired"], r["sliding"]
        lines.append(f"| {r['design']} | {p['d2_mm']:.3f} | {s['d2_mm']:.3f} | "
                     f"{_pct(p['d2_mm'], s['d2_mm'])} | {p['newton_iterations']} / "
                     f"{s['newton_iterations']} | {p['wall_s']:.1f} / {s['wall_s']:.1f} |")
    lines += ["", "The same in 3D to 20 N (no floor-in-roof measure in 3D):", "",
              "| design | paired: N at mm | sliding: N at mm | why sliding stops | wall paired / "
              "sliding (s) |", "|---|---|---|---|---|"]
    for r in d["three_d"]:
        p, s = r["paired"]["to_20N"], r["sliding"]["to_20N"]
        lines.append(f"| {r['design']} | {_f(p['reached_N'], '.2f')} at {_f(p['depth_mm'])} | "
                     f"{_f(s['reached_N'], '.2f')} at {_f(s['depth_mm'])} | "
                     f"{s['stopped'] or 'reached 20 N'} | {p['wall_s']:.0f} / {s['wall_s']:.0f} |")
    lines += ["", "Where the sliding contact stops, pocket2-sil 2D to 20 N, by mesh:", "",
              "| mesh | dofs | reached N | at mm | why it stops |", "|---|---|---|---|---|"]
    for r in d["meshes"]:
        lines.append(f"| {r['mesh']} | {r['dofs']} | {_f(r['reached_N'], '.2f')} | "
                     f"{_f(r['depth_mm'], '.3f')} | {r['stopped'] or 'reached 20 N'} |")
    c = d.get("calculix")
    if c and "error" not in c:
        lines += ["", "CalculiX 2.20 (coarse 3D, elastic, face-to-face roof/floor contact with "
                  f"large sliding, no side-wall contact; {c['ccx_wall_s']:.0f} s on one core) "
                  "against softhand's elastic runs of the same mesh:", "",
                  "| plate travel mm | CalculiX N | paired N | paired vs CalculiX | sliding N | "
                  "sliding vs CalculiX |", "|---|---|---|---|---|---|"]
        for x, cc, p, s in zip(c["depths_mm"], c["ccx_N"], c["paired_N"], c["sliding_N"],
                               strict=True):
            lines.append(f"| {x:g} | {cc:.4f} | {p:.4f} | {_pct(p, cc)} | {s:.4f} | "
                         f"{_pct(s, cc)} |")
    elif c is None:
        lines += ["", "CalculiX: not run (no `ccx` on PATH, or `--no-ccx`)."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(Path(REPORTS_DIR) / "pocket-contact"))
    ap.add_argument("--no-ccx", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out)
    if not out.parent.is_dir():
        print(f"--out {out}: the folder {out.parent} does not exist", file=sys.stderr)
        return 2
    d: dict = {"machine": machine_info()}
    designs = _designs()
    print("2D to 2 N ...", flush=True)
    d["two_newton"] = [_row(label, design, s, 2.0) for label, design, s in designs]
    print("2D to 20 N ...", flush=True)
    d["twenty_newton"] = [_row(label, design, s, 20.0) for label, design, s in designs]
    print("3D to 2 N ...", flush=True)
    d["three_d"] = _three_d()
    print("meshes ...", flush=True)
    d["meshes"] = _meshes()
    if not args.no_ccx:
        print("CalculiX ...", flush=True)
        d["calculix"] = _calculix()
    atomic_write_json(out.with_suffix(".json"), d)
    atomic_write_text(out.with_suffix(".md"), _markdown(d))
    print(f"wrote {out}.md and .json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
