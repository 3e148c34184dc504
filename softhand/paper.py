"""The paper's numbers, loaded from the one data file that holds them.

Every number softhand reproduces or takes as input from Cabibihan, Pradipta & Ge (2011) lives in
``softhand/data/paper.json`` next to the table, figure or section it came from (key ``_source``).
Code and tests read them from here, never from literals.
"""

from __future__ import annotations

import json
from functools import lru_cache
from importlib import resources
from typing import Any


@lru_cache(maxsize=1)
def paper() -> dict[str, Any]:
    """Return the parsed paper data file (cached; treat as read-only)."""
    text = resources.files("softhand").joinpath("data/paper.json").read_text(encoding="utf-8")
    return json.loads(text)


def displacement_at_2n(design: str) -> float | None:
    """Paper's displacement (mm) at 2 N for ``design``, or None when the paper gives none."""
    return paper()["displacement_at_2N_mm"].get(design)


def force_at_2mm(design: str) -> float | None:
    """Paper's force (N) at 2 mm plate displacement for a 2 mm pocket design, or None."""
    return paper()["force_at_2mm_N"].get(design)
