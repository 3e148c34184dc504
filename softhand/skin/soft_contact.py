r"""Calibrated soft contact: a skin's force law written into MuJoCo's solref/solimp.

At rest, one contact row with direct-format ``solref = (-S, -B)`` and ``solimp = (d0, dw, width,
mid, power)`` carries (MuJoCo's constraint model, `\hat A` = the row's approximate inverse
inertia ``efc_diagA``, frozen at ``qpos0``):

    F(r) = \frac{S}{\hat A}\,\frac{d(r)^2}{d_w^2\,(1 - d(r))}\,r
         + \frac{B}{\hat A}\,\frac{d(r)}{d_w\,(1 - d(r))}\,\dot r

where `d(r)` is the impedance sigmoid. So the same (S, B) gives a different force on a
different body; writing `S = \hat S \hat A` and `B = \hat B \hat A` per contact pair
makes the law independent of the bodies' masses and of the hand's posture (`\hat A` is
``body_invweight0[b1, 0] + body_invweight0[b2, 0]``, computed by the compiler). This module fits
`(\hat S, d_0, d_w, \text{width}, \text{mid}, \text{power})` to a force-indentation curve and
writes the pair parameters. The impedance stays `d \le 0.3` so that the contact remains a force
law rather than a motion constraint (DESIGN.md, "Into MuJoCo"). Units: SI inside MuJoCo (m, N);
the fit takes mm and N like the FE curves.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from scipy.optimize import least_squares

from softhand.laws.fit import FitStatus, fit_status, force_weights, paired_arrays
from softhand.validate import check_mapping, check_number, check_numbers, join

__all__ = ["D_MAX", "SoftContactParams", "fit_soft_contact", "impedance"]

D_MAX = 0.3  # largest impedance allowed: beyond it the contact acts as a motion constraint
D_MIN = 1e-4  # MuJoCo's mjMINIMP
#: Largest soft-contact stiffness and damping per unit inverse mass a skin file may hold
#: (SoftContactParams.from_dict says why)
STIFFNESS_MAX = 1e8
DAMPING_MAX = 1e4
MAX_POWER = 20.0  # steepest impedance sigmoid the fit may use


def impedance(r_m, solimp) -> np.ndarray:
    """MuJoCo's impedance d(r) for penetration ``r_m`` (m, >= 0) and ``solimp`` (5 values)."""
    d0, dw, width, mid, power = (float(x) for x in solimp)
    x = np.clip(np.abs(np.asarray(r_m, dtype=float)) / width, 0.0, 1.0)
    if power == 1:
        y = x
    else:
        y = np.where(x <= mid, x**power / mid ** (power - 1),
                     1 - (1 - x) ** power / (1 - mid) ** (power - 1))
    return d0 + y * (dw - d0)


