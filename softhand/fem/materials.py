r"""Storakers hyperfoam with Prony relaxation: the skins' constitutive law.

Energy (paper eq. 2, Storakers 1986), for principal stretches `\lambda_a`, `J=\lambda_1\lambda_2\lambda_3`:

    U = \sum_{i=1}^{N} \frac{2\mu_i}{\alpha_i^2}\Big[\lambda_1^{\alpha_i}+\lambda_2^{\alpha_i}
        +\lambda_3^{\alpha_i}-3+\frac{1}{\beta}\big(J^{-\alpha_i\beta}-1\big)\Big],
    \qquad \beta=\frac{\nu}{1-2\nu}.

With logarithmic principal strains `l_a=\ln\lambda_a`, `L=\ln J=\sum_a l_a` the linear
terms of the bracket cancel exactly, so softhand evaluates

    U = \sum_i 2\mu_i\Big[\sum_a l_a^2\,\varphi_2(\alpha_i l_a) + \beta L^2\,\varphi_2(-\alpha_i\beta L)\Big],
    \qquad \varphi_2(x)=\frac{e^x-1-x}{x^2},

which has no cancellation for silicone's `\alpha_1=0.001` and tends to the Hencky energy
`\mu(\sum_a l_a^2+\beta L^2)` as `\alpha\to0`. Principal Kirchhoff stresses are

    \tau_a=\frac{\partial U}{\partial l_a}=\sum_i 2\mu_i\big[l_a\varphi_1(\alpha_i l_a)
        +\beta L\,\varphi_1(-\alpha_i\beta L)\big],\qquad \varphi_1(x)=\frac{e^x-1}{x},

and `\partial\tau_a/\partial l_b=\sum_i2\mu_i[\delta_{ab}e^{\alpha_i l_a}+\beta e^{-\alpha_i\beta L}]`.
The second Piola-Kirchhoff stress is `S=\sum_a (\tau_a/c_a) N_a\otimes N_a` with `c_a`,
`N_a` the eigenpairs of `C=F^TF` (paper eq. 3), and the tangent
`\mathbb{C}=2\,\partial S/\partial C` follows from the spectral-function derivative, with the
divided differences `(S_a-S_b)/(c_a-c_b)` evaluated stably when `c_a\approx c_b`.

Viscoelasticity (paper eq. 1, 4, 5): the relaxation function
`g(t)=1-\sum_k g_k(1-e^{-t/\tau_k})` acts on the instantaneous hyperfoam stress
`S_0`, `S(t)=\int_0^t g(t-s)\,\dot S_0(s)\,ds`, integrated with the recursive update of
Simo (1987) that is exact when `S_0` is linear in time over a step.

Voigt order everywhere: ``[11, 22, 33, 12, 23, 13]``; strains carry engineering shears.
Units: MPa (N/mm^2), mm, s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from softhand.paper import paper
from softhand.validate import check_mapping, check_number, check_numbers, join, show

__all__ = [
    "CONSTANT_KEYS",
    "MATERIAL_NAMES",
    "Hyperfoam",
    "Material",
    "Prony",
    "ViscoState",
    "check_constants",
    "check_materials",
    "material",
    "phi1",
    "phi2",
    "voigt_to_tensor",
]

Moduli = Literal["long-term", "instantaneous"]
MATERIAL_NAMES = ("sil", "pu")
_VOIGT = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))
_PAIRS = ((0, 1), (1, 2), (0, 2))
_DD_SWITCH = 1e-6  # |l_a - l_b| below which a divided difference uses the midpoint derivative


def phi1(x: np.ndarray) -> np.ndarray:
    """Return (e^x - 1)/x, exact at x = 0 (value 1)."""
    x = np.asarray(x, dtype=float)
    small = np.abs(x) < 1e-8
    safe = np.where(small, 1.0, x)
    return np.where(small, 1.0 + 0.5 * x, np.expm1(safe) / safe)


def phi2(x: np.ndarray) -> np.ndarray:
    """Return (e^x - 1 - x)/x^2, exact at x = 0 (value 1/2), without cancellation."""
    x = np.asarray(x, dtype=float)
    small = np.abs(x) < 1e-3
    safe = np.where(small, 1.0, x)
    series = 0.5 + x / 6.0 + x * x / 24.0 + x**3 / 120.0
    return np.where(small, series, (np.expm1(safe) - safe) / (safe * safe))


def voigt_to_tensor(v: np.ndarray) -> np.ndarray:
    """Return symmetric (..., 3, 3) tensors from (..., 6) Voigt stress vectors."""
    v = np.asarray(v, dtype=float)
    t = np.empty(v.shape[:-1] + (3, 3))
    for k, (i, j) in enumerate(_VOIGT):
        t[..., i, j] = v[..., k]
        t[..., j, i] = v[..., k]
    return t


def _sym_voigt(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Voigt (stress form) of sym(a b^T) for stacks of vectors a, b of shape (n, 3)."""
    out = np.empty(a.shape[:-1] + (6,))
    for k, (i, j) in enumerate(_VOIGT):
        out[..., k] = 0.5 * (a[..., i] * b[..., j] + a[..., j] * b[..., i])
    return out


