"""A regular (non-editable) install works from any folder: the wheel carries the shipped data.

Builds the wheel as a user would (``pip wheel``, isolated build), installs it without
dependencies into a fresh virtual environment that sees this interpreter's packages (mujoco,
numpy, ... are already there), and runs the main job and an FE run from a folder that is not the
repository. The installed package, not this checkout, must be the one that runs.
"""

from __future__ import annotations

import json
import subprocess
import sys
import venv
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_wheel_install_runs_the_handshake_from_another_folder(tmp_path):
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(wheels),
                    str(REPO)], check=True, capture_output=True, text=True, timeout=600)
    (wheel,) = wheels.glob("softhand-*.whl")
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(system_site_packages=True, with_pip=True).create(env_dir)
    python = env_dir / "bin" / "python"
    subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-deps", str(wheel)],
                   check=True, capture_output=True, text=True, timeout=600)
    work = tmp_path / "elsewhere"
    work.mkdir()
    where = subprocess.run([str(python), "-c", "import softhand.paths as p; "
                            "print(p.SKINS_DIR); print(p.IN_CHECKOUT)"],
                           cwd=work, check=True, capture_output=True, text=True).stdout.split()
    assert where[0].startswith(str(env_dir)) and where[1] == "False"
    softhand = env_dir / "bin" / "softhand"
    res = subprocess.run([str(softhand), "handshake", "--json", "--record", "hs.rrd"], cwd=work,
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert len(json.loads(res.stdout)["regions"]) == 18
    assert (work / "hs.rrd").stat().st_size > 0
    res = subprocess.run([str(softhand), "fe", "indent", "solid-pu", "--mode", "2d", "--hold", "0",
                          "--json"], cwd=work, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["displacement_at_2N_mm"] > 0
