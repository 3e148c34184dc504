"""Run the robustness cases of issue 20 against a checkout and tabulate old against new.

Each case runs the ``softhand`` command line (or a few lines of Python against the env) of the
checkout given by ``--checkout`` in a subprocess, with a time limit, and records the exit status,
the last line printed, the seconds it took, the number of warning lines, and whether any file of
that checkout's ``calibration/`` changed (sha256 of every file before and after). Run it on
throw-away checkouts (``git worktree add``): an old version may write into its shipped data.

    python tools/fuzz_cli.py run --checkout /tmp/old --out old.json
    python tools/fuzz_cli.py run --checkout /tmp/new --out new.json
    python tools/fuzz_cli.py table old.json new.json > reports/robustness.md

``--cases 34`` runs the second set instead, one case per concrete item of issue 34 (bad input,
cache, staging folders left by kill -9, interrupted populations, skin apply's pair order, the
env's pickling and headless rendering, the docs as GitHub shows them); its cases may prepare
inputs (``SETUP_34``) and look at what a run left behind (``AFTER_34``), and some run a few
commands in a row from Python (the kill -9 and Ctrl-C cases), with a longer limit (``LIMITS_34``):

    python tools/fuzz_cli.py run --cases 34 --checkout /tmp/o34 --out old34.json
    python tools/fuzz_cli.py run --cases 34 --checkout /tmp/n34 --out new34.json
    python tools/fuzz_cli.py table --cases 34 old34.json new34.json
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


# --- the second set: issue 34 ------------------------------------------------------------------

#: the env in a case's Python (both checkouts have it)
_ENV = "from softhand.envs.handshake import HandshakeEnv as E; "
_VEC = "from softhand.envs.vector import HandshakeVectorEnv as V; "
_LONG = "a" * 300

#: a cached grasp with its variables zeroed (finite numbers): used, or solved again and rewritten?
_GRASP_CACHE = """
import json, os, numpy as np
os.environ['SOFTHAND_CACHE_DIR'] = '{tmp}/cache'
from softhand.hands import grasp as g
from softhand.hands.config import SceneConfig
c = SceneConfig()
solved = g._solve_grasp.__wrapped__(c, g.GRASP_SETTINGS)
path = g._cache_path(c, g.GRASP_SETTINGS)
entry = json.loads(path.read_text())
entry['x'] = [0.0] * len(entry['x'])
path.write_text(json.dumps(entry))
again = g._solve_grasp.__wrapped__(c, g.GRASP_SETTINGS)
left = json.loads(path.read_text())['x']
moved = float(np.max(np.abs(np.asarray(again.partner_q) - np.asarray(solved.partner_q))))
print(('the grasp is the solved one' if moved == 0 else
       'the zeroed entry was used: partner joints off by up to %.2f rad, cost %.3g instead of %.3g'
       % (moved, again.cost, solved.cost))
      + '; the entry ' + ('was rewritten' if any(left) else 'still holds the zeroed x'))
"""

#: skin apply on a fingertip pressed by the same box fixed to the world (a table: MuJoCo puts it
#: first in the pair) and on a mocap body: the pair's law and its force at 0.5, 1 and 2 mm
_PAIR_ORDER = """
import mujoco, numpy as np
from softhand.skin.apply import apply_skin
HAND = '{checkout}/tests/data/menagerie_style_hand.xml'

def settled():
    spec = mujoco.MjSpec.from_file(HAND)
    m = spec.compile(); d = mujoco.MjData(m)
    for _ in range(1500):
        mujoco.mj_step(m, d)
    return d.qpos.copy(), d.xpos[m.geom_bodyid[m.geom('index_tip').id]].copy(), \\
        d.xmat[m.geom_bodyid[m.geom('index_tip').id]].reshape(3, 3).copy()

q0, body, rot = settled()
axis = rot[:, 0]
tip = body + axis * 0.016
quat = np.zeros(4)
mujoco.mju_mat2Quat(quat, np.column_stack([rot[:, 2], np.cross(axis, rot[:, 2]), axis]).ravel())

