r"""The material library of the design search: the paper's SIL and PU, and softer casting silicones.

Every entry lives in ``softhand/data/materials.json`` with the source of each number. Table 3's
SIL and PU take their constants from ``paper.json`` (`softhand.fem.materials.material`). The
Smooth-On silicones have no published compressible hyperelastic constants that this project could
read; their datasheets give two uniaxial tension points, the 100 % modulus ``M100`` (nominal
stress at stretch 2) and the tensile strength ``TS`` at the elongation at break (stretch
``lambda_b``). A one-term Storakers hyperfoam (paper eq. 2, N = 1) at the assumed Poisson ratio
is fitted through both (`fit_datasheet`):

    P(\lambda) = \tau_1(\lambda, \lambda_t, \lambda_t) / \lambda,\qquad
    \tau_2(\lambda, \lambda_t, \lambda_t) = 0,

with `\tau_a` the principal Kirchhoff stresses of `softhand.fem.materials.Hyperfoam` and
`\lambda_t` the free lateral stretch; ``P(2) = M100`` and ``P(lambda_b) = TS`` fix ``mu`` and
``alpha``. The small-strain shear modulus is then ``mu`` (sum of the mu_i). Named assumptions:
the one-term form, nu = 0.49, the paper's SIL Prony series; the indentation compresses the skin,
so its response there is an extrapolation of a fit to tension.

Before the search uses a material, `compression_check` runs it through the FE's homogeneous
test (the patch test of ``tests/test_fem_assembly.py``): a block of distorted quadratic elements
with the homogeneous uniaxial-stress compression prescribed on its boundary must return that
deformation inside and the closed-form stress at every Gauss point.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from typing import Any

import numpy as np
from scipy.optimize import brentq

from softhand.fem.materials import CONSTANT_KEYS, Hyperfoam, Material, material
from softhand.paper import paper

__all__ = ["LibraryMaterial", "check_library_names", "compression_check", "fit_datasheet",
           "library", "library_material", "uniaxial_nominal_stress"]

PSI_MPA = 0.00689476
PLI_N_MM = 0.175127


def _data() -> dict[str, Any]:
    text = resources.files("softhand").joinpath("data/materials.json").read_text(encoding="utf-8")
    return json.loads(text)


@dataclass(frozen=True)
class LibraryMaterial:
    """One library entry: FE constants and what durability needs, each with its source.

    Attributes:
        name: library key (``sil``, ``ecoflex-00-30``, ...).
        product: maker and product.
        shore: Shore hardness as the maker states it (``00-30``, ``A 10``).
        constants: the FE constants (``nu``, ``mu_MPa``, ``alpha``, ``g``, ``tau_s``), the
            format of `softhand.fem.materials.check_constants`.
        elongation_at_break_pct: engineering strain at break (%), None where none was found.
        tensile_strength_MPa: nominal stress at break, None where none was found.
        modulus_100_MPa: nominal stress at 100 % strain, None where none was found.
        tear_strength_N_mm: ASTM D624 die B tear strength, None where none was found.
        sources: per item (``hyperelastic``, ``test_mode``, ``nu``, ``prony``, ``datasheet``) its
            source or the named assumption.
    """

    name: str
    product: str
    shore: str
    constants: dict[str, Any]
    elongation_at_break_pct: float | None
    tensile_strength_MPa: float | None
    modulus_100_MPa: float | None
    tear_strength_N_mm: float | None
    sources: dict[str, str]

    @property
    def hyperfoam(self) -> Hyperfoam:
        c = self.constants
        return Hyperfoam(tuple(c["mu_MPa"]), tuple(c["alpha"]), float(c["nu"]))

    @property
    def shear_modulus_MPa(self) -> float:  # noqa: N802  (the unit, as in the fields)
        """Small-strain shear modulus sum(mu_i), MPa (as the constants are written)."""
        return self.hyperfoam.shear_modulus

    def material(self, *, moduli: str = "long-term", elastic_only: bool = False) -> Material:
        """The FE material (`softhand.fem.materials.material` with these constants)."""
        slot = "sil"  # any Table 3 slot: every constant is replaced
        return material(slot, moduli=moduli, elastic_only=elastic_only,
                        constants=self.constants)


def _entry(name: str, raw: dict[str, Any]) -> LibraryMaterial:
    if raw["constants"] == "table3":
        row = paper()["materials"][name]
        constants = {k: list(row[k]) if isinstance(row[k], list) else row[k]
                     for k in CONSTANT_KEYS}
        sheet: dict[str, Any] = {}
        elong, ts, m100, tear = (raw.get("elongation_at_break_pct"),
                                 raw.get("tensile_strength_MPa"), None,
                                 raw.get("tear_strength_N_mm"))
        datasheet = raw.get("strength_source", "")
    else:
        c = raw["constants"]
        prony = paper()["materials"][c["prony_from"]]
        constants = {"nu": c["nu"], "mu_MPa": list(c["mu_MPa"]), "alpha": list(c["alpha"]),
                     "g": list(prony["g"]), "tau_s": list(prony["tau_s"])}
        sheet = raw["datasheet"]
        elong = float(sheet["elongation_at_break_pct"])
        ts = sheet["tensile_strength_psi"] * PSI_MPA
        m100 = sheet["modulus_100_psi"] * PSI_MPA
        tear = sheet["tear_strength_pli"] * PLI_N_MM
        datasheet = raw["datasheet_source"].replace("; see _datasheet_reading", "")
        datasheet += ". " + _data()["_datasheet_reading"]
    return LibraryMaterial(
        name=name, product=raw["product"], shore=raw["shore"], constants=constants,
        elongation_at_break_pct=elong, tensile_strength_MPa=ts, modulus_100_MPa=m100,
        tear_strength_N_mm=tear,
        sources={"hyperelastic": raw["hyperelastic_source"], "test_mode": raw["test_mode"],
                 "nu": raw["nu_source"], "prony": raw["prony_source"], "datasheet": datasheet})


@lru_cache(maxsize=1)
def library() -> dict[str, LibraryMaterial]:
    """Every library material by name, in the data file's order (cached)."""
    return {name: _entry(name, raw) for name, raw in _data()["materials"].items()}


