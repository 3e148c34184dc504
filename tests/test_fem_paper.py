"""Agreement with the paper at the default 3D mesh (numbers from softhand/data/paper.json).

Tolerances are the ones promised in the docs (docs/designs.md): displacement at 2 N within 15 % for the six
single-material designs; layered solid designs change the homogeneous result with the paper's
sign and within 5 percentage points; 2 mm pocket forces at 2 mm within 20 %. pocket2-sil's force
at 2 mm chose the unstated roof thickness (geometry.py), so that one is a fit, not a prediction.
"""

from __future__ import annotations

import pytest

from softhand.fem.geometry import DESIGNS
from softhand.fem.solver import IndentationSettings, indent
from softhand.paper import paper

pytestmark = pytest.mark.slow  # the 12-design 3D fixture: about a minute idle, more under load


@pytest.fixture(scope="module")
def results_3d():
    settings = IndentationSettings(hold_s=0.0)
    return {name: indent(name, settings) for name in DESIGNS}


SINGLE = ["solid-sil", "solid-pu", "pocket1-sil", "pocket1-pu", "pocket2-sil", "pocket2-pu"]


@pytest.mark.parametrize("design", SINGLE)
def test_displacement_at_2n_within_15_percent(results_3d, design):
    """|d(2 N) - paper| / paper < 15 % (3D, default mesh, long-term moduli)."""
    ref = paper()["displacement_at_2N_mm"][design]
    got = results_3d[design].displacement_at(2.0)
    assert abs(got - ref) / ref < 0.15, f"{design}: {got:.3f} mm vs paper {ref} mm"


@pytest.mark.parametrize("layered,homogeneous", [("solid-pu-sil", "solid-pu"),
                                                 ("solid-sil-pu", "solid-sil")])
def test_layered_solid_change_has_paper_sign_and_size(results_3d, layered, homogeneous):
    """Change of d(2 N) from the homogeneous design: same sign as the paper, within 5 pp."""
    ref = paper()["layered_change_pct"][layered]
    change = 100 * (results_3d[layered].displacement_at(2.0)
                    / results_3d[homogeneous].displacement_at(2.0) - 1)
    assert change * ref > 0
    assert abs(change - ref) < 5.0, f"{layered}: {change:+.1f} % vs paper {ref:+.1f} %"


@pytest.mark.parametrize("design", ["pocket2-sil", "pocket2-sil-pu", "pocket2-pu",
                                    "pocket2-pu-sil"])
def test_pocket2_force_at_2mm_within_20_percent(results_3d, design):
    """|F(2 mm) - paper| / paper < 20 % for the four 2 mm pocket designs."""
    ref = paper()["force_at_2mm_N"][design]
    got = results_3d[design].force_at(2.0)
    assert got is not None and abs(got - ref) / ref < 0.20, f"{design}: {got} N vs paper {ref} N"
