"""When an embedded sensor placement is useful: named criteria, not the paper's.

A placement is useful when its sensitivity (the patch's reading per newton on the plate at
``AT_N``) is at least 0.1 N/N (a 10-bit FlexiForce A101, 0.043 N per quantum, then resolves
0.43 N of load), its dead band at most 0.5 N (a fifth of the partner's 2.5 N grip) and its reading
relaxes by at most 10 % in a 10 s hold. Used by ``softhand bench sensors`` (`softhand.bench.sensors`)
and the design search (`softhand.design.evaluate`).
"""

from __future__ import annotations

__all__ = ["AT_N", "USEFUL"]

USEFUL = {"sensitivity_min": 0.1, "dead_band_max_N": 0.5, "relaxation_max_pct": 10.0}
AT_N = 2.0