def check_library_names(names, *, key: str = "materials") -> list[str]:
    """``names`` as library names, each checked.

    Raises:
        ValueError: ``"{key}: 'x' is unknown; allowed: sil, pu, ..."`` for the first unknown.
    """
    known = library()
    out = []
    for n in names:
        if not isinstance(n, str) or n.strip() not in known:
            raise ValueError(f"{key}: material {n!r} is unknown; allowed: {', '.join(known)}")
        out.append(n.strip())
    return out


def library_material(name: str) -> LibraryMaterial:
    """The library entry ``name``; ValueError listing the allowed names otherwise."""
    (checked,) = check_library_names([name], key="material")
    return library()[checked]


# --- uniaxial tension and the datasheet fit --------------------------------------------------
def _lateral_stretch(law: Hyperfoam, stretch: float) -> float:
    """Free lateral stretch of a uniaxial-stress state (tau_2 = tau_3 = 0)."""
    def lateral(x: float) -> float:
        return float(law.principal_kirchhoff(np.array([stretch, x, x]))[1])

    guess = stretch ** -0.5  # the incompressible answer; nu < 0.5 keeps it within 2x
    with np.errstate(over="ignore"):
        return brentq(lateral, 0.5 * guess, 2.0 * guess, xtol=1e-14, rtol=1e-14)


def uniaxial_nominal_stress(law: Hyperfoam, stretch: float) -> float:
    """Nominal (engineering) stress, MPa, at axial ``stretch`` in uniaxial stress."""
    x = _lateral_stretch(law, stretch)
    return float(law.principal_kirchhoff(np.array([stretch, x, x]))[0]) / stretch


def fit_datasheet(modulus_100_MPa: float, tensile_strength_MPa: float,
                  elongation_at_break_pct: float, nu: float) -> tuple[float, float]:
    """``(mu, alpha)`` of a one-term Storakers hyperfoam through two tension points.

    ``P(2) = modulus_100_MPa`` and ``P(1 + elongation/100) = tensile_strength_MPa`` (uniaxial
    nominal stress, `uniaxial_nominal_stress`). P scales with mu, so alpha solves the ratio
    ``P(lambda_b) / P(2)`` (which rises with alpha) and mu follows.

    Raises:
        ValueError: a value out of range, or a ratio no alpha in [0.05, 12] reaches.
    """
    for key, v in (("modulus_100_MPa", modulus_100_MPa),
                   ("tensile_strength_MPa", tensile_strength_MPa)):
        if not np.isfinite(v) or v <= 0:
            raise ValueError(f"{key} = {v!r}: expected a finite number > 0")
    if not np.isfinite(elongation_at_break_pct) or elongation_at_break_pct <= 100:
        raise ValueError(f"elongation_at_break_pct = {elongation_at_break_pct!r}: expected a "
                         "number > 100 (the second point lies beyond the 100 % modulus)")
    lam_b = 1.0 + elongation_at_break_pct / 100.0
    target = tensile_strength_MPa / modulus_100_MPa

    def ratio(alpha: float) -> float:
        law = Hyperfoam((1.0,), (alpha,), nu)
        return uniaxial_nominal_stress(law, lam_b) / uniaxial_nominal_stress(law, 2.0) - target

    lo, hi = 0.05, 12.0
    if ratio(lo) * ratio(hi) > 0:
        raise ValueError(f"tensile_strength_MPa / modulus_100_MPa = {target:.4g}: no one-term "
                         f"alpha in [{lo}, {hi}] gives it at stretch {lam_b:g}")
    alpha = brentq(ratio, lo, hi, xtol=1e-12)
    mu = modulus_100_MPa / uniaxial_nominal_stress(Hyperfoam((1.0,), (alpha,), nu), 2.0)
    return float(mu), float(alpha)


