"""Run the robustness cases of issue 20 against a checkout and tabulate old against new.

Each case runs the ``softhand`` command line (or a few lines of Python against the env) of the
checkout given by ``--checkout`` in a subprocess, with a time limit, and records the exit status,
the last line printed, the seconds it took, the number of warning lines, and whether any file of
that checkout's ``calibration/`` changed (sha256 of every file before and after). Run it on
throw-away checkouts (``git worktree add``): an old version may write into its shipped data.

    python tools/fuzz_cli.py run --checkout /tmp/old --out old.json
    python tools/fuzz_cli.py run --checkout /tmp/new --out new.json
    python tools/fuzz_cli.py table old.json new.json > reports/robustness.md
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

LIMIT_S = 20.0

#: (item of issue 20, case, arguments of `softhand` or ["-c", python code]); {tmp} is a scratch
#: folder, {cal} the checkout's calibration folder, {file} a plain file inside {tmp}
CASES: list[tuple[str, str, list[str]]] = [
    # item 2: shipped data
    ("2", "fe sweep at the shipped settings, no --force", ["fe", "sweep", "--max-force", "20",
                                                          "--max-depth", "7"]),
    ("2", "sensors calibrate --fit-only (shipped --out)", ["sensors", "calibrate", "--fit-only"]),
    ("2", "fe sweep --mode 2d --out calibration/skins",
     ["fe", "sweep", "--mode", "2d", "--mesh", "coarse", "--hold", "0", "--out", "{cal}/skins"]),
    ("2", "fe export into calibration/fe", ["fe", "export", "solid-pu", "{cal}/fe/x.inp",
                                            "--depth", "1"]),
    ("2", "handshake --record calibration/x.rrd", ["handshake", "--record", "{cal}/x.rrd"]),
    ("2", "render into calibration/", ["render", "{cal}/x.png"]),
    ("2", "bench handshake --out calibration/fe", ["bench", "handshake", "--out", "{cal}/fe"]),
    ("2", "calibrate --fe-dir D --out D (D a copy of the FE folder)",
     ["calibrate", "solid-pu", "--representation", "rigid", "--fe-dir", "{tmp}/fe",
      "--out", "{tmp}/fe"]),
    ("2", "2D one-design sweep into a full 3D FE folder",
     ["fe", "sweep", "--mode", "2d", "--mesh", "coarse", "--hold", "0", "--design", "solid-pu",
      "--out", "{tmp}/fe"]),
    ("2", "calibrate from an FE folder with a corrupt summary.json",
     ["calibrate", "solid-pu", "--representation", "rigid", "--fe-dir", "{tmp}/fe-corrupt",
      "--out", "{tmp}/skins"]),
    # item 3: outputs checked before work
    ("3", "fe export into a read-only mount (/proc)", ["fe", "export", "solid-pu",
                                                        "/proc/deck.inp"]),
    ("3", "fe indent --out into a read-only mount", ["fe", "indent", "solid-pu", "--out",
                                                     "/proc/softhand-out"]),
    ("3", "handshake --record into a read-only mount", ["handshake", "--record", "/proc/x.rrd"]),
    ("3", "skin flex-press --picture into a read-only mount",
     ["skin", "flex-press", "--picture", "/proc/x.png"]),
    ("3", "bench handshake --out into a read-only mount", ["bench", "handshake", "--out",
                                                           "/proc/reports"]),
    ("3", "a 300-character folder name", ["fe", "sweep", "--mode", "2d", "--out",
                                          "{tmp}/" + "x" * 300]),
    # item 5: bounds
    ("5", "--threads 100000", ["fe", "sweep", "--mode", "2d", "--mesh", "coarse", "--hold", "0",
                               "--threads", "100000", "--out", "{tmp}/t"]),
    ("5", "population --workers 64 on 2 CPUs", ["population", "--n", "2", "--workers", "64",
                                                "--out", "{tmp}/pop"]),
    ("5", "--representation ''", ["handshake", "--representation", ""]),
    ("5", "--skin 'Palm1='", ["handshake", "--skin", "Palm1="]),
    ("5", "--sensor-placement ''", ["handshake", "--sensor-placement", ""]),
    ("5", "--partner-size ''", ["handshake", "--partner-size", ""]),
    ("5", "skin apply HAND ''", ["skin", "apply", "", "{tmp}/out.xml", "--geom", "a=solid-pu"]),
    ("5", "--materials /dev/zero", ["fe", "indent", "solid-pu", "--materials", "/dev/zero"]),
    ("5", "--materials: deeply nested JSON", ["fe", "indent", "solid-pu", "--materials",
                                              "{tmp}/nested.json"]),
    ("5", "MUJOCO_GL=bogus render", ["render", "{tmp}/x.png", "@MUJOCO_GL=bogus"]),
    ("5", "env design=''", ["-c", "from softhand.envs.handshake import HandshakeEnv as E; "
                                   "E(design='').reset(seed=0)"]),
    ("5", "env representation=''", ["-c", "from softhand.envs.handshake import HandshakeEnv as "
                                           "E; E(representation='').reset(seed=0)"]),
    ("5", "env calibration_dir=''", ["-c", "from softhand.envs.handshake import HandshakeEnv as "
                                            "E; E(calibration_dir='').reset(seed=0)"]),
    ("5", "env squeeze=1e6", ["-c", "from softhand.envs.handshake import HandshakeEnv as E; "
                                     "E(squeeze=1e6).reset(seed=0)"]),
    ("5", "env step() after close()",
     ["-c", "import numpy as np; from softhand.envs.handshake import HandshakeEnv as E; "
            "e = E(); e.reset(seed=0); e.close(); e.step(np.zeros(6)); print('stepped')"]),
    ("5", "env masked-array action",
     ["-c", "import numpy as np; from softhand.envs.handshake import HandshakeEnv as E; "
            "e = E(); e.reset(seed=0); "
            "a = np.ma.masked_array(np.zeros(6), mask=[1, 0, 0, 0, 0, 0]); "
            "a.data[0] = 9.0; e.step(a); print('stepped')"]),
    ("5", "transfer.json with a wrong k_inf", ["-c", "from softhand.sensors.calibrate import "
                                                      "load_transfer_laws as L; "
                                                      "L('{tmp}/transfer-kinf.json'); "
                                                      "print('loaded')"]),
    ("5", "transfer.json with an unknown top-level key",
     ["-c", "from softhand.sensors.calibrate import load_transfer_laws as L; "
            "L('{tmp}/transfer-extra.json'); print('loaded')"]),
    # item 4: divergence
    ("4", "handshake --representation soft-contact+relaxation --controller open-loop",
     ["handshake", "--representation", "soft-contact+relaxation", "--controller", "open-loop"]),
    ("4", "relaxation, open-loop, partner 215 x 75 mm (a Table 1 corner)",
     ["handshake", "--representation", "soft-contact+relaxation", "--controller", "open-loop",
      "--partner-size", "215,75"]),
    ("4", "relaxation, open-loop, --timestep 0.005",
     ["handshake", "--representation", "soft-contact+relaxation", "--controller", "open-loop",
      "--timestep", "0.005"]),
    ("5", "--timestep 0.00275 (inside the help's range)", ["handshake", "--timestep", "0.00275"]),
    # item 6: warnings
    ("6", "handshake --timestep 0.005", ["handshake", "--timestep", "0.005"]),
    ("6", "handshake (default)", ["handshake"]),
]


def sha_tree(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file() and "__pycache__" not in p.parts}


def scratch(checkout: Path) -> Path:
    """A scratch folder with the inputs the cases read."""
    tmp = Path(tempfile.mkdtemp(prefix="softhand-fuzz-"))
    cal = checkout / "calibration"
    shutil.copytree(cal / "fe", tmp / "fe")
    shutil.copytree(cal / "fe", tmp / "fe-corrupt")
    (tmp / "fe-corrupt" / "summary.json").write_text('{"provenance": ')
    (tmp / "nested.json").write_text("[" * 100000 + "]" * 100000)
    data = json.loads((cal / "sensors" / "transfer.json").read_text())
    first = next(iter(data["laws"].values()))
    next(iter(first.values()))["kernel"]["k_inf"] = 0.5
    (tmp / "transfer-kinf.json").write_text(json.dumps(data))
    data = json.loads((cal / "sensors" / "transfer.json").read_text())
    data["extra"] = 1
    (tmp / "transfer-extra.json").write_text(json.dumps(data))
    return tmp


def run_case(checkout: Path, args: list[str]) -> dict:
    tmp = scratch(checkout)
    env = {**os.environ, "PYTHONPATH": str(checkout), "OMP_NUM_THREADS": "1",
           "MUJOCO_GL": "egl"}
    env.pop("SOFTHAND_TRACEBACK", None)
    words = []
    for a in args:
        if a.startswith("@"):
            key, _, value = a[1:].partition("=")
            env[key] = value
            continue
        words.append(a.format(tmp=tmp, cal=checkout / "calibration"))
    cmd = ([sys.executable, *words] if words[0] == "-c" else
           [sys.executable, "-c", "from softhand.cli import run; run()", *words])
    before = sha_tree(checkout / "calibration")
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, cwd=tmp, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, start_new_session=True)
    try:
        out, _ = proc.communicate(timeout=LIMIT_S)
        rc = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)  # the command and its worker processes
        out, _ = proc.communicate()
        rc = None
    wall = time.perf_counter() - t0
    changed = sorted(set(before.items()) ^ set(sha_tree(checkout / "calibration").items()))
    lines = [ln for ln in out.replace("\r", "\n").splitlines() if ln.strip()]
    last = next((ln for ln in reversed(lines) if not ln.startswith(("fe sweep", "calibrate"))
                 and "%|" not in ln), "")
    shutil.rmtree(tmp, ignore_errors=True)
    if changed:  # put the checkout's shipped data back for the next case
        subprocess.run(["git", "-C", str(checkout), "checkout", "--", "calibration"], check=False)
        subprocess.run(["git", "-C", str(checkout), "clean", "-fdq", "calibration"], check=False)
    return {"rc": rc, "wall_s": round(wall, 1), "last_line": last[:300],
            "traceback": "Traceback" in out, "internal": "internal error" in out,
            "warning_lines": sum("warning" in ln.lower() for ln in lines),
            "calibration_changed": len({c[0] for c in changed})}


def outcome(r: dict) -> str:
    if r["rc"] is None:
        what = f"still working after {LIMIT_S:.0f} s (the work started)"
    elif r["traceback"]:  # an API case (python -c): the exception the caller gets
        what = "raises"
    else:
        what = f"exit {r['rc']} in {r['wall_s']:g} s"
    if r["calibration_changed"]:
        what += f"; {r['calibration_changed']} shipped files changed"
    if r["warning_lines"] > 1:
        what += f"; {r['warning_lines']} warning lines"
    line = r["last_line"].replace("|", "\\|")
    return f"{what}: `{line[:160]}`" if line else what


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    run = sub.add_parser("run")
    run.add_argument("--checkout", required=True, type=Path)
    run.add_argument("--out", required=True, type=Path)
    run.add_argument("--only", default=None, help="run the cases whose name holds this text")
    run.add_argument("--merge", action="store_true", help="add to --out instead of replacing it")
    tab = sub.add_parser("table")
    tab.add_argument("old", type=Path)
    tab.add_argument("new", type=Path)
    a = ap.parse_args()
    if a.cmd == "run":
        results = json.loads(a.out.read_text()) if a.merge and a.out.exists() else {}
        for item, name, args in CASES:
            if a.only and a.only not in name:
                continue
            results[name] = {"item": item, **run_case(a.checkout.resolve(), args)}
            print(f"[{item}] {name}: {outcome(results[name])}", file=sys.stderr, flush=True)
        a.out.write_text(json.dumps(results, indent=1))
        return
    old, new = json.loads(a.old.read_text()), json.loads(a.new.read_text())
    print("| item | case | old outcome | new outcome |\n|---|---|---|---|")
    for item, name, _ in CASES:
        if name in new:
            was = outcome(old[name]) if name in old else "-"
            print(f"| {item} | {name} | {was} | {outcome(new[name])} |")


if __name__ == "__main__":
    main()