def _check_positive(name: str, values: tuple[float, ...]) -> None:
    for k, v in enumerate(values):
        if not np.isfinite(v) or v <= 0.0:
            raise ValueError(f"{name}[{k}] = {v!r} must be finite and > 0")


@dataclass(frozen=True)
class Hyperfoam:
    """Storakers hyperfoam energy with N terms and one Poisson ratio (paper eq. 2).

    Attributes:
        mu: shear moduli mu_i in MPa, each > 0. The initial shear modulus is sum(mu).
        alpha: exponents alpha_i, each non-zero (|alpha| >= 1e-12); tiny values are exact.
        nu: Poisson ratio in (-1, 0.5); beta = nu / (1 - 2 nu).
    """

    mu: tuple[float, ...]
    alpha: tuple[float, ...]
    nu: float

    def __post_init__(self) -> None:
        mu = tuple(float(m) for m in self.mu)
        alpha = tuple(float(a) for a in self.alpha)
        object.__setattr__(self, "mu", mu)
        object.__setattr__(self, "alpha", alpha)
        if len(mu) == 0 or len(mu) != len(alpha):
            raise ValueError(
                f"mu has {len(mu)} terms and alpha has {len(alpha)}: need the same number, >= 1"
            )
        _check_positive("mu (MPa)", mu)
        for k, a in enumerate(alpha):
            if not np.isfinite(a) or abs(a) < 1e-12:
                raise ValueError(
                    f"alpha[{k}] = {a!r} must be finite and non-zero (|alpha| >= 1e-12); "
                    "the alpha -> 0 limit is the Hencky energy, use a small value such as 1e-6"
                )
        if not (-1.0 < float(self.nu) < 0.5):
            raise ValueError(f"nu = {self.nu!r} is outside the allowed range (-1, 0.5)")

    @property
    def beta(self) -> float:
        """Compressibility coefficient beta = nu / (1 - 2 nu)."""
        return self.nu / (1.0 - 2.0 * self.nu)

    @property
    def shear_modulus(self) -> float:
        """Small-strain shear modulus sum(mu_i), MPa."""
        return float(sum(self.mu))

    @property
    def bulk_modulus(self) -> float:
        """Small-strain bulk modulus sum(2 mu_i (1/3 + beta)), MPa."""
        return float(sum(2.0 * m * (1.0 / 3.0 + self.beta) for m in self.mu))

    def scaled(self, factor: float) -> Hyperfoam:
        """Return the same law with every mu_i multiplied by ``factor`` (> 0)."""
        if not factor > 0.0:
            raise ValueError(f"factor = {factor!r} must be > 0")
        return Hyperfoam(tuple(m * factor for m in self.mu), self.alpha, self.nu)

    # --- principal (log-strain) functions -------------------------------------------------
    def _principal(self, l: np.ndarray):
        """Energy, principal Kirchhoff stress and its l-derivative for log strains (n, 3)."""
        L = l.sum(axis=-1)
        beta = self.beta
        W = np.zeros(l.shape[:-1])
        tau = np.zeros_like(l)
        dtau = np.zeros(l.shape + (3,))
        eye = np.eye(3)
        for m, a in zip(self.mu, self.alpha, strict=True):
            W += 2 * m * ((l * l * phi2(a * l)).sum(-1) + beta * L * L * phi2(-a * beta * L))
            vol = beta * L * phi1(-a * beta * L)
            tau += 2 * m * (l * phi1(a * l) + vol[..., None])
            dtau += 2 * m * (
                np.exp(a * l)[..., :, None] * eye + (beta * np.exp(-a * beta * L))[..., None, None]
            )
        return W, tau, dtau

    def _f(self, l: np.ndarray) -> np.ndarray:
        """Deviatoric-like part of tau: f(l) = sum 2 mu_i expm1(alpha_i l)/alpha_i."""
        return sum(2 * m * l * phi1(a * l) for m, a in zip(self.mu, self.alpha, strict=True))

    def _fprime(self, l: np.ndarray) -> np.ndarray:
        return sum(2 * m * np.exp(a * l) for m, a in zip(self.mu, self.alpha, strict=True))

    # --- public API --------------------------------------------------------------------------
    def energy(self, C: np.ndarray) -> np.ndarray:
        """Strain energy per reference volume (MPa = mJ/mm^3) for right Cauchy-Green C (..., 3, 3)."""
        c, _ = np.linalg.eigh(np.asarray(C, dtype=float))
        return self._principal(0.5 * np.log(c))[0]

    def principal_kirchhoff(self, stretches: np.ndarray) -> np.ndarray:
        """Principal Kirchhoff stresses tau_a (MPa) for principal stretches (..., 3)."""
        return self._principal(np.log(np.asarray(stretches, dtype=float)))[1]

    def stress(self, C: np.ndarray, *, tangent: bool = True):
        """Second Piola-Kirchhoff stress (Voigt, MPa) and tangent 2 dS/dC (Voigt 6x6, MPa).

        Args:
            C: right Cauchy-Green tensors, shape (n, 3, 3), symmetric positive definite.
            tangent: also return the tangent.

        Returns:
            ``S`` of shape (n, 6), and with ``tangent`` ``D`` of shape (n, 6, 6) such that
            dS = D dE with E the Green strain in Voigt form (engineering shears).
        """
        C = np.asarray(C, dtype=float)
        c, N = np.linalg.eigh(C)
        if np.any(c <= 0.0) or not np.all(np.isfinite(c)):
            bad = float(np.min(c)) if np.all(np.isfinite(c)) else float("nan")
            raise FloatingPointError(f"C is not positive definite (smallest eigenvalue {bad})")
        l = 0.5 * np.log(c)
        _, tau, dtau = self._principal(l)
        Sa = tau / c
        n_vec = [N[..., :, a] for a in range(3)]
        m = [_sym_voigt(v, v) for v in n_vec]
        S = sum(Sa[..., a, None] * m[a] for a in range(3))
        if not tangent:
            return S
        # diagonal part: 2 dS_a/dc_b = (1/c_a)(dtau_ab)(1/c_b) - 2 delta_ab tau_a / c_a^2
        dS = dtau / (c[..., :, None] * c[..., None, :]) - 2.0 * np.eye(3) * (tau / c**2)[..., None]
        D = np.zeros(C.shape[:-2] + (6, 6))
        for a in range(3):
            for b in range(3):
                D += dS[..., a, b, None, None] * (m[a][..., :, None] * m[b][..., None, :])
        # off-diagonal (rotation) part: 4 Gamma_ab p_ab p_ab^T with Gamma = (S_a-S_b)/(c_a-c_b)
        L = l.sum(-1)
        V = sum(2 * mu * self.beta * L * phi1(-al * self.beta * L)
                for mu, al in zip(self.mu, self.alpha, strict=True))
        for a, b in _PAIRS:
            gamma = self._gamma(l[..., a], l[..., b], V)
            p = _sym_voigt(n_vec[a], n_vec[b])
            D += 4.0 * gamma[..., None, None] * (p[..., :, None] * p[..., None, :])
        return S, D

    def _gamma(self, la: np.ndarray, lb: np.ndarray, V: np.ndarray) -> np.ndarray:
        """(S_a - S_b)/(c_a - c_b) without cancellation when c_a ~ c_b."""
        h = la - lb
        close = np.abs(h) < _DD_SWITCH
        hs = np.where(close, 1.0, h)
        mid = 0.5 * (la + lb)

        def q(x):
            return self._f(x) * np.exp(-2 * x)

        dq_mid = (self._fprime(mid) - 2.0 * self._f(mid)) * np.exp(-2 * mid)
        dd_q = np.where(close, dq_mid, (q(la) - q(lb)) / hs)
        dd_c = 2.0 * np.exp(2 * lb) * phi1(2 * h)
        dd_e = -2.0 * np.exp(-2 * lb) * phi1(-2 * h)
        return (dd_q + V * dd_e) / dd_c


