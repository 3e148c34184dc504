"""The pair law: a skin pressed against human tissue, both indenting, as one calibrated soft contact.

When a prosthetic skin meets the partner's tissue, the same force F compresses both, so the pair's
indentation is the sum of the two at that force (springs in series):

    delta_pair(F) = delta_skin(F) + delta_tissue(F).

Both inversions are exact on the laws (monotone, `ElasticLaw.displacement_at`): the skin's
loading curve at the paper's 0.5 mm/s from its QLV law (the curve its ``soft-contact`` is fitted
to), the tissue's elastic law. The series curve is built over the whole range both laws are
tabulated on (the FE curves reach 20 N; the human law is tabulated to 20 N), then one soft contact
(`softhand.skin.soft_contact.fit_soft_contact`) is fitted to all of it, weighted absolute up
to 2 N and relative above. Its error against the exact series curve is reported up to 2 N (% of
2 N) and above (% of the force). The *calibrated* range of the pair is the smaller of the two laws'
data ranges (a design's FE curves, the tissue's published data:
`softhand.laws.references.DATA_MAX_N`); above it the handshake flags the contact.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from softhand.laws.elastic import monotone_inverse
from softhand.laws.fit import SkinLaw, split_errors
from softhand.paper import paper
from softhand.skin.soft_contact import SoftContactParams, fit_soft_contact
from softhand.validate import check_mapping, check_number, join, show

__all__ = ["PairLaw", "fit_pair_law", "loading_inverse", "series_curve"]

_SAMPLES = 240
#: Error up to 2 N (% of 2 N) above which a fit started from the skin's own law is redone with
#: the multi-start search.
RETRY_PCT_OF_2N = 2.5
#: the paper's plate speed: the loading curve each soft contact is fitted to
_RAMP_MM_S = float(paper()["loading"]["plate_speed_mm_s"])


def loading_inverse(law: SkinLaw, force_N: np.ndarray, *, top_N: float) -> np.ndarray:
    """Indentation (mm) at each force of ``law``'s loading ramp at 0.5 mm/s (QLV; an elastic law:
    its own curve), by interpolating a dense monotone ramp up to ``top_N``."""
    depth = law.quasi_static_displacement_at(top_N, _RAMP_MM_S)
    d = np.linspace(0.0, depth, 4000)
    return monotone_inverse(force_N, d, law.force(d / _RAMP_MM_S, d))


def series_curve(skin: SkinLaw, tissue: SkinLaw, top_N: float) -> tuple[np.ndarray, np.ndarray]:
    """(indentation mm, force N) of ``skin`` in series with ``tissue``, 0 to ``top_N``."""
    force = np.linspace(0.0, top_N, _SAMPLES + 1)[1:]
    d_skin = loading_inverse(skin, force, top_N=top_N)
    d_tissue = tissue.elastic.displacement_at(force)
    return np.concatenate([[0.0], d_skin + d_tissue]), np.concatenate([[0.0], force])


@dataclass(frozen=True)
class PairLaw:
    """A skin's soft contact against human tissue.

    Attributes:
        against: the tissue's skin name (``human-middle-phalanx``).
        params: the fitted soft-contact parameters of the pair.
        fitted_max_N: top of the series curve it was fitted to (N).
        calibrated_max_N: top of the data behind both laws (N): the range the scene trusts.
        rms_pct_of_2N_to_2N: RMS error against the exact series curve up to 2 N, % of 2 N.
        rms_pct_above_2N: RMS error above 2 N, % of the force (None if the curve stops at 2 N).
        max_pct_of_2N: largest error over the whole curve, % of 2 N.
        fit_status: how the fit ended (``converged`` or ``evaluation budget``).
    """

    against: str
    params: SoftContactParams
    fitted_max_N: float
    calibrated_max_N: float
    rms_pct_of_2N_to_2N: float
    rms_pct_above_2N: float | None
    max_pct_of_2N: float
    fit_status: str

    def to_dict(self) -> dict:
        return {"against": self.against, "params": self.params.to_dict(),
                "fitted_max_N": self.fitted_max_N, "calibrated_max_N": self.calibrated_max_N,
                "rms_pct_of_2N_to_2N": self.rms_pct_of_2N_to_2N,
                "rms_pct_above_2N": self.rms_pct_above_2N, "max_pct_of_2N": self.max_pct_of_2N,
                "fit_status": self.fit_status}

    @classmethod
    def from_dict(cls, d: Any, *, key: str = "pair_law") -> PairLaw:
        """Parse `to_dict` output, every value checked (ValueError naming the key path)."""
        names = ("against", "params", "fitted_max_N", "calibrated_max_N", "rms_pct_of_2N_to_2N",
                 "rms_pct_above_2N", "max_pct_of_2N", "fit_status")
        check_mapping(key, d, required=names)
        for text in ("against", "fit_status"):
            if not isinstance(d[text], str):
                raise ValueError(f"{join(key, text)} = {show(d[text])}: expected a string")
        above = d["rms_pct_above_2N"]
        fitted = check_number(join(key, "fitted_max_N"), d["fitted_max_N"], lo=0.0, lo_open=True)
        calibrated = check_number(join(key, "calibrated_max_N"), d["calibrated_max_N"], lo=0.0,
                                  lo_open=True, hi=fitted, why="(at most fitted_max_N)")
        return cls(d["against"], SoftContactParams.from_dict(d["params"], key=join(key, "params")),
                   fitted, calibrated,
                   check_number(join(key, "rms_pct_of_2N_to_2N"), d["rms_pct_of_2N_to_2N"], lo=0.0),
                   None if above is None else check_number(join(key, "rms_pct_above_2N"), above,
                                                           lo=0.0),
                   check_number(join(key, "max_pct_of_2N"), d["max_pct_of_2N"], lo=0.0),
                   d["fit_status"])


def fit_pair_law(skin: SkinLaw, tissue: SkinLaw, *, skin_top_N: float, skin_data_N: float,
                 tissue_top_N: float, tissue_data_N: float, reference_mass_kg: float,
                 initial: SoftContactParams | None = None) -> PairLaw:
    """Fit the pair law of ``skin`` against ``tissue`` (see the module docstring).

    Args:
        skin, tissue: the two laws.
        skin_top_N, tissue_top_N: forces each law is tabulated to (its curve's end).
        skin_data_N, tissue_data_N: forces each law's data reach (its calibrated range).
        reference_mass_kg: lightest body the pair will move (sets the contact damping).
        initial: a start for the fit (one start instead of the multi-start search, which runs
            anyway when that start ends above RETRY_PCT_OF_2N up to 2 N).
    """
    top = min(skin_top_N, tissue_top_N)
    d, f = series_curve(skin, tissue, top)
    params, _, status = fit_soft_contact(d, f, reference_mass_kg=reference_mass_kg,
                                         initial=initial)
    split = split_errors(params.force(d)[1:], f[1:])
    if initial is not None and split["rms_pct_of_2N_to_2N"] > RETRY_PCT_OF_2N:
        # the skin's own law was a poor start: the multi-start search, kept if it does better
        other, _, other_status = fit_soft_contact(d, f, reference_mass_kg=reference_mass_kg)
        other_split = split_errors(other.force(d)[1:], f[1:])
        if other_split["rms_pct_of_2N_to_2N"] < split["rms_pct_of_2N_to_2N"]:
            params, status, split = other, other_status, other_split
    model = params.force(d)
    return PairLaw(tissue.name, params, float(top), float(min(top, skin_data_N, tissue_data_N)),
                   split["rms_pct_of_2N_to_2N"], split["rms_pct_above_2N"],
                   float(100 * np.abs(model - f).max() / 2.0), status.value)
