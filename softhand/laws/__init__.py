"""Skin laws: elastic force-indentation laws with quasi-linear viscoelastic relaxation.

Second stage of the flow: fitted to the FE stage's curves (`softhand.fem`), read by the MuJoCo
calibration (`softhand.skin`). Imports only `softhand.fem` data, never later stages.
"""

from softhand.laws.elastic import ElasticLaw
from softhand.laws.fit import Curve, CurveError, SkinLaw, curve_errors, fit_skin_law, load_curve
from softhand.laws.qlv import Prony, qlv_force

__all__ = ["Curve", "CurveError", "ElasticLaw", "Prony", "SkinLaw", "curve_errors",
           "fit_skin_law", "load_curve", "qlv_force"]
