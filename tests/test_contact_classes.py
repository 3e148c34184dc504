"""Contact classes: a pair's law follows its two geoms' shapes (softhand.skin.contact_classes)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from softhand.laws.fit import Curve, fit_skin_law
from softhand.laws.qlv import Prony
from softhand.laws.references import HUMAN, reference_law
from softhand.skin.contact_classes import (
    CLASSES,
    classify,
    geom_shape,
    shape_ratio,
    tissue_class_law,
    tissue_counterpart,
)

_XML = """
<mujoco><worldbody>
  <geom name="phalanx" type="capsule" size="0.009 0.015"/>
  <geom name="palm" type="box" size="0.04 0.04 0.01" pos="0 0.2 0"/>
  <geom name="thick" type="cylinder" size="0.02 0.05" pos="0 0.4 0"/>
  <geom name="pad" type="ellipsoid" size="0.02 0.012 0.03" pos="0 0.6 0"/>
  <geom name="floor" type="plane" size="1 1 0.1" pos="0 0 -1"/>
</worldbody></mujoco>"""


@pytest.fixture(scope="module")
def model():
    return mujoco.MjModel.from_xml_string(_XML)


def test_shapes_and_classes_follow_the_geoms(model):
    g = {model.geom(i).name: i for i in range(model.ngeom)}
    assert geom_shape(model, g["phalanx"]) == ("round", pytest.approx(9.0))
    assert geom_shape(model, g["pad"]) == ("round", pytest.approx(12.0))  # smallest semi-axis
    assert geom_shape(model, g["palm"])[0] == geom_shape(model, g["floor"])[0] == "flat"
    assert classify(model, g["phalanx"], g["phalanx"]) == "phalanx/finger"
    assert classify(model, g["phalanx"], g["palm"]) == "phalanx/flat"
    assert classify(model, g["palm"], g["phalanx"]) == "palm/finger"
    assert classify(model, g["palm"], g["floor"]) == "palm/flat"
    # a round geom wider than a finger presses like a flat (20 mm > FINGER_MAX_RADIUS_MM)
    assert classify(model, g["phalanx"], g["thick"]) == "phalanx/flat"
    # the tissue is pressed by the skin's body: a phalanx like a finger, a palm like a flat
    assert [tissue_counterpart(k) for k in CLASSES] == ["finger", "finger", "flat", "flat"]


def _ramp(law, depth_mm: float, speed: float = 0.5, n: int = 300) -> Curve:
    t = np.linspace(0.0, depth_mm / speed, n)
    d = speed * t
    return Curve(t, d, law.force(t, d), np.zeros(n, bool), label="synthetic")


def test_a_fixed_relaxation_is_kept_and_the_elastic_law_refitted():
    """fit_skin_law(prony=...) keeps the relaxation to the bit and recovers a law's own ramp."""
    tissue = reference_law(HUMAN)
    prony = Prony((0.08, 0.01), (0.2, 2.6))
    from softhand.laws.fit import SkinLaw

    law = SkinLaw("x", tissue.elastic, prony)
    curve = _ramp(law, 4.0)
    fitted = fit_skin_law("x", [curve], prony=prony)
    assert fitted.prony == prony
    d = np.linspace(0.2, 4.0, 40)
    t = d / 0.5
    err = np.abs(fitted.force(t, d) - law.force(t, d))
    assert err.max() < 0.02 * 2.0  # within 2 % of 2 N over the ramp


def test_the_tissue_finger_law_is_the_plate_law_times_the_shape_ratio():
    """The stated assumption, exactly: the tissue's finger law is its plate law times the
    reference design's cylinder/plate ratio at the same depth (to the spline fit, 2 % of 2 N)."""
    tissue = reference_law(HUMAN)
    d = np.linspace(0.0, 6.0, 200)
    plate = Curve(d / 0.5, d, 0.2 * d ** 2, np.zeros(d.size, bool), label="plate")
    finger = Curve(d / 0.5, d, 0.2 * d ** 2 * (0.5 + 0.05 * d), np.zeros(d.size, bool),
                   label="finger")
    ratio = shape_ratio(plate, finger)
    assert ratio(2.0) == pytest.approx(0.6, rel=1e-3)
    assert ratio(0.1) == pytest.approx(ratio(0.25))  # held below the first trusted depth
    law = tissue_class_law(tissue, "finger", plate, finger)
    x = np.linspace(0.5, 5.0, 30)
    want = tissue.elastic.force(x) * (0.5 + 0.05 * x)
    assert np.abs(law.elastic.force(x) - want).max() < 0.02 * 2.0
    assert tissue_class_law(tissue, "flat") is tissue
    with pytest.raises(ValueError, match="counterpart = 'edge'"):
        tissue_class_law(tissue, "edge")
    with pytest.raises(ValueError, match="plate and finger FE curves"):
        tissue_class_law(tissue, "finger")
