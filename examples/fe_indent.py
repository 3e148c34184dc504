"""Indent two skin designs and compare them with the paper and with a human finger.

Run: ``python examples/fe_indent.py`` (3D, about a minute) or ``python examples/fe_indent.py 2d``
(plane strain, a few seconds). Prints displacement at 1 N and 2 N, force at 2 mm, and how much
the force relaxes during a 5 s hold.
"""

from __future__ import annotations

import sys

from softhand.fem import IndentationSettings, indent
from softhand.paper import paper


def main(mode: str = "3d", mesh: str = "default") -> dict[str, dict[str, float | None]]:
    human = paper()["human_displacement_at_2N_mm"]["Middle2-curled"][0]
    settings = IndentationSettings(mode=mode, mesh=mesh, hold_s=5.0)
    out = {}
    for design in ("solid-sil", "pocket2-sil"):
        r = indent(design, settings)
        s = r.summary()
        out[design] = s
        ref = paper()["displacement_at_2N_mm"][design]
        print(f"{design:12s} d(1 N) {s['displacement_at_1N_mm']:.2f} mm, "
              f"d(2 N) {s['displacement_at_2N_mm']:.2f} mm (paper {ref}, human Middle2 {human}), "
              f"after 5 s hold {100 * s['relaxed_force_N'] / s['peak_force_N']:.1f} % of the peak")
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])