@dataclass(frozen=True)
class Prony:
    """Prony relaxation function g(t) = 1 - sum g_k (1 - exp(-t/tau_k)) (paper eq. 5), the one
    relaxation function of softhand: it relaxes the FE stress here and the force of the skin
    laws (`softhand.laws.qlv`, where it is the normalised G(t) of quasi-linear
    viscoelasticity). ``Prony()`` is no relaxation.

    Attributes:
        g: relaxation ratios g_k, each >= 0, with sum(g) < 1.
        tau_s: relaxation times tau_k in seconds, each > 0, as many as ``g``.
    """

    g: tuple[float, ...] = ()
    tau_s: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        g = tuple(float(v) for v in self.g)
        tau = tuple(float(v) for v in self.tau_s)
        object.__setattr__(self, "g", g)
        object.__setattr__(self, "tau_s", tau)
        if len(g) != len(tau):
            raise ValueError(f"g has {len(g)} terms and tau_s has {len(tau)}: need the same number")
        for k, v in enumerate(g):
            if not np.isfinite(v) or v < 0.0:
                raise ValueError(f"g[{k}] = {v!r}: each g_i must be finite and >= 0")
        if sum(g) >= 1.0:
            raise ValueError(f"sum(g) = {sum(g)!r} must be < 1 (allowed range [0, 1))")
        for k, v in enumerate(tau):
            if not np.isfinite(v) or v <= 0.0:
                raise ValueError(f"tau_s[{k}] = {v!r}: each tau_i must be finite and > 0 s")

    @property
    def g_inf(self) -> float:
        """g(inf) = 1 - sum(g): long-term modulus over instantaneous modulus."""
        return 1.0 - sum(self.g)

    def relaxation(self, t: np.ndarray) -> np.ndarray:
        """Relaxation function g(t) for times t >= 0 (s)."""
        t = np.asarray(t, dtype=float)
        out = np.ones_like(t)
        for gk, tk in zip(self.g, self.tau_s, strict=True):
            out -= gk * -np.expm1(-t / tk)
        return out

    def step_factors(self, dt_s) -> tuple[np.ndarray, np.ndarray]:
        """The one hereditary recursion's coefficients over steps ``dt_s`` (scalar or array).

        For each term k and x = dt / tau_k: the decay e^{-x} and the ramp weight (1 - e^{-x}) / x
        (-> 1 as dt -> 0). A history h_k obeys h_k <- e^{-x} h_k + (1 - e^{-x}) / x * du for an
        input that changes by du linearly over the step: exact for piecewise-linear inputs
        (Simo's recursion; the FE stress update and the QLV force both use it).

        Returns:
            (decay, ramp), each of shape ``(n_terms, *shape(dt_s))``.
        """
        dt = np.asarray(dt_s, dtype=float)
        x = dt[None, ...] / np.asarray(self.tau_s, dtype=float).reshape((-1,) + (1,) * dt.ndim)
        return np.exp(-x), phi1(-x)

    def to_dict(self) -> dict:
        return {"g": list(self.g), "tau_s": list(self.tau_s), "g_inf": self.g_inf}

    @classmethod
    def from_dict(cls, d: Any, *, key: str = "prony") -> Prony:
        """Parse `to_dict` output, checking every value.

        Args:
            d: mapping with ``g`` (numbers in [0, 1), sum < 1), ``tau_s`` (as many numbers > 0)
                and optionally ``g_inf`` (must equal 1 - sum(g) within 1e-6).
            key: key path of ``d`` in messages.

        Raises:
            ValueError: ``"{key}.tau_s[0] = -1.0: expected a finite number > 0"`` and the like.
        """
        check_mapping(key, d, required=("g", "tau_s"), optional=("g_inf",))
        g = check_numbers(join(key, "g"), d["g"], lo=0.0, hi=1.0, hi_open=True)
        tau = check_numbers(join(key, "tau_s"), d["tau_s"], length=len(g), lo=0.0, lo_open=True,
                            why=f"(as many as {join(key, 'g')})")
        if sum(g) >= 1:
            raise ValueError(f"{join(key, 'g')} = {show(list(g))}: the sum {sum(g):.6g} must be "
                             "< 1 (g_inf > 0)")
        if "g_inf" in d:
            g_inf = check_number(join(key, "g_inf"), d["g_inf"], lo=0.0, hi=1.0, lo_open=True)
            if abs(g_inf - (1.0 - sum(g))) > 1e-6:
                raise ValueError(f"{join(key, 'g_inf')} = {show(d['g_inf'])}: expected "
                                 f"1 - sum(g) = {1.0 - sum(g):.9g}")
        return cls(g, tau)