@dataclass(frozen=True)
class SoftContactParams:
    """Mass-normalised soft-contact parameters of one skin.

    Attributes:
        stiffness: `\\hat S`, N/m per unit inverse inertia (solref[0] = -stiffness * A).
        damping: `\\hat B`, N s/m per unit inverse inertia (solref[1] = -damping * A).
        solimp: (d0, dw, width_m, midpoint, power).
    """

    stiffness: float
    damping: float
    solimp: tuple[float, float, float, float, float]

    def __post_init__(self) -> None:
        if not np.isfinite(self.stiffness) or self.stiffness <= 0:
            raise ValueError(f"stiffness = {self.stiffness!r} must be finite and > 0")
        if not np.isfinite(self.damping) or self.damping < 0:
            raise ValueError(f"damping = {self.damping!r} must be finite and >= 0")
        if len(self.solimp) != 5:
            raise ValueError(f"solimp = {self.solimp!r} must have 5 values")
        d0, dw, width, mid, power = (float(x) for x in self.solimp)
        if not D_MIN <= d0 <= dw <= D_MAX:
            raise ValueError(f"solimp d0 = {d0:.4g}, dw = {dw:.4g}: need {D_MIN} <= d0 <= dw "
                             f"<= {D_MAX}")
        if not width > 0:
            raise ValueError(f"solimp width = {width!r} must be > 0 (m)")
        if not 0 < mid < 1:
            raise ValueError(f"solimp midpoint = {mid!r} must be in (0, 1)")
        if not power >= 1:
            raise ValueError(f"solimp power = {power!r} must be >= 1")
        object.__setattr__(self, "solimp", (d0, dw, width, mid, power))

    def force(self, r_mm, rate_mm_s=0.0) -> np.ndarray:
        """Contact force (N) at penetration ``r_mm`` (and penetration rate), any body masses."""
        r = np.maximum(np.asarray(r_mm, dtype=float), 0.0) * 1e-3
        d = impedance(r, self.solimp)
        dw = self.solimp[1]
        f = (self.stiffness * d**2 / dw**2 * r
             + self.damping * d / dw * np.asarray(rate_mm_s, dtype=float) * 1e-3) / (1 - d)
        return np.where(r > 0, f, 0.0)

    @property
    def end_stiffness(self) -> float:
        """Stiffness (N/m) once the impedance is full: the law's stiffest straight part."""
        return self.stiffness / (1 - self.solimp[1])

    def solref(self, inv_inertia: float) -> tuple[float, float]:
        """Direct-format solref for a contact pair whose ``efc_diagA`` is ``inv_inertia``."""
        if not np.isfinite(inv_inertia) or inv_inertia <= 0:
            raise ValueError(f"inv_inertia = {inv_inertia!r} must be finite and > 0")
        return (-self.stiffness * inv_inertia, -self.damping * inv_inertia)

    def to_dict(self) -> dict:
        return {"stiffness_N_per_m_per_invmass": self.stiffness,
                "damping_Ns_per_m_per_invmass": self.damping, "solimp": list(self.solimp)}

    @classmethod
    def from_dict(cls, d: Any, *, key: str = "params") -> SoftContactParams:
        """Parse `to_dict` output, checking every value.

        Allowed: ``stiffness_N_per_m_per_invmass`` in (0, 1e8], ``damping_Ns_per_m_per_invmass``
        in [0, 1e4] (per unit inverse mass: a stiffness k is a squared angular frequency and a
        damping b a rate, and MuJoCo's step at the smallest timestep softhand allows, 0.1 ms,
        stays stable for sqrt(k) dt < 2 and b dt < 2, i.e. k < 4e8 and b < 2e4; the shipped
        calibrations lie within 193-2.4e5 and 0.5-6.2), ``solimp`` 5 numbers: d0 and dw in
        [1e-4, 0.3] with d0 <= dw, width > 0 (m), midpoint in (0, 1), power >= 1.

        Raises:
            ValueError: ``"{key}.solimp[0] = 'x': expected a finite number in [0.0001, 0.3]"``.
        """
        names = ("stiffness_N_per_m_per_invmass", "damping_Ns_per_m_per_invmass", "solimp")
        check_mapping(key, d, required=names)
        stiffness = check_number(join(key, names[0]), d[names[0]], lo=0.0, hi=STIFFNESS_MAX,
                                 lo_open=True, why="(beyond it no timestep integrates it stably)")
        damping = check_number(join(key, names[1]), d[names[1]], lo=0.0, hi=DAMPING_MAX,
                               why="(beyond it no timestep integrates it stably)")
        si = join(key, "solimp")
        if not isinstance(d["solimp"], (list, tuple)) or len(d["solimp"]) != 5:
            check_numbers(si, d["solimp"], length=5)  # raises: not a list of 5
        d0, dw, width, mid, power = d["solimp"]
        solimp = (check_number(f"{si}[0]", d0, lo=D_MIN, hi=D_MAX, why="(d0)"),
                  check_number(f"{si}[1]", dw, lo=D_MIN, hi=D_MAX, why="(dw)"),
                  check_number(f"{si}[2]", width, lo=0.0, lo_open=True, why="(width, m)"),
                  check_number(f"{si}[3]", mid, lo=0.0, hi=1.0, lo_open=True, hi_open=True,
                               why="(midpoint)"),
                  check_number(f"{si}[4]", power, lo=1.0, why="(power)"))
        if solimp[0] > solimp[1]:
            raise ValueError(f"{si}[0] = {solimp[0]!r}: expected d0 <= dw = {solimp[1]!r}")
        return cls(stiffness, damping, solimp)


