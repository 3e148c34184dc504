"""Reference skins that have no FE model: the human middle phalanx and the commercial prosthesis.

Both are built from the paper's measured numbers (``softhand/data/paper.json``), with the shape
assumptions stated here; neither has relaxation data in the paper, so both are elastic (G = 1).

* Human middle phalanx: F = a (exp(b delta) - 1), the exponential stiffening of finger pulp under
  a flat plate (Serina, Mote & Rempel 1997, J Biomech 30(10):1035-1040; Pawluk & Howe 1999,
  J Biomech Eng 121(6):605-611, 0-2 N). Two numbers fix a and b: the grand mean of the six Fig. 5d
  means at 2 N (3.68 mm) and an indentation at 1 N of 2.5 mm. The paper states only "more than
  2 mm" at 1 N; 2.5 mm is an assumption (the bound plus a quarter of the 2-N depth's margin above
  it), marked as such in the law's source.

  Beyond the paper's 2 N: the same exponential, whose form was measured on finger pulp and is the
  force-displacement relation that Serina, Mote & Rempel (1998, J Biomech 31(7):639-646) matched
  with a structural fingertip model over contact forces of 0.25-7.0 N. So the law counts as
  calibrated to 7 N (`DATA_MAX_N`), with two named assumptions: that the middle phalanx's
  tissue follows the pulp's exponential form, and that the paper's 0-2 N numbers fix its two
  constants also above 2 N (no middle-phalanx data above 2 N were found). Above 7 N the law is an
  extrapolation (the handshake flags contacts there); it is tabulated to 20 N so that the pair laws
  have a shape over the whole FE range.
* Commercial prosthetic phalanx (Regal 102L): about 0.2 mm at 1 N (Fig. 8); linear, 5 N/mm (a thin
  cosmetic silicone glove over a rigid frame; assumption). Calibrated to 1 N, the paper's number.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from softhand.laws.elastic import ElasticLaw
from softhand.laws.fit import SkinLaw
from softhand.laws.qlv import Prony
from softhand.paper import paper

__all__ = ["DATA_MAX_N", "HUMAN", "PROSTHETIC", "TABLE_MAX_N", "human_law", "prosthetic_law",
           "reference_law"]

HUMAN = "human-middle-phalanx"
PROSTHETIC = "prosthetic-102l"
HUMAN_AT_1N_MM = 2.5  # assumption: the paper says "more than 2 mm" at 1 N
#: Largest force of the data behind each reference law (N): human tissue 7 N, the top of the
#: 0.25-7.0 N range over which the pulp's exponential law was confirmed (Serina et al. 1998; the
#: paper's phalanges were indented to 2 N); the 102L phalanx is quoted at 1 N (Fig. 8). Beyond
#: these the laws are extrapolations, not calibration.
DATA_MAX_N = {HUMAN: 7.0, PROSTHETIC: 1.0}
#: Force (N) the reference laws are tabulated to, as the FE curves of the designs are (the
#: calibrated range of the pair laws is set by DATA_MAX_N, not by this).
TABLE_MAX_N = 20.0


def _human_at_2n_mm() -> float:
    data = paper()["human_displacement_at_2N_mm"]
    means = [v[0] for k, v in data.items() if not k.startswith("_") and isinstance(v, list)]
    return float(np.mean(means))


def human_law() -> SkinLaw:
    """Exponential law through the paper's human mean at 2 N and 2.5 mm at 1 N."""
    d2, d1 = _human_at_2n_mm(), HUMAN_AT_1N_MM
    # F(d2) / F(d1) = 2 fixes b; then a from F(d2) = 2 N
    b = brentq(lambda b: np.expm1(b * d2) / np.expm1(b * d1) - 2.0, 1e-6, 20.0)
    a = 2.0 / np.expm1(b * d2)
    top = float(np.log1p(TABLE_MAX_N / a) / b)  # depth at TABLE_MAX_N
    d = np.linspace(0.0, top, 400)
    law = ElasticLaw.fit(d, a * np.expm1(b * d), n_basis=24)
    return SkinLaw(HUMAN, law, Prony(), source={
        "form": "F = a (exp(b delta) - 1)", "a_N": a, "b_per_mm": b,
        "paper": {"displacement_at_2N_mm": d2, "_source": paper()["human_displacement_at_2N_mm"]
                  ["_source"]},
        "assumption": {"displacement_at_1N_mm": d1, "paper_says": "more than 2 mm at 1 N",
                       "above_2N": "the pulp's exponential form (Serina et al. 1997, 1998) with the "
                                   "paper's constants; calibrated to 7 N, tabulated to 20 N"},
        "relaxation": "none measured in the paper: elastic (G = 1)"})


def prosthetic_law() -> SkinLaw:
    """Linear law through the paper's 0.2 mm at 1 N."""
    d1 = float(paper()["prosthetic_102l_displacement_mm"]["value"])
    k = 1.0 / d1
    d = np.linspace(0.0, TABLE_MAX_N / k, 50)
    law = ElasticLaw.fit(d, k * d, n_basis=3)
    return SkinLaw(PROSTHETIC, law, Prony(), source={
        "form": "F = k delta", "k_N_per_mm": k,
        "paper": {"displacement_at_1N_mm": d1,
                  "_source": paper()["prosthetic_102l_displacement_mm"]["_source"]},
        "relaxation": "none measured in the paper: elastic (G = 1)"})


def reference_law(name: str) -> SkinLaw:
    """``human-middle-phalanx`` or ``prosthetic-102l``."""
    if name == HUMAN:
        return human_law()
    if name == PROSTHETIC:
        return prosthetic_law()
    raise ValueError(f"reference skin {name!r} is unknown; allowed: {HUMAN}, {PROSTHETIC}")