@dataclass
class ViscoState:
    """History of the Prony integration at n material points.

    Attributes:
        S0: instantaneous hyperfoam stress at the last converged time, shape (n, 6).
        H: hereditary integrals per Prony term, shape (K, n, 6).
    """

    S0: np.ndarray
    H: np.ndarray

    @classmethod
    def zeros(cls, n: int, n_terms: int) -> ViscoState:
        return cls(np.zeros((n, 6)), np.zeros((n_terms, n, 6)))

    def copy(self) -> ViscoState:
        return ViscoState(self.S0.copy(), self.H.copy())


@dataclass(frozen=True)
class Material:
    """A skin material: instantaneous hyperfoam response plus optional Prony relaxation.

    ``hyperfoam`` always holds the *instantaneous* law (t = 0+); the long-term law is that times
    ``prony.g_inf``.
    """

    name: str
    hyperfoam: Hyperfoam
    prony: Prony | None = None
    moduli: str = field(default="instantaneous")

    @property
    def n_terms(self) -> int:
        return 0 if self.prony is None else len(self.prony.g)

    def elastic(self) -> Material:
        """The same material without relaxation, at its long-term (fully relaxed) stiffness."""
        if self.prony is None:
            return self
        return Material(self.name, self.hyperfoam.scaled(self.prony.g_inf), None,
                        "long-term")

    def update(self, C: np.ndarray, state: ViscoState | None, dt: float):
        """Stress and tangent at the end of a time step of length ``dt`` (s).

        Returns:
            ``(S, D, new_state)``: total stress (n, 6), consistent tangent (n, 6, 6) and the
            history to keep if the step is accepted (``None`` for an elastic material).
        """
        S0, D0 = self.hyperfoam.stress(C)
        if self.prony is None or state is None:
            return S0, D0, None
        if not dt >= 0.0:
            raise ValueError(f"dt = {dt!r} must be >= 0")
        dS0 = S0 - state.S0
        H = np.empty_like(state.H)
        S = S0.copy()
        factor = 1.0
        decay, gamma = self.prony.step_factors(dt)
        for k, gk in enumerate(self.prony.g):
            H[k] = decay[k] * state.H[k] + gamma[k] * dS0
            S -= gk * (S0 - H[k])
            factor -= gk * (1.0 - gamma[k])
        return S, factor * D0, ViscoState(S0, H)


