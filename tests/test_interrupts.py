"""Ctrl-C (SIGINT to the process group): batches stop, keep what finished, exit 130, no partial file.

The signal is sent the way a terminal sends it: to every process of the group, workers included.
The timeouts below only guard against a hang (a worker left running would take minutes); how fast a
batch stops is measured by hand (docs/reliability.md), not asserted.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from conftest import HANG_S, interrupt_when, start_interruptible


def test_run_tasks_keeps_the_finished_task_and_stops_the_running_one(tmp_path):
    (tmp_path / "naps.py").write_text("import time\n\ndef nap(s):\n    time.sleep(s)\n"
                                      "    return s\n")
    script = tmp_path / "batch.py"
    script.write_text(textwrap.dedent("""
        import json, sys
        from naps import nap
        from softhand.parallel import run_tasks

        if __name__ == "__main__":
            out = run_tasks(nap, [("fast", (0.05,)), ("slow", (600.0,))], threads=2,
                            on_done=lambda key, ok: print("done", key, flush=True))
            print(json.dumps({"results": out.results, "missing": out.missing,
                              "interrupted": out.interrupted}), flush=True)
            sys.exit(130 if out.interrupted else 0)
    """))
    env = {**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    proc = start_interruptible([sys.executable, str(script)], env=env, cwd=tmp_path)
    out, err = interrupt_when(proc, proc.stdout, "done fast")
    assert proc.returncode == 130, err
    outcome = json.loads(out[out.index('{"results"'):].strip())
    assert outcome == {"results": {"fast": 0.05}, "missing": ["slow"], "interrupted": True}


@pytest.mark.slow
def test_fe_sweep_writes_the_finished_design_and_lists_the_missing_one(tmp_path):
    out_dir = tmp_path / "fe"
    proc = start_interruptible([sys.executable, "-m", "softhand.cli", "fe", "sweep", "--mode", "2d",
                   "--mesh", "fine", "--hold", "0", "--max-force", "10", "--threads", "2",
                   "--design", "solid-pu", "--design", "pocket2-sil", "--out", str(out_dir)])
    _, err = interrupt_when(proc, proc.stderr, "1/2")
    assert proc.returncode == 130, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("interrupted (Ctrl-C): wrote 1 of 2 designs") and "pocket2-sil" in last
    summary = json.loads((out_dir / "summary.json").read_text())
    assert summary["complete"] is False
    assert summary["missing"] == {"pocket2-sil": "interrupted"}
    assert list(summary["designs"]) == ["solid-pu"]
    assert sorted(p.name for p in out_dir.iterdir()) == ["solid-pu.csv", "summary.json"]
    assert "Traceback" not in err


def test_interrupted_single_run_writes_nothing(tmp_path):
    out_dir = tmp_path / "out"
    proc = start_interruptible([sys.executable, "-m", "softhand.cli", "fe", "indent", "pocket2-sil",
                   "--mode", "2d", "--mesh", "fine", "--max-force", "10", "--out", str(out_dir)])
    _, err = interrupt_when(proc, proc.stderr, "pocket2-sil:")
    assert proc.returncode == 130
    assert err.strip().splitlines()[-1] == "interrupted (Ctrl-C); nothing was written"
    assert not out_dir.exists()


def test_no_temporary_file_is_left_by_an_interrupted_write(tmp_path):
    """atomic_open: an exception inside the block removes the temp file; the old file stays."""
    from softhand.io import atomic_write_text

    target = tmp_path / "f.txt"
    atomic_write_text(target, "old")

    class Boom(BaseException):
        pass

    from softhand.io import atomic_open

    with pytest.raises(Boom), atomic_open(target) as fh:
        fh.write("new, half")
        raise Boom
    assert target.read_text() == "old"
    assert [p.name for p in Path(tmp_path).iterdir()] == ["f.txt"]


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return f"{pid} (gone)"


def _session_processes(session: int) -> list[int]:
    """Pids of the live processes whose session id is ``session`` (Linux /proc)."""
    pids = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2:].split()
        if fields[0] != "Z" and int(fields[3]) == session:  # state, ppid, pgrp, session
            pids.append(int(entry.name))
    return pids


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_sigterm_to_the_command_alone_stops_its_workers_too(tmp_path):
    """SIGTERM to the main process only (a kill, a scheduler's limit), not the group: the sweep
    stops as on Ctrl-C, keeps the finished design, exits 130 and leaves no worker running (before,
    the default action killed the main process alone and its two workers ran on as orphans)."""
    out_dir = tmp_path / "fe"
    proc = start_interruptible([sys.executable, "-m", "softhand.cli", "fe", "sweep", "--mode", "2d",
                   "--mesh", "fine", "--hold", "0", "--max-force", "10", "--threads", "2",
                   "--design", "solid-pu", "--design", "pocket2-sil", "--out", str(out_dir)])
    seen = ""
    while "1/2" not in seen:
        ch = proc.stderr.read(1)
        if not ch:
            break
        seen += ch
    assert "1/2" in seen, seen[-500:]
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 130, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("interrupted (SIGTERM): wrote 1 of 2 designs"), last
    assert sorted(p.name for p in out_dir.iterdir()) == ["solid-pu.csv", "summary.json"]
    # the workers are killed before the main process exits; the resource trackers (helpers of
    # joblib's loky and of multiprocessing) exit when they see the main process's pipe close,
    # which on a loaded machine is a moment later (seen once: one process left at the first look)
    deadline = time.monotonic() + 5.0
    while _session_processes(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    left = _session_processes(proc.pid)
    assert left == [], [_cmdline(pid) for pid in left]


def test_a_ctrl_c_held_while_writing_says_the_files_were_written(tmp_path):
    """A Ctrl-C during a write block (softhand.io.interrupts_deferred) waits for the block, and
    the line says that what finished was written, not "nothing was written"."""
    script = textwrap.dedent(f"""
        import os, signal, click
        from softhand.cli import _Softhand
        from softhand.io import atomic_write_text, interrupts_deferred

        group = _Softhand()

        @group.command()
        def write():
            with interrupts_deferred():
                os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C in the middle of the writes
                atomic_write_text({str(tmp_path / "a.txt")!r}, "a")
                atomic_write_text({str(tmp_path / "b.txt")!r}, "b")
            atomic_write_text({str(tmp_path / "after.txt")!r}, "never")

        group.main(["write"])
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=HANG_S)
    assert proc.returncode == 130, proc.stderr
    assert proc.stderr.strip().splitlines()[-1] == (
        "interrupted (Ctrl-C) while writing: what had finished was written, each file whole")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt"]
    assert "Traceback" not in proc.stderr