class SoftContactFit(NamedTuple):
    """What `fit_soft_contact` found: the parameters, their RMS error (N) on the given
    curve and how the best start's least-squares fit ended."""

    params: SoftContactParams
    rms_N: float
    status: FitStatus


def fit_soft_contact(delta_mm, force_N, *, damping_ratio: float = 0.5,
                     reference_mass_kg: float = 0.02,
                     initial: SoftContactParams | None = None) -> tuple[SoftContactParams, float]:
    """Fit the rest law F(r) to a force-indentation curve; return params and RMS error (N).

    The damping is set, not fitted: ``damping_ratio`` of critical for ``reference_mass_kg`` on the
    law's end stiffness (N s/m at full impedance; it adds ``damping * rate`` to the force). Use the
    lightest body the skin will touch: contact damping is explicit under ``implicitfast``, so a
    damping set for a heavier body makes a light one unstable. ``initial`` replaces the
    multi-start search by one start (a close law, e.g. the skin's own when fitting skin + tissue).
    Residuals are weighted by `softhand.laws.fit.force_weights` (absolute up to 2 N,
    relative above); ``rms_N`` is the plain RMS force error over the whole curve.
    """
    d, f = paired_arrays(delta_mm, force_N, ("delta_mm", "force_N"), min_size=5)
    keep = d > 0
    d, f = d[keep], f[keep]
    top = float(d.max()) * 1e-3
    secant_end = float(f[-1] / d[-1]) * 1e3  # N/m

    # bounded physical parameters: log stiffness, dw, d0 / dw, width / top, midpoint, power
    lower = np.array([np.log(secant_end) - 8, 0.02, 1e-3, 0.05, 0.05, 1.0])
    upper = np.array([np.log(secant_end) + 8, D_MAX, 1.0, 3.0, 0.95, MAX_POWER])

    def unpack(p):
        dw = float(p[1])
        d0 = max(D_MIN, float(p[2]) * dw)
        return float(np.exp(p[0])), (d0, dw, float(p[3]) * top, float(p[4]), float(p[5]))

    def model(p, r_m):
        s, si = unpack(p)
        dd = impedance(r_m, si)
        return s * dd**2 / si[1] ** 2 * r_m / (1 - dd)

    r = d * 1e-3
    w = force_weights(f)  # absolute up to 2 N, relative above (curves reach 20 N)
    best = None
    # the sigmoid's shape is not convex to fit: several starts, or one close law
    starts = [np.array([np.log(secant_end), dw0, 0.3, 1.0, mid0, pw0])
              for dw0 in (0.05, 0.3) for mid0 in (0.2, 0.45, 0.7, 0.9) for pw0 in (1.5, 4.0, 10.0)]
    if initial is not None:
        d0, dw, width, mid, power = initial.solimp
        starts = [np.clip([np.log(initial.stiffness), dw, d0 / dw, width / top, mid, power],
                          lower + 1e-9, upper - 1e-9)]
    for x0 in starts:
        res = least_squares(lambda p: w * (model(p, r) - f), x0, bounds=(lower, upper),
                            method="trf", max_nfev=2000, xtol=1e-12, ftol=1e-12)
        if best is None or res.cost < best.cost:
            best = res
    status = fit_status(best, "soft contact (solref/solimp)")
    stiffness, solimp = unpack(best.x)
    k_end = float(np.gradient(model(best.x, r), r)[-1])
    damping = 2 * damping_ratio * np.sqrt(max(k_end, 1e-9) * reference_mass_kg) * (1 - solimp[1])
    params = SoftContactParams(float(stiffness), float(damping), tuple(float(x) for x in solimp))
    rms = float(np.sqrt(np.mean((params.force(d) - f) ** 2)))
    return SoftContactFit(params, rms, status)
