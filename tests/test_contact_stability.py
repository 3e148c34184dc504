"""The stability bound of a calibrated soft contact under MuJoCo's explicit contact update
(softhand.skin.rig.contact_stable_timestep) against the simulation: a free indenter on a slide
joint (the rig, kappa = 3) under a dead weight holds still just below the bound and oscillates
without bound just above it; the skinned Menagerie-style hand at a 2 ms step gets no stiffness
warning and follows its law (issue 24: ``skin apply`` warned "unstable" there)."""

from __future__ import annotations

import warnings
from pathlib import Path

import mujoco
import numpy as np
import pytest
from test_skin_apply import _press

from softhand.skin.apply import apply_skin
from softhand.skin.files import load_calibration
from softhand.skin.rig import (
    RigSettings,
    SkinRangeWarning,
    build_rig,
    contact_stable_timestep,
    pair_inverse_inertia,
    pair_mobility,
)

HAND = Path(__file__).resolve().parent / "data" / "menagerie_style_hand.xml"


def _dead_weight_spread_mm(design: str, mass_kg: float, force_N: float, timestep: float) -> float:
    """Ramp a dead weight onto the rig's free indenter over 0.5 s, hold to 1.5 s; the spread
    (standard deviation, mm) of the indentation over the last 0.3 s (inf if it blew up)."""
    params = load_calibration(design).soft_contact
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SkinRangeWarning)
        model = build_rig("soft-contact", params, settings=RigSettings(
            timestep=timestep, mass_kg=mass_kg, load_cell_hz=0.0))
    data = mujoco.MjData(model)
    depth = []
    for k in range(int(1.5 / timestep)):
        data.qfrc_applied[0] = -force_N * min(1.0, k * timestep / 0.5)
        mujoco.mj_step(model, data)
        depth.append(-1e3 * data.qpos[0])
    tail = np.array(depth[int(1.2 / timestep):])
    return float(tail.std()) if np.all(np.isfinite(tail)) else float("inf")


@pytest.mark.parametrize("design, mass_kg, force_N", [
    ("pocket2-sil", 0.02, 20.0),  # bound 2.02 ms
    ("solid-pu", 0.002, 10.0),    # bound 0.90 ms
])
def test_the_bound_separates_still_from_diverging(design, mass_kg, force_N):
    params = load_calibration(design).soft_contact
    model = build_rig("soft-contact", params, settings=RigSettings(mass_kg=mass_kg,
                                                                   load_cell_hz=0.0))
    pid = model.pair("skin_plate").id
    mobility = pair_mobility(model, pid)
    assert mobility == pytest.approx(3.0, rel=1e-6)  # a slide joint: 1/m against 1/(3m)
    bound = contact_stable_timestep(params, pair_inverse_inertia(model, pid), mobility=mobility,
                                    top_N=force_N).max_timestep_s
    assert _dead_weight_spread_mm(design, mass_kg, force_N, 0.95 * bound) < 1e-6
    assert _dead_weight_spread_mm(design, mass_kg, force_N, 1.05 * bound) > 0.1


def test_skinned_hand_at_2_ms_is_not_called_unstable_and_follows_its_law():
    """The fingertip's pocket2-sil pair at MuJoCo's default 2 ms step: the bound up to 20 N is
    several milliseconds (the old criterion, omega h < 1 at the law's full-impedance stiffness
    that lies beyond the bone, said 1.59 ms); a press at 2 ms follows the law."""
    spec = mujoco.MjSpec.from_file(str(HAND))
    spec.option.timestep = 0.002
    with warnings.catch_warnings():
        warnings.simplefilter("error", SkinRangeWarning)
        (tip,) = apply_skin(spec, ["index_tip=pocket2-sil"])
    model = spec.compile()
    pid = model.pair("skin_index_tip__plate").id
    stability = contact_stable_timestep(tip.law, pair_inverse_inertia(model, pid),
                                        mobility=pair_mobility(model, pid))
    assert stability.max_timestep_s > 0.004
    depth, force = _press(model, "index_tip", 0.0)
    assert np.all(np.isfinite(force)) and force.max() > 2.0
    assert np.sqrt(np.mean((force - tip.law.force(depth)) ** 2)) < 0.002


def test_bad_arguments_name_the_value():
    params = load_calibration("solid-pu").soft_contact
    with pytest.raises(ValueError, match=r"inv_inertia = -1\.0"):
        contact_stable_timestep(params, -1.0)
    with pytest.raises(ValueError, match="top_N = 0"):
        contact_stable_timestep(params, 1.0, top_N=0)
