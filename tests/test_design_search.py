"""The design search (issue 38): the material library, the design space, objectives, search, STL.

Library: Table 3's entries are the paper's constants; each datasheet fit reproduces the datasheet's
two tension points (100 % modulus, tensile strength at break); the hyperfoam's small-strain shear
modulus is the sum of its mu_i; every material passes the FE's homogeneous compression check.
"""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from softhand.cli import main
from softhand.fem.library import (
    compression_check,
    fit_datasheet,
    library,
    library_material,
    uniaxial_nominal_stress,
)
from softhand.fem.materials import Hyperfoam
from softhand.paper import paper

NAMES = list(library())
SHEETS = [n for n in NAMES if library()[n].modulus_100_MPa is not None]


@pytest.mark.parametrize("name", ["sil", "pu"])
def test_table3_entries_are_the_papers_constants(name):
    row, m = paper()["materials"][name], library_material(name)
    for key in ("nu", "mu_MPa", "alpha", "g", "tau_s"):
        assert m.constants[key] == row[key]
    assert m.shear_modulus_MPa == pytest.approx({"sil": 0.09, "pu": 0.163}[name], rel=1e-12)


@pytest.mark.parametrize("name", SHEETS)
def test_datasheet_fit_reproduces_the_datasheet_tension_points(name):
    """One-term Storakers through M100 at stretch 2 and TS at the elongation at break, 1e-4."""
    m = library_material(name)
    lam_b = 1 + m.elongation_at_break_pct / 100
    assert uniaxial_nominal_stress(m.hyperfoam, 2.0) == pytest.approx(m.modulus_100_MPa, rel=1e-4)
    assert uniaxial_nominal_stress(m.hyperfoam, lam_b) == pytest.approx(m.tensile_strength_MPa,
                                                                        rel=1e-4)
    assert m.constants["g"] == paper()["materials"]["sil"]["g"]  # the named Prony assumption


@pytest.mark.parametrize("name", NAMES)
def test_small_strain_shear_modulus_is_the_sum_of_mu(name):
    """Simple shear gamma = 1e-6: sigma_12 / gamma = sum(mu_i) to 1e-5."""
    law = library_material(name).hyperfoam
    g = 1e-6
    F = np.eye(3)
    F[0, 1] = g
    S = law.stress((F.T @ F)[None], tangent=False)[0]
    assert S[3] / g == pytest.approx(sum(law.mu), rel=1e-5)


def test_fit_recovers_known_constants_from_synthetic_datasheet_points():
    law = Hyperfoam((0.05,), (2.3,), 0.49)
    m100, ts = uniaxial_nominal_stress(law, 2.0), uniaxial_nominal_stress(law, 8.0)
    mu, alpha = fit_datasheet(m100, ts, 700.0, 0.49)
    assert (mu, alpha) == pytest.approx((0.05, 2.3), rel=1e-8)


@pytest.mark.parametrize("name", NAMES)
def test_every_material_passes_the_homogeneous_compression_check(name):
    c = compression_check(name)
    assert c.passed, c
    assert c.axial_stress_MPa < 0 < c.lateral_stretch - 1  # compression, lateral bulge


def test_unknown_material_is_named_with_the_allowed_ones():
    with pytest.raises(ValueError, match=r"material 'ecoflex-00-31' is unknown; allowed: sil, pu"):
        library_material("ecoflex-00-31")
    r = CliRunner().invoke(main, ["materials", "ecoflex-00-31"])
    assert r.exit_code == 2
    assert r.output.count("\n") == 1 and "'ecoflex-00-31' is unknown" in r.output


def test_materials_command_lists_every_material_with_its_sources():
    r = CliRunner().invoke(main, ["materials"])
    assert r.exit_code == 0, r.output
    for name in NAMES:
        assert f"{name}: " in r.output
    assert "Table 3" in r.output and "technical bulletin" in r.output
