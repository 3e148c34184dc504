"""Press a calibrated skin in MuJoCo and compare it with its FE curve and with a human finger.

Run: ``python examples/skin_in_mujoco.py [SKIN]`` (default pocket2-sil; a few seconds). Uses the
shipped calibration in ``calibration/skins`` (``softhand calibrate`` makes it). Prints the force at
1 mm and 2 mm of indentation for the FE record, rigid contact, calibrated soft contact and the
relaxation pad, and the force left after the 10 s hold; then the human middle phalanx at the same
indentations (the reference law from the paper's numbers, `softhand.laws.references`: no hold,
the paper measured none).
"""

from __future__ import annotations

import sys

import numpy as np

from softhand.laws.references import human_law
from softhand.skin.calibrate import CALIBRATION_MASS_KG, fe_curves
from softhand.skin.files import FE_DIR, load_calibration
from softhand.skin.rig import RigSettings, build_rig, run_rig


def main(skin: str = "pocket2-sil") -> dict[str, dict[str, float]]:
    cal = load_calibration(skin)
    curve = fe_curves(skin, FE_DIR)[0][0]
    ramp = ~curve.hold
    settings = RigSettings(mass_kg=CALIBRATION_MASS_KG)
    rows = {"FE": {"F_1mm": float(np.interp(1.0, curve.displacement_mm[ramp], curve.force_N[ramp])),
                   "F_2mm": float(np.interp(2.0, curve.displacement_mm[ramp], curve.force_N[ramp])),
                   "F_end": float(curve.force_N[-1])}}
    for rep in ("rigid", "soft-contact", "soft-contact+relaxation"):
        out = run_rig(build_rig(rep, cal.params(rep), settings=settings), curve.time_s,
                      curve.displacement_mm, settings=settings)
        up = out.time_s <= curve.time_s[curve.peak_index]
        rows[rep] = {"F_1mm": float(np.interp(1.0, out.displacement_mm[up], out.force_N[up])),
                     "F_2mm": float(np.interp(2.0, out.displacement_mm[up], out.force_N[up])),
                     "F_end": float(out.force_N[-1])}
    human = human_law().elastic
    rows["human middle phalanx"] = {"F_1mm": float(human.force(1.0)),
                                    "F_2mm": float(human.force(2.0)), "F_end": float("nan")}
    print(f"{skin}: force (N) at 1 mm and 2 mm of indentation, and after the 10 s hold")
    print(f"  {'':24s} {'1 mm':>9s} {'2 mm':>9s} {'held':>9s}")
    for name, r in rows.items():
        held = "-" if np.isnan(r["F_end"]) else f"{r['F_end']:.3f}"
        print(f"  {name:24s} {r['F_1mm']:9.3f} {r['F_2mm']:9.3f} {held:>9s}")
    return rows


if __name__ == "__main__":
    main(*sys.argv[1:2])