def test_a_staging_folder_left_by_a_killed_run_is_removed_by_the_next(tmp_path):
    """kill -9 during a staged write leaves ``.NAME.new-*`` beside the set (nothing can clean
    up); the next staged write there removes it with a warning, keeps a live run's, and puts
    the set back when a run was killed between a commit's two renames."""
    import subprocess
    import warnings

    from softhand.io import StaleStageWarning, remove_stale_stages, staged_folder

    target = tmp_path / "skins"
    target.mkdir()
    (target / "a.json").write_text("old", encoding="utf-8")
    proc = subprocess.Popen(["sleep", "0"])
    proc.wait()
    killed = tmp_path / ".skins.new-killed"
    (killed / "skins").mkdir(parents=True)
    (killed / "owner.pid").write_text(str(proc.pid), encoding="utf-8")
    live = tmp_path / ".skins.new-live"
    live.mkdir()
    (live / "owner.pid").write_text(str(os.getppid()), encoding="utf-8")
    with (pytest.warns(StaleStageWarning, match="skins.new-killed"),
          staged_folder(target, stage=True) as staged):
        (staged.path / "a.json").write_text("new", encoding="utf-8")
        staged.commit()
    assert not killed.exists() and live.exists()
    assert (target / "a.json").read_text(encoding="utf-8") == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == [".skins.new-live", "skins"]
    # killed between the renames: the set sits in .skins.old-*, skins/ is gone
    old = tmp_path / ".skins.old-killed"
    old.mkdir()
    (old / "owner.pid").write_text(str(proc.pid), encoding="utf-8")
    os.rename(target, old / "skins")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        remove_stale_stages(target)
    assert (target / "a.json").read_text(encoding="utf-8") == "new" and not old.exists()
    assert any("put back" in str(w.message) for w in caught)