def press(where, depth_mm):
    spec = mujoco.MjSpec.from_file(HAND)
    centre = tip + axis * (0.0075 + 0.002 - 1e-3 * depth_mm)
    if where == 'world':
        spec.worldbody.add_geom(name='box', type=mujoco.mjtGeom.mjGEOM_BOX,
                                size=[0.006, 0.006, 0.002], pos=centre, quat=quat)
    else:
        b = spec.worldbody.add_body(name='boxbody', mocap=True, pos=centre, quat=quat)
        b.add_geom(name='box', type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.006, 0.006, 0.002])
    (tip_skin,) = apply_skin(spec, dict(index_tip='pocket2-sil'), against=['box'])
    m = spec.compile(); d = mujoco.MjData(m)
    d.qpos[:] = q0
    g, box = m.geom('index_tip').id, m.geom('box').id
    f6 = np.zeros(6)
    for _ in range(1500):
        mujoco.mj_step(m, d)
    f = pen = 0.0
    for i in range(d.ncon):
        c = d.contact[i]
        if box in (c.geom1, c.geom2) and g in (c.geom1, c.geom2):
            mujoco.mj_contactForce(m, d, i, f6)
            f, pen = f + f6[0], max(pen, -c.dist)
    return list(tip_skin.pair_laws.values())[0], 1e3 * pen, f

out = []
for where in ('world', 'mocap'):
    runs = [press(where, d) for d in (0.5, 1.0, 2.0)]
    out.append('%s box: %s law, ' % (where, runs[0][0]) + ', '.join(
        '%.2f N at %.2f mm' % (f, pen) for _, pen, f in runs))
print('; '.join(out))
"""

#: kill -9 a forced `fe sweep` (shipped settings) once its staging folder exists, then start the
#: same command again and kill it the same way: what is left beside calibration/fe each time
_KILL9 = """
import glob, os, signal, subprocess, sys, threading, time
cal = '{cal}'
cmd = [sys.executable, '-c', 'from softhand.cli import run; run()', 'fe', 'sweep',
       '--max-force', '20', '--max-depth', '7', '--force']

def killed_run(seen):
    p = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True)
    out = []
    threading.Thread(target=lambda: out.extend(p.stdout), daemon=True).start()
    t0 = time.time()
    while time.time() - t0 < 20 and not set(glob.glob(cal + '/.fe.new-*')) - seen:
        time.sleep(0.1)
    time.sleep(1.0)
    os.killpg(p.pid, signal.SIGKILL)
    p.wait()
    time.sleep(0.2)
    return out

def left():
    stages = sorted(glob.glob(cal + '/.fe.new-*'))
    files = sum(len(f) for s in stages for _, _, f in os.walk(s))
    return stages, files

killed_run(set())
first, files1 = left()
out = killed_run(set(first))
now, files = left()
said = [ln.strip() for ln in out if first and os.path.basename(first[0]) in ln]
print('after the first kill -9: %d staging folder(s), %d files; after the second run (also '
      'killed): %d, %d files, the first one %s%s'
      % (len(first), files1, len(now), files, 'still there' if first and first[0] in now
         else 'removed', (': ' + said[0][:150]) if said else ' (nothing printed about it before '
         'the kill)'))
"""

#: `population --n 4` complete in P, then the same with Ctrl-C after the first partners
_POPULATION = """
import json, os, re, signal, subprocess, sys, threading, time
P = '{tmp}/pop'
cmd = [sys.executable, '-c', 'from softhand.cli import run; run()', 'population', '--n', '4',
       '--seed', '7', '--workers', '1', '--out', P]
subprocess.run(cmd, capture_output=True, check=True)
before = len(json.load(open(P + '/results.json'))['partners'])
p = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.PIPE,
                     stderr=subprocess.STDOUT, text=True, bufsize=1)
buf = []
def read():
    while True:
        ch = p.stdout.read(1)
        if not ch:
            return
        buf.append(ch)
threading.Thread(target=read, daemon=True).start()
t0 = time.time()
while time.time() - t0 < 60 and not re.search(r'\\b(25|50)/100\\b|\\b[12]/4\\b',
                                                ''.join(buf)):
    time.sleep(0.1)
os.killpg(p.pid, signal.SIGINT)
rc = p.wait(timeout=30)
time.sleep(0.2)
after = len(json.load(open(P + '/results.json'))['partners'])
beside = sorted(n for n in os.listdir('{tmp}') if n != 'pop')
lines = [ln for ln in ''.join(buf).replace('\\r', '\\n').splitlines() if ln.strip()]
print('complete set: %d partners; after Ctrl-C (exit %s): results.json holds %d partners%s; '
      'last line: %s' % (before, rc, after, (', beside it: ' + ', '.join(beside)) if beside
                         else '', lines[-1][:160] if lines else ''))