CONSTANT_KEYS = ("nu", "mu_MPa", "alpha", "g", "tau_s")
NU_RANGE = (0.0, 0.5)  # open: the skins are compressible elastomers with a positive Poisson ratio
ALPHA_MIN = 1e-12  # smallest |alpha_i|; the alpha -> 0 limit is the Hencky energy


def check_constants(name: str, constants: Any, *, key: str | None = None) -> dict[str, Any]:
    """Table 3 row of ``name`` with user ``constants`` merged in, every value checked.

    Allowed (the law needs them to be a stable, relaxing solid):

    * ``nu``: a number in (0, 0.5) (the skins' 0.47-0.49; the hyperfoam law itself would take
      (-1, 0.5));
    * ``mu_MPa``: a list of N numbers > 0, N >= 1 (N = Table 3's 2, or the length of ``alpha``);
    * ``alpha``: a list of N finite non-zero numbers, ``|alpha_i| >= 1e-12``;
    * ``g``: a list of K numbers in [0, 1) with sum < 1 (K >= 0; K = Table 3's 3, or the length of
      ``tau_s``);
    * ``tau_s``: a list of K numbers > 0 (s).

    Args:
        name: ``sil`` or ``pu``.
        constants: a mapping of some of the keys above, or None.
        key: key path of ``constants`` in messages (default ``name``).

    Raises:
        ValueError: ``"{key}.{field} = {value}: expected ..."`` for the first bad value.
    """
    key = name if key is None else key
    if name not in MATERIAL_NAMES:
        raise ValueError(f"material {name!r} is unknown; allowed: {', '.join(MATERIAL_NAMES)}")
    row = {k: paper()["materials"][name][k] for k in CONSTANT_KEYS}
    if constants is None:
        return row
    check_mapping(key, constants, optional=CONSTANT_KEYS)
    given = dict(constants)
    if "nu" in given:
        row["nu"] = check_number(join(key, "nu"), given["nu"], lo=NU_RANGE[0], hi=NU_RANGE[1],
                                 lo_open=True, hi_open=True)
    for a, b, lo, lo_open, n_min in (("mu_MPa", "alpha", 0.0, True, 1), ("g", "tau_s", 0.0, False, 0),
                                     ("tau_s", "g", 0.0, True, 0), ("alpha", "mu_MPa", None, False, 1)):
        if a not in given:
            continue
        partner = given.get(b, row[b])
        n = len(partner) if isinstance(partner, (list, tuple)) else len(row[b])
        if n < n_min:
            n = None
        why = f"(as many as {join(key, b)})" if b in given else f"(as many as Table 3's {b})"
        hi = 1.0 if a == "g" else None
        row[a] = check_numbers(join(key, a), given[a], length=n, min_length=n_min, lo=lo, hi=hi,
                               lo_open=lo_open, hi_open=True, why=why)
    for k, v in enumerate(row["alpha"]):
        if abs(v) < ALPHA_MIN:
            raise ValueError(f"{join(key, 'alpha')}[{k}] = {v!r}: expected a finite non-zero "
                             f"number (|alpha| >= {ALPHA_MIN:g}); the alpha -> 0 limit is the "
                             "Hencky energy, use a small value such as 1e-6")
    if sum(row["g"]) >= 1.0:
        raise ValueError(f"{join(key, 'g')} = {show(list(row['g']))}: the sum {sum(row['g']):.6g} "
                         "must be < 1 (allowed range [0, 1): the long-term modulus stays > 0)")
    return row