# --- the FE's homogeneous compression check ---------------------------------------------------
@dataclass(frozen=True)
class CompressionCheck:
    """The homogeneous compression check of one material.

    Attributes:
        name: the material.
        stretch: axial stretch of the uniaxial-stress compression (< 1).
        lateral_stretch: the closed form's free lateral stretch.
        axial_stress_MPa: closed-form Cauchy stress along the axis (negative: compression).
        displacement_error_mm: largest |u_FE - u_exact| at the free (interior) nodes.
        stress_error: largest |S_FE - S_exact| over the Gauss points / max |S_exact|.
        lateral_stress_ratio: largest |sigma_lateral| / |sigma_axial| of the FE stress.
        passed: every error within its tolerance (1e-8 mm, 1e-8, 1e-8).
    """

    name: str
    stretch: float
    lateral_stretch: float
    axial_stress_MPa: float
    displacement_error_mm: float
    stress_error: float
    lateral_stress_ratio: float
    passed: bool


def _patch_block(n: int = 2, seed: int = 0):
    """n^3 quadratic elements on the unit cube, interior nodes moved at random (the patch test's
    block, as in ``tests/test_fem_assembly.py``)."""
    from softhand.fem.elements import reference_element
    from softhand.fem.mesh import Mesh

    dim, m = 3, 2 * n + 1
    axes = [np.linspace(0.0, 1.0, m)] * dim
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    ids = np.arange(m**dim).reshape((m,) * dim)
    interior = np.all((grid > 1e-12) & (grid < 1 - 1e-12), axis=1)
    grid[interior] += np.random.default_rng(seed).uniform(-0.06, 0.06,
                                                          size=(interior.sum(), dim))
    elems = []
    for e in np.ndindex(*(n,) * dim):
        elems.append([ids[tuple(2 * e[k] + p[::-1][k] for k in range(dim))]
                      for p in np.ndindex(*(3,) * dim)])
    boundary = np.flatnonzero(~interior)
    empty = np.zeros((0, 9), dtype=int)
    return Mesh(dim=dim, X=grid, elements=np.array(elems), layer=np.zeros(len(elems), int),
                ref=reference_element(dim), fixed=(boundary[:, None] * dim + np.arange(dim)).ravel(),
                outer_faces=empty, roof_faces=empty, floor_faces=empty, symmetry_factor=1.0,
                length_mm=1.0)


def compression_check(name: str, stretch: float = 0.7) -> CompressionCheck:
    """Run library material ``name`` through the FE's homogeneous uniaxial compression.

    Args:
        name: a library material.
        stretch: axial stretch in (0.3, 1) (0.7: 30 % compression, deeper than a 2 N
            indentation strains the skin on average).

    Raises:
        ValueError: an unknown name or a stretch outside (0.3, 1).
    """
    import scipy.sparse.linalg as spla

    from softhand.fem.assembly import Assembler

    entry = library_material(name)
    if not 0.3 < stretch < 1.0:
        raise ValueError(f"stretch = {stretch!r}: allowed range (0.3, 1) (a compression)")
    law = entry.hyperfoam
    mat = entry.material(elastic_only=True)
    lat = _lateral_stretch(law, stretch)
    Fh = np.diag([lat, stretch, lat])  # compression along y, the indentation's axis
    mesh = _patch_block()
    asm = Assembler(mesh, [mat], threads=1, engine="numpy")
    exact = (mesh.X @ (Fh - np.eye(3)).T).ravel()
    free = np.setdiff1d(np.arange(mesh.n_dofs), mesh.fixed)
    u = exact.copy()
    u[free] += 1e-4 * np.random.default_rng(3).standard_normal(free.size)
    state = asm.initial_state()
    for _ in range(30):
        f, K, _ = asm.assemble(u, state, 0.0)
        if np.abs(f[free]).max() < 1e-13:
            break
        u[free] -= spla.spsolve(K[free][:, free].tocsc(), f[free])
    asm.close()
    C = Fh.T @ Fh
    S_exact = law.stress(C[None], tangent=False)[0]
    F = asm.deformation_gradient(u).reshape(-1, 3, 3)
    S = law.stress(np.einsum("nki,nkj->nij", F, F), tangent=False)
    # Cauchy stress of the FE state: sigma = F S F^T / J (Voigt [11, 22, 33, 12, 23, 13])
    idx = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))
    St = np.zeros((len(S), 3, 3))
    for k, (i, j) in enumerate(idx):
        St[:, i, j] = St[:, j, i] = S[:, k]
    sig = np.einsum("nij,njk,nlk->nil", F, St, F) / np.linalg.det(F)[:, None, None]
    axial = float(np.abs(sig[:, 1, 1]).max())
    du = float(np.abs(u - exact).max())
    dS = float(np.abs(S - S_exact).max() / np.abs(S_exact).max())
    lateral = float(max(np.abs(sig[:, 0, 0]).max(), np.abs(sig[:, 2, 2]).max()) / axial)
    sigma_exact = float(law.principal_kirchhoff(np.array([lat, stretch, lat]))[1]
                        / (stretch * lat * lat))
    return CompressionCheck(name=name, stretch=stretch, lateral_stretch=lat,
                            axial_stress_MPa=sigma_exact, displacement_error_mm=du,
                            stress_error=dS, lateral_stress_ratio=lateral,
                            passed=du < 1e-8 and dS < 1e-8 and lateral < 1e-8)
