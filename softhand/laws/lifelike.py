"""Lifelike score: how far a skin's compliance is from the human middle phalanx (Fig. 8).

For each skin, the indentation at 1 N and at 2 N in a 0.5 mm/s ramp (the paper's test) is compared
with the human reference law (`softhand.laws.references.human_law`):

    distance = 100 * sqrt(mean_F ((d_skin(F) - d_human(F)) / d_human(F))^2),  F in {1 N, 2 N}

0 is human; the commercial prosthetic skin is the baseline. Ranked from most to least lifelike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from softhand.laws.fit import SkinLaw
from softhand.laws.references import PROSTHETIC, human_law, prosthetic_law

__all__ = ["LifelikeRow", "distance_pct", "human_displacements_mm", "lifelike_ranking"]

FORCES_N = (1.0, 2.0)


@dataclass(frozen=True)
class LifelikeRow:
    name: str
    displacement_mm: tuple[float, ...]  # at FORCES_N
    human_mm: tuple[float, ...]
    distance_pct: float
    better_than_prosthetic: bool

    def to_dict(self) -> dict:
        return {"name": self.name, "forces_N": list(FORCES_N),
                "displacement_mm": list(self.displacement_mm), "human_mm": list(self.human_mm),
                "distance_pct": self.distance_pct,
                "better_than_prosthetic": self.better_than_prosthetic}


def human_displacements_mm() -> tuple[float, ...]:
    """The human reference's indentation (mm) at each of `FORCES_N` in the paper's ramp."""
    human = human_law()
    return tuple(human.quasi_static_displacement_at(f) for f in FORCES_N)


def distance_pct(displacements_mm, human_mm: tuple[float, ...] | None = None) -> float:
    """The lifelike distance (module docstring) of a skin's indentation at `FORCES_N`, e.g. read
    off an FE ramp at 0.5 mm/s (the design search) or from a fitted law (`lifelike_ranking`)."""
    h = np.asarray(human_displacements_mm() if human_mm is None else human_mm)
    rel = (np.asarray(displacements_mm, dtype=float) - h) / h
    return float(100 * np.sqrt(np.mean(rel**2)))


def _row(law: SkinLaw, human: tuple[float, ...]) -> tuple[tuple[float, ...], float]:
    d = tuple(law.quasi_static_displacement_at(f) for f in FORCES_N)
    return d, distance_pct(d, human)


def lifelike_ranking(laws: dict[str, SkinLaw]) -> list[LifelikeRow]:
    """Rank ``laws`` (and the commercial baseline) by distance from the human phalanx."""
    h = human_displacements_mm()
    all_laws = dict(laws)
    all_laws.setdefault(PROSTHETIC, prosthetic_law())
    rows = {name: _row(law, h) for name, law in all_laws.items()}
    base = rows[PROSTHETIC][1]
    out = [LifelikeRow(name, d, h, dist, dist < base) for name, (d, dist) in rows.items()]
    return sorted(out, key=lambda r: r.distance_pct)
