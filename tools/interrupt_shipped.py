"""Ctrl-C on `softhand fe sweep --max-force 20 --max-depth 7 --force` (the shipped settings) after
2 of 12 designs: calibration/ must stay byte-identical. Usage: python tools/interrupt_shipped.py CHECKOUT
(a throw-away clone: with an old version the sweep would replace its shipped data)."""
import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

repo = Path(sys.argv[1])
cal = repo / "calibration"

def tree():
    return {str(p.relative_to(cal)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(cal.rglob("*")) if p.is_file() and "__pycache__" not in p.parts}

def digest(t):
    return hashlib.sha256("".join(f"{k} {v}\n" for k, v in t.items()).encode()).hexdigest()

before = tree()
print(f"before: {len(before)} files, sha256 of the listing {digest(before)}")
t0 = time.time()
proc = subprocess.Popen([sys.executable, "-m", "softhand.cli", "fe", "sweep", "--max-force", "20",
                         "--max-depth", "7", "--force"], cwd=repo, stderr=subprocess.PIPE,
                        stdout=subprocess.PIPE, text=True, start_new_session=True)
seen = ""
while "2/12" not in seen:
    ch = proc.stderr.read(1)
    if not ch:
        break
    seen += ch
print(f"2 of 12 designs finished after {time.time() - t0:.0f} s: SIGINT to the process group")
os.killpg(proc.pid, signal.SIGINT)
out, err = proc.communicate(timeout=120)
print(f"exit {proc.returncode}; last line: {(seen + err).strip().splitlines()[-1]}")
after = tree()
print(f"after: {len(after)} files, sha256 of the listing {digest(after)}")
print("byte-identical" if after == before else f"CHANGED: {set(before.items()) ^ set(after.items())}")
print("left in calibration/:", sorted(p.name for p in cal.iterdir()))