def check_materials(data: Any, *, key: str = "") -> dict[str, dict[str, Any]]:
    """Check a whole ``--materials`` object: material name -> constants (see `check_constants`).

    Args:
        data: the parsed JSON; its top level must be an object keyed by ``sil`` and/or ``pu``.
        key: key path of ``data`` in messages (``""``: the file's top level).

    Returns:
        The constants as given, for `IndentationSettings`.

    Raises:
        ValueError: the first bad key or value, named.
    """
    check_mapping(key, data, optional=MATERIAL_NAMES)
    for name, constants in data.items():
        check_constants(name, constants, key=join(key, name))
    return dict(data)


def material(
    name: str,
    *,
    moduli: Moduli = "long-term",
    elastic_only: bool = False,
    constants: dict | None = None,
) -> Material:
    """Return a Table 3 material preset, or a material from user constants.

    Args:
        name: ``"sil"`` (silicone GLS 40) or ``"pu"`` (polyurethane Poly 74-45).
        moduli: how the mu_i are read: ``"long-term"`` (fully relaxed; instantaneous =
            mu / (1 - sum g)) or ``"instantaneous"`` (t = 0+).
        elastic_only: drop the Prony series and keep the law at the moduli as written.
        constants: replaces Table 3 for this material; keys ``nu``, ``mu_MPa``, ``alpha``,
            ``g``, ``tau_s`` (missing keys keep the Table 3 value); allowed values: see
            `check_constants`.

    Raises:
        ValueError: an unknown name or moduli, or a bad constant (``"sil.nu = 0.7: ..."``).
    """
    if name not in MATERIAL_NAMES:
        raise ValueError(f"material {name!r} is unknown; allowed: {', '.join(MATERIAL_NAMES)}")
    if moduli not in ("long-term", "instantaneous"):
        raise ValueError(f"moduli = {moduli!r} is not allowed; use 'long-term' or 'instantaneous'")
    row = check_constants(name, constants)
    law = Hyperfoam(tuple(row["mu_MPa"]), tuple(row["alpha"]), float(row["nu"]))
    if elastic_only:
        return Material(name, law, None, moduli)
    prony = Prony(tuple(row["g"]), tuple(row["tau_s"]))
    if moduli == "long-term":
        law = law.scaled(1.0 / prony.g_inf)
    return Material(name, law, prony, moduli)
