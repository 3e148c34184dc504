"""Indent two skin designs and compare them with the paper and with a human finger.

Run: ``python examples/fe_indent.py`` (3D, about a minute) or ``python examples/fe_indent.py 2d``
(plane strain, a few seconds). Plane strain ignores the free ends of the 10 mm long phalanx, so
2D is stiffer than 3D by design (smaller displacements; ``softhand bench fe`` gives the difference
per design): 2D for a quick look, 3D for numbers. Prints displacement at 1 N and 2 N and how much
the force relaxes during a 5 s hold.
"""

from __future__ import annotations

import sys

from softhand.fem import IndentationSettings, indent
from softhand.paper import paper


def main(mode: str = "3d", mesh: str = "default") -> dict[str, dict[str, float | None]]:
    human = paper()["human_displacement_at_2N_mm"]["Middle2-curled"][0]
    settings = IndentationSettings(mode=mode, mesh=mesh, hold_s=5.0)
    designs = ("solid-sil", "pocket2-sil")
    took = ("3D, about a minute; 2D takes a few seconds" if mode == "3d"
            else "2D plane strain, a few seconds")
    print(f"indenting {' and '.join(designs)} to 2 N, then a 5 s hold: {took} (2D is stiffer "
          "than 3D by design: plane strain ignores the phalanx's free ends)")
    out = {}
    for i, design in enumerate(designs, 1):
        print(f"{design} ({i} of {len(designs)}) ...", flush=True)
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
