"""Verify the Storakers hyperfoam + Prony law against closed forms and finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from softhand.fem.materials import (
    Hyperfoam,
    Material,
    Prony,
    ViscoState,
    material,
    phi1,
    phi2,
    voigt_to_tensor,
)
from softhand.paper import paper

NAMES = ("sil", "pu")
LAMS = (0.6, 0.9, 1.1, 1.5)
LD = np.longdouble
_VOIGT = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))


def row(name: str) -> dict:
    return paper()["materials"][name]


def table_law(name: str) -> Hyperfoam:
    r = row(name)
    return Hyperfoam(tuple(r["mu_MPa"]), tuple(r["alpha"]), r["nu"])


def table_prony(name: str) -> Prony:
    return Prony(tuple(row(name)["g"]), tuple(row(name)["tau_s"]))


def rotation(seed: int = 7) -> np.ndarray:
    q, r = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def ref_parts(law: Hyperfoam, lams):
    lam = np.asarray(lams, dtype=LD)
    nu = LD(law.nu)
    return lam, lam.prod(), nu / (1 - 2 * nu)


def ref_cauchy(law: Hyperfoam, lams) -> np.ndarray:
    """Naive paper eq. 2 principal Cauchy stresses in 80-bit long double."""
    lam, J, beta = ref_parts(law, lams)
    s = np.zeros(3, dtype=LD)
    for m, a in zip(law.mu, law.alpha, strict=True):
        m, a = LD(m), LD(a)
        s += m / a * (lam**a - J ** (-a * beta))
    return 2 * s / J


def ref_energy(law: Hyperfoam, lams) -> LD:
    """Naive paper eq. 2 energy in 80-bit long double."""
    lam, J, beta = ref_parts(law, lams)
    u = LD(0)
    for m, a in zip(law.mu, law.alpha, strict=True):
        m, a = LD(m), LD(a)
        u += 2 * m / a**2 * ((lam**a).sum() - 3 + (J ** (-a * beta) - 1) / beta)
    return u


def code_cauchy(law: Hyperfoam, F: np.ndarray) -> np.ndarray:
    S = voigt_to_tensor(law.stress((F.T @ F)[None], tangent=False))[0]
    return F @ S @ F.T / np.linalg.det(F)


def strain_to_c(E: np.ndarray) -> np.ndarray:
    """C = I + 2E for a Voigt strain with engineering shears."""
    Et = np.zeros((3, 3))
    for k, (i, j) in enumerate(_VOIGT):
        Et[i, j] = Et[j, i] = E[k] if i == j else 0.5 * E[k]
    return np.eye(3) + 2.0 * Et


def green_voigt(F: np.ndarray) -> np.ndarray:
    Et = 0.5 * (F.T @ F - np.eye(3))
    return np.array([Et[i, j] * (1.0 if i == j else 2.0) for i, j in _VOIGT])


STRETCHES = {
    "uniaxial": lambda lam: (lam, 1.0, 1.0),
    "equibiaxial": lambda lam: (lam, lam, 1.0),
    "hydrostatic": lambda lam: (lam, lam, lam),
}


# --- 1. closed-form homogeneous responses ---------------------------------------------------
@pytest.mark.parametrize("rotated", [False, True])
@pytest.mark.parametrize("lam", LAMS)
@pytest.mark.parametrize("mode", sorted(STRETCHES))
@pytest.mark.parametrize("name", NAMES)
def test_cauchy_closed_form(name, mode, lam, rotated):
    """Cauchy stress equals (2/J) sum mu_i/alpha_i (lam_a^alpha_i - J^-alpha_i beta), rel < 1e-8."""
    law, lams = table_law(name), STRETCHES[mode](lam)
    ref = ref_cauchy(law, lams)
    R = rotation() if rotated else np.eye(3)
    F = R @ np.diag(lams) @ R.T  # rotated principal axes: exercises the eigenvector path
    sig = code_cauchy(law, F)
    expect = R @ np.diag(ref.astype(float)) @ R.T
    if not rotated:
        assert np.all(np.abs(np.diag(sig) - ref) <= 1e-8 * np.abs(ref))
    assert np.max(np.abs(sig - expect)) <= 1e-8 * np.max(np.abs(ref))
    # a rigid rotation on the left rotates sigma and leaves S unchanged
    Q = rotation(11)
    np.testing.assert_allclose(
        code_cauchy(law, Q @ F), Q @ sig @ Q.T, rtol=0, atol=1e-12 * np.max(np.abs(sig))
    )


@pytest.mark.parametrize("lam", LAMS)
@pytest.mark.parametrize("name", NAMES)
def test_uniaxial_stress(name, lam):
    """Uniaxial stress: code |s22|,|s33| < 1e-10 s11 and s11 = closed form, rel < 1e-8."""
    law = table_law(name)
    mu_lat = brentq(
        lambda x: float(ref_cauchy(law, (lam, x, x))[1]), 0.5, 2.0, xtol=1e-15, rtol=1e-15
    )
    ref = ref_cauchy(law, (lam, mu_lat, mu_lat))
    sig = code_cauchy(law, np.diag([lam, mu_lat, mu_lat]))
    assert abs(sig[0, 0] - ref[0]) <= 1e-8 * abs(ref[0])
    assert max(abs(sig[1, 1]), abs(sig[2, 2])) < 1e-10 * abs(sig[0, 0])
    assert (lam - 1.0) * (mu_lat - 1.0) < 0.0  # lateral contraction under tension and vice versa


# --- 2. energy --------------------------------------------------------------------------------
ENERGY_LAMS = [(0.6, 1, 1), (0.9, 0.9, 1), (1.5, 1.5, 1.5), (1.1, 0.8, 1.3), (0.7, 1.2, 0.95)]


@pytest.mark.parametrize("lams", [*ENERGY_LAMS, (0.9, 0.9, 0.9)])
@pytest.mark.parametrize("name", NAMES)
def test_energy_closed_form(name, lams):
    """U equals the naive paper eq. 2 energy evaluated in long double, rel < 1e-8."""
    law = table_law(name)
    ref = ref_energy(law, lams)
    R = rotation(3)
    U = law.energy((R @ np.diag(np.square(lams)) @ R.T)[None])[0]
    assert ref > 0 and abs(U - ref) <= 1e-8 * ref


# --- 3. small-alpha (Hencky) limit ------------------------------------------------------------
@pytest.mark.parametrize("nu", [0.3, row("sil")["nu"], row("pu")["nu"]])
def test_small_alpha_hencky_limit(nu):
    """alpha->0 gives mu(sum l^2 + beta L^2): rel <= alpha*|l|max*max(2, beta), < 1e-8 at 1e-9."""
    mu, l = 0.1, np.array([0.2, -0.1, 0.05])
    beta, L = nu / (1 - 2 * nu), l.sum()
    hencky = mu * (np.sum(l**2) + beta * L**2)
    first = (np.sum(l**3) - beta**2 * L**3) / (3 * (np.sum(l**2) + beta * L**2))
    C = np.diag(np.exp(2 * l))[None]
    for alpha in (1e-3, 1e-6, 1e-9):
        rel = abs(Hyperfoam((mu,), (alpha,), nu).energy(C)[0] - hencky) / hencky
        assert rel <= alpha * np.max(np.abs(l)) * max(2.0, beta)
        assert rel / alpha == pytest.approx(abs(first), rel=1e-2)  # linear in alpha
    assert rel < 1e-8
    lam = np.exp(l)
    alpha = 1e-9
    bracket = np.sum(lam**alpha) - 3 + (lam.prod() ** (-alpha * beta) - 1) / beta
    naive = 2 * mu / alpha**2 * bracket
    assert abs(naive - hencky) / hencky > 0.1  # why the cancellation-free form exists


# --- 4. derivatives vs finite differences ------------------------------------------------------
def _points():
    rng = np.random.default_rng(2024)
    pts = [np.eye(3) + 0.15 * rng.standard_normal((3, 3)) for _ in range(3)]
    return [*pts, np.eye(3), np.diag([0.8, 1.0, 1.0]), 0.9 * np.eye(3)]


@pytest.mark.parametrize("k", range(6), ids=["rnd0", "rnd1", "rnd2", "I", "uni0.8", "hyd0.9"])
@pytest.mark.parametrize("name", NAMES)
def test_fd_stress_and_tangent(name, k):
    """S = dU/dE and D = dS/dE by central FD (h=1e-6) to 1e-6 rel; D symmetric to 1e-10 rel."""
    law, h = table_law(name), 1e-6
    E0 = green_voigt(_points()[k])
    S, D = (a[0] for a in law.stress(strain_to_c(E0)[None]))
    Sfd, Dfd = np.empty(6), np.empty((6, 6))
    for j in range(6):
        Cp, Cm = (strain_to_c(E0 + s * h * np.eye(6)[j])[None] for s in (1, -1))
        Sfd[j] = (law.energy(Cp)[0] - law.energy(Cm)[0]) / (2 * h)
        Dfd[:, j] = (law.stress(Cp, tangent=False)[0] - law.stress(Cm, tangent=False)[0]) / (2 * h)
    assert np.max(np.abs(Sfd - S)) <= 1e-6 * max(np.max(np.abs(S)), law.shear_modulus)
    assert np.max(np.abs(Dfd - D)) <= 1e-6 * np.max(np.abs(D))
    assert np.max(np.abs(D - D.T)) <= 1e-10 * np.max(np.abs(D))


@pytest.mark.parametrize("name", NAMES)
def test_divided_difference_near_coincident(name):
    """For diagonal C, D[3,3] = (S1-S2)/(c1-c2) (long-double reference) across gaps, rel < 1e-8."""
    law = table_law(name)
    for gap in (1e-8, 5e-7, 1.5e-6, 1e-4, 1e-2, 0.3):
        lams = np.array([0.9, 0.9 * np.exp(gap), 1.1])
        S = ref_cauchy(law, lams) * np.prod(lams.astype(LD)) / lams.astype(LD) ** 2
        ref = (S[0] - S[1]) / (LD(lams[0]) ** 2 - LD(lams[1]) ** 2)
        D33 = law.stress(np.diag(lams**2)[None])[1][0, 3, 3]
        assert abs(D33 - ref) <= 1e-8 * abs(ref), gap


def test_phi_functions():
    """phi1 = (e^x-1)/x, phi2 = (e^x-1-x)/x^2 match a long-double series/closed form, rel 1e-12."""
    x = np.concatenate([[0.0], np.geomspace(1e-12, 30, 80), -np.geomspace(1e-12, 30, 80)])
    xl = x.astype(LD)
    k = np.arange(40)
    fact = np.cumprod(np.concatenate([[1], np.arange(1, 43)]).astype(LD))
    series1 = np.sum(xl[:, None] ** k / fact[k + 1], axis=1)
    series2 = np.sum(xl[:, None] ** k / fact[k + 2], axis=1)
    big = np.abs(x) > 0.5
    xs = np.where(big, xl, LD(1))
    ref1 = np.where(big, np.expm1(xs) / xs, series1)
    ref2 = np.where(big, (np.expm1(xs) - xs) / xs**2, series2)
    np.testing.assert_allclose(phi1(x), ref1.astype(float), rtol=1e-12, atol=0)
    np.testing.assert_allclose(phi2(x), ref2.astype(float), rtol=1e-12, atol=0)


# --- 5. small-strain limit --------------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_small_strain_limit(name):
    """At F=I, D is isotropic linear elasticity with mu0=sum mu, K0=sum 2mu(1/3+beta), rel 1e-10."""
    law, r = table_law(name), row(name)
    beta = r["nu"] / (1 - 2 * r["nu"])
    mu0 = sum(r["mu_MPa"])
    K0 = sum(2 * m * (1 / 3 + beta) for m in r["mu_MPa"])
    lame = K0 - 2 / 3 * mu0
    Dref = np.zeros((6, 6))
    Dref[:3, :3] = lame
    Dref += np.diag([2 * mu0] * 3 + [mu0] * 3)
    S, D = law.stress(np.eye(3)[None])
    assert np.all(S == 0.0)
    assert np.max(np.abs(D[0] - Dref)) <= 1e-10 * np.max(np.abs(Dref))
    assert law.shear_modulus == pytest.approx(mu0, rel=1e-14)
    assert law.bulk_modulus == pytest.approx(K0, rel=1e-14)
    E0 = 9 * K0 * mu0 / (3 * K0 + mu0)
    assert abs(E0 / (2 * mu0) - 1 - r["nu"]) < 1e-12


# --- 6. Prony relaxation ----------------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_relaxation_function(name):
    """g(t) = 1 - sum g_k (1 - exp(-t/tau_k)) to rel 1e-12; g(0)=1, g(inf)=1-sum g."""
    pr, r = table_prony(name), row(name)
    t = np.concatenate([[0.0], np.geomspace(1e-4, 1e4, 41), r["tau_s"]])
    ref = np.ones_like(t, dtype=LD)
    for gk, tk in zip(r["g"], r["tau_s"], strict=True):
        ref -= LD(gk) * (1 - np.exp(-t.astype(LD) / LD(tk)))
    np.testing.assert_allclose(pr.relaxation(t), ref.astype(float), rtol=1e-12, atol=0)
    assert pr.relaxation(np.array(0.0)) == 1.0
    assert pr.relaxation(np.array(1e12)) == pytest.approx(1 - sum(r["g"]), rel=1e-15)
    assert pr.g_inf == pytest.approx(1 - sum(r["g"]), rel=1e-15)


C_UNI = np.diag([0.81, 1.0, 1.0])[None]  # uniaxial lam = 0.9


@pytest.mark.parametrize("moduli", ["long-term", "instantaneous"])
@pytest.mark.parametrize("name", NAMES)
def test_step_strain_relaxes_exactly(name, moduli):
    """Held step strain: S(t) = g(t) S0 at every step (geometric and one huge dt), rel 1e-12."""
    mat = material(name, moduli=moduli)
    taus, default = row(name)["tau_s"], material(name)
    assert default.moduli == "long-term" and default == material(name, moduli="long-term")
    S0, D0, state = mat.update(C_UNI, ViscoState.zeros(1, mat.n_terms), 0.0)
    assert np.array_equal(S0, mat.hyperfoam.stress(C_UNI, tangent=False))
    np.testing.assert_array_equal(D0, mat.hyperfoam.stress(C_UNI)[1])
    times = np.concatenate(
        [np.geomspace(1e-3 * min(taus), 5 * max(taus), 30), [5 * max(taus) + 1e3 * max(taus)]]
    )
    t_prev = 0.0
    for t in times:
        S, _, state = mat.update(C_UNI, state, t - t_prev)
        t_prev = t
        np.testing.assert_allclose(
            S, mat.prony.relaxation(t) * S0, rtol=1e-12, atol=1e-12 * np.max(np.abs(S0))
        )


@pytest.mark.parametrize("name", NAMES)
def test_moduli_interpretation(name):
    """long-term relaxes to the Table 3 law (rel 1e-6 at 50 max tau); instantaneous is it at 0+."""
    table = table_law(name)
    S_tab = table.stress(C_UNI, tangent=False)
    long = material(name, moduli="long-term")
    _, _, st = long.update(C_UNI, ViscoState.zeros(1, long.n_terms), 0.0)
    S_inf, _, _ = long.update(C_UNI, st, 50 * max(row(name)["tau_s"]))
    np.testing.assert_allclose(S_inf, S_tab, rtol=1e-6, atol=1e-6 * np.max(np.abs(S_tab)))
    np.testing.assert_allclose(
        long.hyperfoam.mu, np.array(table.mu) / long.prony.g_inf, rtol=1e-15
    )
    np.testing.assert_allclose(long.elastic().hyperfoam.mu, table.mu, rtol=1e-15)
    inst = material(name, moduli="instantaneous")
    S_0, D_0, _ = inst.update(C_UNI, ViscoState.zeros(1, inst.n_terms), 0.0)
    np.testing.assert_array_equal(S_0, S_tab)
    np.testing.assert_array_equal(D_0, table.stress(C_UNI)[1])
    assert isinstance(long, Material) and long.prony == table_prony(name)
    assert material(name, elastic_only=True).prony is None
    assert material(name, elastic_only=True).hyperfoam == table


# --- 7. ramp vs convolution integral and consistent tangent -----------------------------------
@pytest.mark.parametrize("name", NAMES)
@pytest.mark.slow
def test_ramp_matches_convolution(name):
    """Ramp-hold E11 to 1e-4: S = int g(t-s) dS0/ds ds (quad) rel 1e-3; D = dS/dE by FD rel 1e-6."""
    mat = material(name, moduli="long-term")
    law, pr = mat.hyperfoam, mat.prony
    T, eps, n = 2 * max(pr.tau_s), 1e-4, 100
    rate = np.array([eps / T, 0, 0, 0, 0, 0])

    def c_at(s):
        return strain_to_c(rate * min(s, T))[None]

    def conv(t, j):
        f = lambda s: pr.relaxation(t - s) * (law.stress(c_at(s))[1][0] @ rate)[j]  # noqa: E731
        return quad(f, 0.0, min(t, T), epsabs=0, epsrel=1e-10, limit=200)[0]

    state, times = ViscoState.zeros(1, mat.n_terms), np.linspace(0, 2 * T, 2 * n + 1)
    for k in range(1, len(times)):
        prev, (S, D, state) = state, mat.update(c_at(times[k]), state, times[k] - times[k - 1])
        if k % 25 == 0:
            for j in (0, 1):
                assert S[0, j] == pytest.approx(conv(times[k], j), rel=1e-3)
        if k == n // 2:  # consistent tangent of one step, by FD on the strain
            dt, E, h = times[k] - times[k - 1], rate * times[k], 1e-6
            Dfd = np.empty((6, 6))
            for j in range(6):
                Sp, Sm = (
                    mat.update(strain_to_c(E + s * h * np.eye(6)[j])[None], prev, dt)[0][0]
                    for s in (1, -1)
                )
                Dfd[:, j] = (Sp - Sm) / (2 * h)
            assert np.max(np.abs(Dfd - D[0])) <= 1e-6 * np.max(np.abs(D[0]))
            x = dt / np.array(pr.tau_s)
            factor = 1 - np.sum(np.array(pr.g) * (1 - (1 - np.exp(-x)) / x))
            D0 = law.stress(c_at(times[k]))[1][0]
            assert np.max(np.abs(D[0] - factor * D0)) <= 1e-12 * np.max(np.abs(D0))
            assert factor < 1.0


# --- 8. bad input -----------------------------------------------------------------------------
BAD = [
    ("nu0.5", lambda: Hyperfoam((0.1,), (2.0,), 0.5), "0.5"),
    ("nu-1", lambda: Hyperfoam((0.1,), (2.0,), -1.0), "-1.0"),
    ("nu0.7", lambda: Hyperfoam((0.1,), (2.0,), 0.7), "0.7"),
    ("mu0", lambda: Hyperfoam((0.0,), (2.0,), 0.3), "0.0"),
    ("mu-0.1", lambda: Hyperfoam((0.1, -0.1), (2.0, 3.0), 0.3), "-0.1"),
    ("alpha0", lambda: Hyperfoam((0.1,), (0.0,), 0.3), "0.0"),
    ("len", lambda: Hyperfoam((0.1, 0.2), (2.0,), 0.3), "2 terms"),
    ("sumg1", lambda: Prony((0.5, 0.5), (1.0, 2.0)), "1.0"),
    ("sumg1.2", lambda: Prony((0.6, 0.6), (1.0, 2.0)), "1.2"),
    ("tau0", lambda: Prony((0.1,), (0.0,)), "0.0"),
    ("tau-1", lambda: Prony((0.1,), (-1.0,)), "-1.0"),
    ("g-neg", lambda: Prony((0.2, -0.1), (1.0, 2.0)), "-0.1"),
    ("prony-len", lambda: Prony((0.1, 0.2), (1.0,)), "2 terms"),
    ("steel", lambda: material("steel"), "steel"),
    ("bogus", lambda: material("sil", moduli="bogus"), "bogus"),
    ("dt", lambda: material("pu").update(C_UNI, ViscoState.zeros(1, 3), -1.0), "-1.0"),
]


@pytest.mark.parametrize(("make", "value"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input_raises(make, value):
    """Invalid parameters raise ValueError whose message names the offending value."""
    with pytest.raises(ValueError) as info:
        make()
    assert value in str(info.value)
