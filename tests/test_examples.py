"""Every example runs, on fast settings, and prints the numbers it promises."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _load(name: str):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_fe_indent_example(capsys):
    """The pocket makes the phalanx softer: d(2 N) pocket2 > 2 mm > solid, printed per design."""
    out = _load("fe_indent").main("2d", "coarse")
    assert out["pocket2-sil"]["displacement_at_2N_mm"] > 2.0
    assert out["solid-sil"]["displacement_at_2N_mm"] < 1.0
    assert "pocket2-sil" in capsys.readouterr().out


def test_skin_in_mujoco_example(capsys):
    """Calibrated skins give the FE force within 3 % of 2 N; rigid contact is far off."""
    out = _load("skin_in_mujoco").main("pocket2-sil")
    for rep in ("soft-contact", "soft-contact+relaxation"):
        for key in ("F_1mm", "F_2mm"):
            assert abs(out[rep][key] - out["FE"][key]) < 0.06
    assert abs(out["soft-contact+relaxation"]["F_end"] - out["FE"]["F_end"]) < 0.1
    assert out["rigid"]["F_1mm"] > 10 * out["FE"]["F_1mm"]
    assert "soft-contact" in capsys.readouterr().out


def test_handshake_force_regulating_example(capsys):
    """The digits that reach the partner hold about the target; none runs away above it."""
    out = _load("handshake_force_regulating").main(2.5)
    touching = [v for v in out.values() if v > 0.3]
    assert len(touching) >= 2, out
    assert max(touching) == pytest.approx(2.5, rel=0.3)
    assert all(v < 2 * 2.5 for v in out.values())
    assert "held during the shake" in capsys.readouterr().out


def test_handshake_open_loop_example(capsys):
    """Closing the hand loads the fingers the partner's hand lies in; skins change the peaks."""
    out = _load("handshake_open_loop").main(0.6)
    for design in ("rigid", "pocket2-sil"):
        assert max(out[design][r] for r in ("Index1", "Index2", "Index3")) > 2.0
    assert out["rigid"] != out["pocket2-sil"]
    assert "> 2 N" in capsys.readouterr().out