"""

#: an address that answers, but not as a Dask scheduler (a server on the loopback writing HTTP)
_NOT_DASK = """
import socket, sys, threading
s = socket.socket(); s.bind(('127.0.0.1', 0)); s.listen(4)
def serve():
    while True:
        try:
            c, _ = s.accept(); c.sendall(b'HTTP/1.1 200 OK\\r\\n\\r\\n' + b'\\xff' * 64)
        except OSError:
            return
threading.Thread(target=serve, daemon=True).start()
from softhand.cli import run
sys.argv = ['softhand', 'population', '--n', '2', '--out', '{tmp}/pop', '--cluster',
            'tcp://127.0.0.1:%d' % s.getsockname()[1]]
run()
"""

#: docs/controllers.md as GitHub shows it: table rows in the Markdown, or a build-time marker
_CONTROLLERS_MD = """
import pathlib, re
t = pathlib.Path('{checkout}/docs/controllers.md').read_text()
lines = t.splitlines()
markers = [i for i, ln in enumerate(lines) if re.match(r'<!-- softhand:[a-z-]+ -->', ln)]
def body(i):
    end = next((j for j in range(i + 1, len(lines)) if lines[j].startswith('<!-- /softhand')),
               None)
    return [] if end is None else [ln for ln in lines[i + 1:end] if ln.startswith('|')]
held = [len(body(i)) for i in markers]
rows = sum(ln.startswith('|') for ln in lines)
print('%d table rows in the Markdown; generated regions %s hold %s table rows%s'
      % (rows, ', '.join(lines[i][14:-4] for i in markers), held,
         ' (placeholders, filled only when the site is built)' if markers and not any(held)
         else ''))
"""

_RAW_INCLUDES = """
import pathlib
pages = {{p.name: sum(ln.startswith('--8<--') for ln in p.read_text().splitlines())
         for p in sorted(pathlib.Path('{checkout}/docs').glob('*.md'))}}
raw = {{k: v for k, v in pages.items() if v}}
print('%d raw --8<-- lines on %d pages%s' % (sum(raw.values()), len(raw),
                                              (': ' + ', '.join(raw)) if raw else ''))
"""

_PAIR_COUNT = """
import pathlib, re
from softhand.envs.handshake import HandshakeEnv
said = {{}}
for f in ('docs/handshake.md', 'models/mjcf/README.md'):
    found = re.findall(r'(\\d+) (?:contact )?pairs|(\\d+) in all', pathlib.Path(
        '{checkout}/' + f).read_text())
    said[f] = sorted({{n for t in found for n in t if n}})
print('the shipped scene has %d pairs; the docs say %s' % (HandshakeEnv().model.npair, said))
"""

_STIFF = """
import numpy as np
from softhand.envs.handshake import HandshakeEnv as E
e = E(calibration_dir='{tmp}/skins')
e.reset(seed=0)
done = False
while not done:
    _, _, term, trunc, info = e.step(np.zeros(6))
    done = term or trunc
