"""The declared minimum versions: an older library is refused in one line; the minimums run.

The slow test installs exactly the declared minimums of the checked libraries in a fresh virtual
environment (from the package registry; skipped, saying so, where the registry cannot be
reached) and runs the main job with a recording: the lower bounds in pyproject.toml are tested,
not guessed (numpy>=1.26 and scipy>=1.11 could not be installed beside rerun-sdk 0.40).
"""

from __future__ import annotations

import os
import subprocess
import sys
import venv
from importlib import metadata
from pathlib import Path

import pytest
from conftest import checkout_build_lock

from softhand.requirements import CHECKED, RequirementError, check, minimums

ROOT = Path(__file__).resolve().parents[1]


def test_every_checked_library_has_a_declared_minimum():
    assert set(minimums()) == set(CHECKED), minimums()


def test_an_older_library_is_refused_in_one_line(monkeypatch):
    real = metadata.version
    monkeypatch.setattr(metadata, "version",
                        lambda name: "3.14.0" if name == "mujoco" else real(name))
    with pytest.raises(RequirementError) as caught:
        check(*CHECKED)
    assert str(caught.value) == ("mujoco 3.14.0 is installed, and softhand needs mujoco>=4.0: "
                                 "pip install -U 'mujoco>=4.0'")
    check("numpy", "scipy")  # the others pass


def test_the_command_line_says_it_in_one_line(tmp_path):
    """An old library met by the command line: one line on stderr, exit 1, no traceback (the
    package is imported before the command line's own error handling runs)."""
    shim = tmp_path / "sitecustomize.py"
    shim.write_text("from importlib import metadata\n_real = metadata.version\n"
                    "metadata.version = lambda n: '0.36.3' if n == 'rerun-sdk' else _real(n)\n",
                    encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)])}
    out = subprocess.run([sys.executable, "-m", "softhand.cli", "--version"], env=env,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 1, (out.stdout, out.stderr)
    assert out.stderr.strip() == ("error: rerun-sdk 0.36.3 is installed, and softhand needs "
                                  "rerun-sdk>=0.40: pip install -U 'rerun-sdk>=0.40'")


@pytest.mark.slow
def test_the_declared_minimums_install_and_run_the_main_job(tmp_path):
    """numpy, scipy, mujoco, rerun-sdk and gymnasium at exactly their declared minimums, the rest
    as pip resolves them, in a fresh virtual environment: the README's main job writes its
    recording."""
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True)
    python = env_dir / "bin" / "python"
    pins = [f"{name}=={version}" for name, version in minimums().items()]
    with checkout_build_lock():
        install = subprocess.run([str(python), "-m", "pip", "install", "-q", "-e", str(ROOT),
                                  *pins], capture_output=True, text=True, timeout=900)
    if install.returncode != 0 and "ResolutionImpossible" not in install.stderr and any(
            s in install.stderr for s in ("Could not find a version", "Connection", "Network")):
        pytest.skip(f"the package registry could not be reached: {install.stderr[-300:]}")
    assert install.returncode == 0, install.stderr[-3000:]
    listed = subprocess.run([str(python), "-m", "pip", "list", "--format=freeze"],
                            capture_output=True, text=True, check=True).stdout.lower()
    for pin in pins:
        assert pin.lower() in listed.splitlines() or pin.lower() + ".0" in listed.splitlines(), pin
    rrd = tmp_path / "handshake.rrd"
    run = subprocess.run([str(env_dir / "bin" / "softhand"), "handshake", "--record", str(rrd)],
                         capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-3000:]
    assert rrd.stat().st_size > 0 and "regions over 2 N" in run.stdout
