"""What the palm's rounded border costs: the laws the scene uses there against an FE of it.

    python tools/border_law_error.py [--out reports/border-law-error] [--designs all]

`reports/contact-geometry.md` finds 94 % of the default handshake's force on a rounded border of
the prosthetic palm's one convex surface (radius 8-23 mm, median 13.7, p10-p90), pressed by the
partner's fingers and carried by the palm/finger law: an FE cylinder of radius 9 mm across a flat
slab of the design's layers over the metacarpals. No FE curve of a rounded border exists yet
(issue 36, item 2), so this runs the nearest body the FE has: the phalanx section widened to a
border, width 20 mm and height 8 mm (a half ellipse, n = 2: radius a^2 / b = 12.5 mm at its top,
the median border's; the design's layers and pocket as on the phalanx; 8 mm of skin over a flat
bone, the palm model's 9 mm over the crest), under the same 9 mm cylinder across it, to 20 N on
the 3D quarter model. Against it, each skin's two laws that could carry a finger there: the
palm/finger law the pair carries and the phalanx/finger law (its elastic force on the FE's ramp
history, with its relaxation), as the RMS and largest difference in % of 2 N over the FE's
0-2 N and 0-20 N. Beside pocket2-sil, the border's radius moved: width 20 mm, height 7.7 mm
(13.0 mm) and 9 mm (11.1 mm); a flatter section leaves its flanks too tight for a 2 mm pocket's
layers, so the FE's phalanx reaches no larger radius. Writes ``OUT.md`` and ``OUT.json``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from softhand.bench.common import machine_info, machine_line
from softhand.fem.geometry import DESIGNS
from softhand.fem.solver import ConvergenceError, IndentationSettings, indent
from softhand.io import atomic_write_json, atomic_write_text
from softhand.skin.files import load_calibration

BORDER = {"width_mm": 20.0, "height_mm": 8.0}
RADII = ({"width_mm": 20.0, "height_mm": 7.7}, {"width_mm": 20.0, "height_mm": 9.0})
FINGER = "cylinder:9@90"
LAWS = ("palm/finger", "phalanx/finger")


def _fe(design: str, geometry: dict) -> dict:
    s = IndentationSettings(mode="3d", indenter=FINGER, geometry=geometry, max_force_N=20.0,
                            hold_s=0.0)
    try:
        r = indent(design, s)
        status = "reached 20 N"
    except ConvergenceError as exc:
        return {"error": str(exc)[:200]}
    ramp = ~r.hold
    return {"time_s": r.time_s[ramp].tolist(), "displacement_mm": r.displacement_mm[ramp].tolist(),
            "force_N": r.force_N[ramp].tolist(), "status": status,
            "d_2N_mm": r.displacement_at(2.0)}


def _errors(fe: dict, design: str) -> dict:
    cal = load_calibration(design)
    t, d, f = (np.asarray(fe[k]) for k in ("time_s", "displacement_mm", "force_N"))
    out = {}
    for key in LAWS:
        law = cal.pair_laws[key].law if key in cal.pair_laws else None
        if law is None:
            out[key] = None
            continue
        g = law.force(t, d)
        row = {}
        for top in (2.0, 20.0):
            sel = f <= top + 1e-9
            diff = 100.0 * (g[sel] - f[sel]) / 2.0
            row[f"to_{top:g}N"] = {"rms_pct_of_2N": float(np.sqrt(np.mean(diff ** 2))),
                                   "max_pct_of_2N": float(np.abs(diff).max()),
                                   "mean_signed_pct_of_2N": float(diff.mean())}
        row["law_force_at_fe_2N_depth_N"] = float(np.interp(fe["d_2N_mm"], d, g))
        out[key] = row
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="reports/border-law-error")
    ap.add_argument("--designs", default="all")
    args = ap.parse_args()
    designs = list(DESIGNS) if args.designs == "all" else args.designs.split(",")
    data: dict = {"machine": machine_info(), "border": BORDER, "finger": FINGER, "rows": [],
                  "radii": []}
    for design in designs:
        print(design, flush=True)
        fe = _fe(design, BORDER)
        row = {"design": design, "fe": fe}
        if "error" not in fe:
            row["errors"] = _errors(fe, design)
        data["rows"].append(row)
    for geometry in RADII:
        print("pocket2-sil", geometry, flush=True)
        fe = _fe("pocket2-sil", geometry)
        data["radii"].append({"geometry": geometry, "fe": fe,
                              "errors": None if "error" in fe else _errors(fe, "pocket2-sil")})
    out = Path(args.out)
    atomic_write_json(out.with_suffix(".json"), data)
    atomic_write_text(out.with_suffix(".md"), markdown(data))
    print(markdown(data))


def _cell(e: dict | None, top: str) -> str:
    if e is None:
        return "n/a"
    r = e[f"to_{top}N"]
    return f"{r['rms_pct_of_2N']:.0f} / {r['max_pct_of_2N']:.0f} ({r['mean_signed_pct_of_2N']:+.0f})"


def markdown(d: dict) -> str:
    lines = ["# The palm's rounded border against the laws that carry it", "",
             "`python tools/border_law_error.py --out reports/border-law-error`: the FE's nearest "
             f"body to the palm's rounded border (the phalanx section widened to width "
             f"{d['border']['width_mm']:g} mm, height {d['border']['height_mm']:g} mm: a "
             "12.5 mm top radius, the median border the partner's fingers press in the default "
             f"handshake, `reports/contact-geometry.md`) under the finger ({d['finger']}), 3D, to "
             "20 N, against the palm/finger law the scene's pair carries there and the "
             "phalanx/finger law: RMS / largest difference in % of 2 N (mean signed: the law "
             "above the FE is +), over the FE's 0-2 N and 0-20 N.", "",
             machine_line(d["machine"]), "",
             "| design | FE d(2 N) mm | palm/finger law, 0-2 N | 0-20 N | law's force at the "
             "FE's 2 N depth | phalanx/finger law, 0-2 N | 0-20 N |",
             "|---|---|---|---|---|---|---|"]
    for r in d["rows"]:
        fe = r["fe"]
        if "error" in fe:
            lines.append(f"| {r['design']} | FE stopped: {fe['error'][:80]} | | | | | |")
            continue
        e = r["errors"]
        pf = e["palm/finger"]
        at = "n/a" if pf is None else f"{pf['law_force_at_fe_2N_depth_N']:.2f} N"
        lines.append(f"| {r['design']} | {fe['d_2N_mm']:.3f} | {_cell(pf, '2')} | "
                     f"{_cell(pf, '20')} | {at} | {_cell(e['phalanx/finger'], '2')} | "
                     f"{_cell(e['phalanx/finger'], '20')} |")
    lines += ["", "pocket2-sil with the border's radius moved (the same laws):", "",
              "| border (width x height mm) | top radius mm | FE d(2 N) mm | palm/finger law, "
              "0-2 N | phalanx/finger law, 0-2 N |", "|---|---|---|---|---|"]
    for r in d["radii"]:
        g, fe = r["geometry"], r["fe"]
        rad = (g["width_mm"] / 2) ** 2 / g["height_mm"]
        if "error" in fe:
            lines.append(f"| {g['width_mm']:g} x {g['height_mm']:g} | {rad:.1f} | FE stopped | | |")
            continue
        lines.append(f"| {g['width_mm']:g} x {g['height_mm']:g} | {rad:.1f} | "
                     f"{fe['d_2N_mm']:.3f} | {_cell(r['errors']['palm/finger'], '2')} | "
                     f"{_cell(r['errors']['phalanx/finger'], '2')} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
