"""A regular (non-editable) install works from any folder: the wheel carries the shipped data.

Builds the wheel as a user would (``pip wheel``, isolated build), installs it without
dependencies into a fresh virtual environment, and runs the main job and an FE run from a folder
that is not the repository. The installed package, not this checkout, must be the one that runs.

The new environment must see exactly this interpreter's installed dependencies (mujoco, numpy,
gymnasium, ...), whether this interpreter is a system Python or itself a virtual environment.
``system_site_packages=True`` is not that: inside a venv it exposes the *base* interpreter's
site-packages, not the running venv's, and the handshake then fails on a missing import. So the
venv is created bare and a ``.pth`` file lists this interpreter's import paths (its site dirs and
what their ``.pth`` files add). A ``.pth`` file's plain path lines are appended as they are, and
the ``.pth`` files inside those folders are not run, so the editable install of softhand in this
environment (``__editable__*.pth`` importing a finder that maps ``softhand`` to the checkout)
does not follow; the test checks that every softhand module that runs is the wheel's copy.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import venv
from pathlib import Path

import pytest
from conftest import checkout_build_lock

REPO = Path(__file__).resolve().parents[1]

# no PYTHONPATH/PYTHONHOME: either could put the checkout ahead of the installed package
ENV = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}

SYS_PATH = "import json, sys; print(json.dumps(sys.path))"

WHERE = """
import importlib.metadata as md, json, sys
import softhand, softhand.calibration, softhand.paths as p
print(json.dumps({
    "softhand": softhand.__file__,
    "calibration": list(softhand.calibration.__path__),
    "skins": str(p.SKINS_DIR),
    "in_checkout": p.IN_CHECKOUT,
    "dist": str(md.distribution("softhand").locate_file("")),
    "meta_path": [repr(f) for f in sys.meta_path],
}))
"""


def _run(cmd, **kw):
    return subprocess.run(cmd, check=True, capture_output=True, text=True, env=ENV,
                          timeout=600, **kw)


def _parent_paths(cwd: Path, own: list[str]) -> list[str]:
    """This interpreter's import paths beyond the new venv's own (its stdlib is the same)."""
    paths = json.loads(_run([sys.executable, "-c", SYS_PATH], cwd=cwd).stdout)
    keep = []
    for p in paths:
        if not p or p in own or p in keep or not os.path.exists(p):
            continue
        if Path(p).resolve() == REPO:  # a path-style editable install: the checkout itself
            continue
        keep.append(p)
    return keep


@pytest.mark.slow
def test_wheel_install_runs_the_handshake_from_another_folder(tmp_path):
    wheels = tmp_path / "wheels"
    with checkout_build_lock():
        _run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(wheels),
              str(REPO)])
    (wheel,) = wheels.glob("softhand-*.whl")
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(system_site_packages=False, with_pip=True).create(env_dir)
    python = env_dir / "bin" / "python"
    # installed before the .pth exists: pip must not see this environment's softhand 0.1.0 and
    # call the requirement satisfied
    _run([str(python), "-m", "pip", "install", "-q", "--no-deps", str(wheel)])
    work = tmp_path / "elsewhere"
    work.mkdir()
    own = json.loads(_run([str(python), "-c", SYS_PATH], cwd=work).stdout)
    site = Path(_run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                     cwd=work).stdout.strip())
    assert site.is_relative_to(env_dir)
    parent = _parent_paths(work, own)
    assert parent, "this interpreter has no import paths beyond the standard library"
    (site / "_softhand_test_parent_env.pth").write_text("".join(p + "\n" for p in parent))

    where = json.loads(_run([str(python), "-c", WHERE], cwd=work).stdout)
    for key in ("softhand", "skins", "dist"):
        assert Path(where[key]).is_relative_to(site), (key, where[key])
    assert all(Path(c).is_relative_to(site) for c in where["calibration"]), where["calibration"]
    assert where["in_checkout"] is False
    assert not any("editable" in f.lower() for f in where["meta_path"]), where["meta_path"]

    softhand = env_dir / "bin" / "softhand"
    res = subprocess.run([str(softhand), "handshake", "--json", "--record", "hs.rrd"], cwd=work,
                         capture_output=True, text=True, timeout=600, env=ENV)
    assert res.returncode == 0, res.stderr
    assert len(json.loads(res.stdout)["regions"]) == 18
    assert (work / "hs.rrd").stat().st_size > 0
    res = subprocess.run([str(softhand), "fe", "indent", "solid-pu", "--mode", "2d", "--hold", "0",
                          "--json"], cwd=work, capture_output=True, text=True, timeout=600, env=ENV)
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["displacement_at_2N_mm"] > 0
