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

__all__ = ["LifelikeRow", "lifelike_ranking"]

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


def _row(law: SkinLaw, human: tuple[float, ...]) -> tuple[tuple[float, ...], float]:
    d = tuple(law.quasi_static_displacement_at(f) for f in FORCES_N)
    rel = (np.asarray(d) - np.asarray(human)) / np.asarray(human)
    return d, float(100 * np.sqrt(np.mean(rel**2)))


def lifelike_ranking(laws: dict[str, SkinLaw]) -> list[LifelikeRow]:
    """Rank ``laws`` (and the commercial baseline) by distance from the human phalanx."""
    human = human_law()
    h = tuple(human.quasi_static_displacement_at(f) for f in FORCES_N)
    all_laws = dict(laws)
    all_laws.setdefault(PROSTHETIC, prosthetic_law())
    rows = {name: _row(law, h) for name, law in all_laws.items()}
    base = rows[PROSTHETIC][1]
    out = [LifelikeRow(name, d, h, dist, dist < base) for name, (d, dist) in rows.items()]
    return sorted(out, key=lambda r: r.distance_pct)
