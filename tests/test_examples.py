"""Every example runs, on fast settings, and prints the numbers it promises."""

from __future__ import annotations

import importlib.util
from pathlib import Path

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
