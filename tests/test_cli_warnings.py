"""Warnings on the command line (issue 20, item 6): each kind once, with its count, and warnings
from worker processes brought back to the main process instead of printed by each worker."""

from __future__ import annotations

import textwrap
import warnings

import pytest
from click.testing import CliRunner

from softhand.cli import _warnings_summarised, main
from softhand.envs.skins import CalibratedRangeWarning
from softhand.parallel import run_tasks
from softhand.skin.rig import SkinRangeWarning


def test_each_kind_prints_once_with_its_count(capsys):
    with _warnings_summarised():
        for i in range(3):
            warnings.warn(f"episode {i}: beyond range", CalibratedRangeWarning, stacklevel=1)
        warnings.warn("304 skin pairs are outside their calibrated range", SkinRangeWarning,
                      stacklevel=1)
    assert capsys.readouterr().err.splitlines() == [
        "warning (CalibratedRangeWarning) x3: episode 0: beyond range (and 2 more like it)",
        "warning (SkinRangeWarning): 304 skin pairs are outside their calibrated range"]


def test_the_summary_prints_when_the_command_fails_and_filters_still_apply(capsys):
    with pytest.raises(KeyboardInterrupt), _warnings_summarised():
        warnings.warn("before the interrupt", CalibratedRangeWarning, stacklevel=1)
        raise KeyboardInterrupt
    assert capsys.readouterr().err == ("warning (CalibratedRangeWarning): before the "
                                       "interrupt\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", CalibratedRangeWarning)  # -W error still makes it an error
        with pytest.raises(CalibratedRangeWarning), _warnings_summarised():
            warnings.warn("an error now", CalibratedRangeWarning, stacklevel=1)


@pytest.mark.slow
def test_handshake_outside_the_calibrated_timestep_prints_one_line_per_kind():
    """``softhand handshake --timestep 0.005`` (inside the help's range) printed 385 warning
    lines (383 SkinRangeWarning, one per pair, and 2 CalibratedRangeWarning); now one line per
    kind (the CalibratedRangeWarning only where a contact went beyond its law's range: on the
    arms' handshake at 5 ms none does)."""
    res = CliRunner().invoke(main, ["handshake", "--timestep", "0.005", "--json"])
    assert res.exit_code == 0, res.output
    lines = [line for line in res.stderr.splitlines() if line.startswith("warning")]
    kinds = [line.split(":")[0] for line in lines]
    assert kinds[0] == "warning (SkinRangeWarning)" and len(kinds) == len(set(kinds)), lines
    assert set(kinds) <= {"warning (SkinRangeWarning)", "warning (CalibratedRangeWarning)"}
    assert "timestep 5 ms is outside the calibrated range 0.5-2 ms" in lines[0]
    assert all(line.startswith("warning (CalibratedRangeWarning): episode ended at t = ")
               for line in lines[1:]), lines


def test_warnings_from_worker_processes_come_back_once(tmp_path, monkeypatch):
    """Before, each worker printed its warnings itself, in Python's two-line format, past the
    command line's summary, and the main process saw none; now they come back with the results:
    a warning every task raises shows once per batch, a task's own warning once each."""
    (tmp_path / "warning_tasks.py").write_text(textwrap.dedent("""
        import warnings
        from softhand.envs.skins import CalibratedRangeWarning

        def task(i):
            warnings.warn("the same in every task", CalibratedRangeWarning)
            warnings.warn(f"task {i}'s own", CalibratedRangeWarning)
            return i
    """))
    monkeypatch.syspath_prepend(str(tmp_path))  # spawned workers get this process's sys.path
    from warning_tasks import task

    with warnings.catch_warnings(record=True) as caught:
        out = run_tasks(task, [(i, (i,)) for i in range(4)], threads=2)
    assert out.complete and sorted(out.results) == [0, 1, 2, 3]
    texts = sorted(str(w.message) for w in caught)
    assert texts == ["task 0's own", "task 1's own", "task 2's own", "task 3's own",
                     "the same in every task"], texts
    assert all(w.category is CalibratedRangeWarning and w.filename.endswith("warning_tasks.py")
               for w in caught)