print('ran: episode ended at t = %.3f s, unstable = %s' % (info['time_s'], info.get('unstable')))
"""


def _setup_class_laws(tmp: Path, cal: Path) -> None:
    fe, out = tmp / "fe-plates", tmp / "skins"
    fe.mkdir()
    out.mkdir()
    for f in [*(cal / "fe").glob("*.csv"), cal / "fe" / "summary.json"]:
        shutil.copy(f, fe / f.name)
    shutil.copy(cal / "skins" / "pocket2-sil.json", out / "pocket2-sil.json")


def _after_class_laws(tmp: Path, cal: Path) -> str:
    data = json.loads((tmp / "skins" / "pocket2-sil.json").read_text())
    same = (tmp / "skins" / "pocket2-sil.json").read_bytes() == (
        cal / "skins" / "pocket2-sil.json").read_bytes()
    return ("pocket2-sil.json in --out unchanged" if same else
            "pocket2-sil.json in --out rewritten " + ("with" if data.get("pair_laws") else
                                                      "WITHOUT") + " its pair_laws")


def _setup_stale_skins(tmp: Path, cal: Path) -> None:
    stale = cal / ".skins.new-fuzz34xx"
    shutil.copytree(cal / "skins", stale / "skins")
    old = time.time() - 600
    for p in [stale, *stale.rglob("*")]:
        os.utime(p, (old, old))


def _after_stale_skins(tmp: Path, cal: Path) -> str:
    stale = cal / ".skins.new-fuzz34xx"
    there = stale.exists()
    shutil.rmtree(stale, ignore_errors=True)
    return "the stale .skins.new-* " + ("is still there" if there else "was removed")


def _after_kill9(tmp: Path, cal: Path) -> str:
    for stage in cal.glob(".fe.new-*"):  # the leftovers this case counted
        shutil.rmtree(stage, ignore_errors=True)
    return ""


def _setup_stiff(tmp: Path, cal: Path) -> None:
    shutil.copytree(cal / "skins", tmp / "skins")
    path = tmp / "skins" / "pocket2-sil.json"
    data = json.loads(path.read_text())
    for law in data["pair_laws"].values():
        law["pair_law"]["params"]["stiffness_N_per_m_per_invmass"] = 1e300
    path.write_text(json.dumps(data))


def _setup_transfer(tmp: Path, cal: Path) -> None:
    shutil.copytree(cal / "sensors", tmp / "sensors")
    path = tmp / "sensors" / "transfer.json"
    data = json.loads(path.read_text())
    del data["laws"]["pocket2-sil"]
    path.write_text(json.dumps(data))


def _setup_floor(tmp: Path, cal: Path) -> None:
    (tmp / "floor.xml").write_text(
        '<mujoco><worldbody><geom name="floor" type="plane" size="1 1 0.1"/>'
        '<body name="b" pos="0 0 0.1"><freejoint/><geom name="box" type="box" size=".01 .01 .01"/>'
        "</body></worldbody></mujoco>")


def _after_nothing_written(tmp: Path, cal: Path) -> str:
    left = [p.name[:20] + ("..." if len(p.name) > 20 else "") for p in tmp.iterdir()
            if p.name.startswith("a")]
    return "wrote " + ", ".join(left) if left else "nothing written"


#: (build item of issue 34, case, arguments as in CASES)
CASES_34: list[tuple[str, str, list[str]]] = [
    # 1: nothing lost
    ("1", "calibrate --class-laws-only, FE folder without the class folders",
     ["calibrate", "pocket2-sil", "--class-laws-only", "--fe-dir", "{tmp}/fe-plates", "--out",
      "{tmp}/skins"]),
    ("1", "kill -9 a forced fe sweep twice (staging folder left beside calibration/fe)",
     ["-c", _KILL9]),
    ("1", "a .skins.new-* left 10 min ago, then calibrate --class-laws-only --force",
     ["calibrate", "pocket2-sil", "--class-laws-only", "--force"]),
    ("1", "population --n 4 complete, then the same with Ctrl-C after the first partners",
     ["-c", _POPULATION]),
    # 2: caches
    ("2", "a cached grasp with its x zeroed", ["-c", _GRASP_CACHE]),
    # 3: a pair's law from the shapes, not the order
    ("3", "skin apply: fingertip pressed by a world box and by a mocap box (0.5, 1, 2 mm)",
     ["-c", _PAIR_ORDER]),
    # 4: minimum versions
    ("4", "import softhand with mujoco reported as 3.3.7 (metadata patched)",
     ["-c", "import importlib.metadata as m; v = m.version; "
            "m.version = lambda n: '3.3.7' if n == 'mujoco' else v(n); import softhand; "
            "print('imported')"]),
    # 5: honoured or refused, one line
    ("5", "handshake --hand human --sensor-placement bone",
     ["handshake", "--hand", "human", "--sensor-placement", "bone"]),
    ("5", "render --sheet --at 3", ["render", "{tmp}/x.png", "--sheet", "--at", "3"]),
    ("5", "fe indent --solver pardiso --engine numpy",
     ["fe", "indent", "pocket2-sil", "--solver", "pardiso", "--engine", "numpy"]),
    ("5", "fe indent --solver cholmod --engine numpy",
     ["fe", "indent", "pocket2-sil", "--solver", "cholmod", "--engine", "numpy"]),
    ("5", "a skin stiffness of 1e300 in pair_laws (env, calibration_dir)", ["-c", _STIFF]),
    ("5", "fe indent --indenter sphere:0.000001 (1 nm)",
     ["fe", "indent", "solid-pu", "--indenter", "sphere:0.000001"]),
    ("5", "bench handshake --scale --worlds 1_0", ["bench", "handshake", "--scale", "--worlds",
                                                   "1_0"]),
    ("5", "env partner_size = a dict",
     ["-c", _ENV + "E(partner_size=dict([(180.0, 1), (85.0, 2)])).reset(seed=0); "
                   "print('accepted')"]),
    ("5", "--skin Index1=rigid --skin Index1=solid-pu",
     ["handshake", "--skin", "Index1=rigid", "--skin", "Index1=solid-pu"]),
    ("5", "--geometry pocket_roof_mm=1.5 --geometry pocket_roof_mm=2",
     ["fe", "indent", "pocket2-sil", "--geometry", "pocket_roof_mm=1.5", "--geometry",
      "pocket_roof_mm=2"]),
    ("5", "fe indent --body palm --sensor interface",
     ["fe", "indent", "pocket2-sil", "--body", "palm", "--sensor", "interface"]),
    ("5", "fe export OUT with a 300-character file name",
     ["fe", "export", "pocket2-sil", "{tmp}/" + _LONG + ".inp"]),
    ("5", "handshake --record with a 300-character file name",
     ["handshake", "--record", "{tmp}/" + _LONG + ".rrd"]),
    ("5", "env.render() before reset()",
     ["-c", _ENV + "e = E(render_mode='rgb_array'); e.render(); print('rendered')"]),
    ("5", "vector env nthread=0", ["-c", _VEC + "V(num_envs=2, nthread=0).reset(seed=0); "
                                               "print('built and reset')"]),
    ("5", "vector env nthread=-1", ["-c", _VEC + "V(num_envs=2, nthread=-1).reset(seed=0); "
                                                "print('built and reset')"]),
    ("5", "vector env nthread=10**6", ["-c", _VEC + "V(num_envs=2, nthread=10**6).reset(seed=0); "
                                                   "print('built and reset')"]),
    ("5", "vector env nthread=1.5", ["-c", _VEC + "V(num_envs=2, nthread=1.5).reset(seed=0); "
                                                 "print('built and reset')"]),
    ("5", "vector env num_envs=10**6", ["-c", _VEC + "V(num_envs=10**6).reset(seed=0); "
                                                    "print('built and reset')"]),
    ("5", "vector env device='cuda:0' on the cpu backend",
     ["-c", _VEC + "V(num_envs=2, device='cuda:0').reset(seed=0); print('built and reset')"]),
    ("5", "--cluster tcp://10.255.255.1:8786 (nothing answers)",
     ["population", "--n", "2", "--out", "{tmp}/pop", "--cluster", "tcp://10.255.255.1:8786"]),
    ("5", "--cluster at a loopback server that answers HTTP", ["-c", _NOT_DASK]),
    ("5", "env partner width 72.5 mm (bound 72.53)",
     ["-c", _ENV + "E(partner_size=(190, 72.5)).reset(seed=0); print('accepted')"]),
    ("5", "env action 1.0001",
     ["-c", "import numpy as np; " + _ENV + "e = E(); e.reset(seed=0); "
            "e.step(np.array([1.0001, 0, 0, 0, 0, 0])); print('stepped')"]),
    ("5", "transfer.json without the skin's design (env sensor_dir)",
     ["-c", _ENV + "E(sensor_dir='{tmp}/sensors').reset(seed=0); print('accepted')"]),
    ("5", "env timestep_s=0.005, frame_skip=20",
     ["-c", _ENV + "E(timestep_s=0.005, frame_skip=20).reset(seed=0); print('accepted')"]),
    ("5", "skin apply on a world plane", ["skin", "apply", "{tmp}/floor.xml", "{tmp}/out.xml",
                                          "--geom", "floor=pocket2-sil"]),
    ("5", "MUJOCO_GL=osmesa render (no libOSMesa here)", ["render", "{tmp}/x.png",
                                                          "@MUJOCO_GL=osmesa", "@-DISPLAY"]),
    ("5", "MUJOCO_GL=glfw render without a display", ["render", "{tmp}/x.png", "@MUJOCO_GL=glfw",
                                                      "@-DISPLAY"]),
    # 7: headless rendering, docs as GitHub shows them, py.typed, CITATION.cff
    ("7", "env.render() with neither MUJOCO_GL nor DISPLAY set",
     ["-c", "import os; " + _ENV + "e = E(render_mode='rgb_array'); e.reset(seed=0); "
            "print('rendered', e.render().shape, 'with MUJOCO_GL =', os.environ.get('MUJOCO_GL'))",
      "@-MUJOCO_GL", "@-DISPLAY"]),
    ("7", "docs/controllers.md as GitHub shows it", ["-c", _CONTROLLERS_MD]),
    ("7", "raw --8<-- include lines in docs/*.md", ["-c", _RAW_INCLUDES]),
    ("7", "the pair count in the docs and the model", ["-c", _PAIR_COUNT]),
    ("7", "py.typed and CITATION.cff",
     ["-c", "import pathlib; r = pathlib.Path('{checkout}'); "
            "print('py.typed:', (r / 'softhand/py.typed').exists(), '; CITATION.cff:', "
            "(r / 'CITATION.cff').exists())"]),
    # 8: pickle and deepcopy
    ("8", "pickle.dumps(env)", ["-c", "import pickle; " + _ENV + "e = E(); e.reset(seed=0); "
                                "print('pickled,', len(pickle.dumps(e)), 'bytes')"]),
    ("8", "copy.deepcopy(env)", ["-c", "import copy; " + _ENV + "e = E(); e.reset(seed=0); "
                                 "copy.deepcopy(e); print('deep-copied')"]),
]

SETUP_34 = {
    "calibrate --class-laws-only, FE folder without the class folders": _setup_class_laws,
    "a .skins.new-* left 10 min ago, then calibrate --class-laws-only --force": _setup_stale_skins,
    "a skin stiffness of 1e300 in pair_laws (env, calibration_dir)": _setup_stiff,
    "transfer.json without the skin's design (env sensor_dir)": _setup_transfer,
    "skin apply on a world plane": _setup_floor,
}
AFTER_34 = {
    "kill -9 a forced fe sweep twice (staging folder left beside calibration/fe)": _after_kill9,
    "calibrate --class-laws-only, FE folder without the class folders": _after_class_laws,
    "a .skins.new-* left 10 min ago, then calibrate --class-laws-only --force": _after_stale_skins,
    "fe export OUT with a 300-character file name": _after_nothing_written,
    "handshake --record with a 300-character file name": _after_nothing_written,
}
#: cases that run several commands, or a whole handshake before the point they check
LIMITS_34 = {
    "kill -9 a forced fe sweep twice (staging folder left beside calibration/fe)": 60.0,
    "population --n 4 complete, then the same with Ctrl-C after the first partners": 150.0,
    "a cached grasp with its x zeroed": 60.0,
    "skin apply: fingertip pressed by a world box and by a mocap box (0.5, 1, 2 mm)": 60.0,
    "a skin stiffness of 1e300 in pair_laws (env, calibration_dir)": 40.0,
    "--cluster tcp://10.255.255.1:8786 (nothing answers)": 40.0,
    "--cluster at a loopback server that answers HTTP": 40.0,
    "MUJOCO_GL=osmesa render (no libOSMesa here)": 40.0,
    "MUJOCO_GL=glfw render without a display": 40.0,
    "handshake --record with a 300-character file name": 40.0,
    "handshake --hand human --sensor-placement bone": 40.0,
}


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


def run_case(checkout: Path, args: list[str], *, setup=None, after=None,
             limit_s: float = LIMIT_S) -> dict:
    """Run one case; ``setup(tmp, cal)`` prepares its inputs (set 34: a scratch folder of its
    own, no copies of the FE folder), ``after(tmp, cal)`` says what the run left behind."""
    cal = checkout / "calibration"
    if setup is None:
        tmp = scratch(checkout)
    else:
        tmp = Path(tempfile.mkdtemp(prefix="softhand-fuzz-"))
        setup(tmp, cal)
    env = {**os.environ, "PYTHONPATH": str(checkout), "OMP_NUM_THREADS": "1",
           "MUJOCO_GL": "egl"}
    if setup is not None:  # set 34: solved grasps kept per checkout, out of the user's cache
        env["SOFTHAND_CACHE_DIR"] = str(Path(tempfile.gettempdir()) / "softhand-fuzz34-cache"
                                        / checkout.name)
    env.pop("SOFTHAND_TRACEBACK", None)
    words = []
    for a in args:
        if a.startswith("@-"):  # unset a variable (MUJOCO_GL, DISPLAY)
            env.pop(a[2:], None)
            continue
        if a.startswith("@"):
            key, _, value = a[1:].partition("=")
            env[key] = value
            continue
        words.append(a.format(tmp=tmp, cal=cal, checkout=checkout))
    cmd = ([sys.executable, *words] if words[0] == "-c" else
           [sys.executable, "-c", "from softhand.cli import run; run()", *words])
    before = sha_tree(cal)
    t0 = time.perf_counter()
    # set 34: SIGINT at its default in the case (and its children), so that a case that sends
    # Ctrl-C works when this tool runs where SIGINT is ignored (nohup, a background job)
    default_sigint = None if setup is None else (
        lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    proc = subprocess.Popen(cmd, env=env, cwd=tmp, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, start_new_session=True,
                            preexec_fn=default_sigint)
    try:
        out, _ = proc.communicate(timeout=limit_s)
        rc = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)  # the command and its worker processes
        out, _ = proc.communicate()
        rc = None
    wall = time.perf_counter() - t0
    changed = sorted(set(before.items()) ^ set(sha_tree(cal).items()))
    if setup is not None:  # set 34: staging folders (.fe.new-*) are what some cases report
        changed = [c for c in changed if not c[0].startswith(".")]
    left = after(tmp, cal) if after is not None else None
    lines = [ln for ln in out.replace("\r", "\n").splitlines() if ln.strip()]
    last = next((ln for ln in reversed(lines) if not ln.startswith(("fe sweep", "calibrate"))
                 and "%|" not in ln), "")
    shutil.rmtree(tmp, ignore_errors=True)
    if changed or any(p.name.startswith(".") for p in cal.iterdir()):
        # put the checkout's shipped data back for the next case, staging folders removed
        subprocess.run(["git", "-C", str(checkout), "checkout", "--", "calibration"], check=False)
        subprocess.run(["git", "-C", str(checkout), "clean", "-fdq", "calibration"], check=False)
    return {"rc": rc, "wall_s": round(wall, 1), "last_line": last[:300],
            "traceback": "Traceback" in out, "internal": "internal error" in out,
            "warning_lines": sum("warning" in ln.lower() for ln in lines),
            "calibration_changed": len({c[0] for c in changed}),
            **({"limit_s": limit_s} if limit_s != LIMIT_S else {}),
            **({"left": left} if left is not None else {})}


def outcome(r: dict, width: int = 160) -> str:
    if r["rc"] is None:
        what = f"still working after {r.get('limit_s', LIMIT_S):.0f} s (the work started)"
    elif r["traceback"]:  # an API case (python -c): the exception the caller gets
        what = "raises"
    else:
        what = f"exit {r['rc']} in {r['wall_s']:g} s"
    if r["calibration_changed"]:
        what += f"; {r['calibration_changed']} shipped files changed"
    if r["warning_lines"] > 1:
        what += f"; {r['warning_lines']} warning lines"
    line = r["last_line"].replace("|", "\\|")
    what = f"{what}: `{line[:width]}`" if line else what
    return f"{what}; {r['left']}" if r.get("left") else what


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
    for p in (run, tab):
        p.add_argument("--cases", choices=["20", "34"], default="20",
                       help="the cases of issue 20 (default) or of issue 34")
    a = ap.parse_args()
    cases = CASES_34 if a.cases == "34" else CASES
    width = 240 if a.cases == "34" else 160
    if a.cmd == "run":
        results = json.loads(a.out.read_text()) if a.merge and a.out.exists() else {}
        for item, name, args in cases:
            if a.only and a.only not in name:
                continue
            extra = {} if a.cases == "20" else {
                "setup": SETUP_34.get(name, lambda tmp, cal: None), "after": AFTER_34.get(name),
                "limit_s": LIMITS_34.get(name, LIMIT_S)}
            results[name] = {"item": item, **run_case(a.checkout.resolve(), args, **extra)}
            print(f"[{item}] {name}: {outcome(results[name], width)}", file=sys.stderr,
                  flush=True)
            a.out.write_text(json.dumps(results, indent=1))
        a.out.write_text(json.dumps(results, indent=1))
        return
    old, new = json.loads(a.old.read_text()), json.loads(a.new.read_text())
    print("| item | case | old outcome | new outcome |\n|---|---|---|---|")
    for item, name, _ in cases:
        if name in new:
            was = outcome(old[name], width) if name in old else "-"
            print(f"| {item} | {name} | {was} | {outcome(new[name], width)} |")


if __name__ == "__main__":
    main()
