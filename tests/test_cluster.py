"""Batches on a Dask distributed cluster (``--cluster``) against the local default (joblib's loky
workers): the same curves, progress once per task, failures and warnings as locally, Ctrl-C, and a
bad address refused before any work, in one line.

One ``LocalCluster`` of 2 single-threaded worker processes serves the module (a second or two to
start); the FE runs are 2D, coarse, no hold, to 2 N (under a second each, but a worker's first
import of the FE stage and the local workers' start make those tests 3-12 s: marked slow, like the
Ctrl-C test, whose task left running on a worker makes the cluster's shutdown take 4 s).
"""

from __future__ import annotations

import json
import math
import socket
import sys
import textwrap
import warnings

import pytest
from click.testing import CliRunner
from conftest import interrupt_when, start_interruptible

import softhand.parallel
from softhand.cli import main
from softhand.fem.solver import IndentationSettings, indent
from softhand.fem.sweep import curve_csv
from softhand.parallel import TaskError, run_tasks

DESIGNS = ["pocket2-sil", "solid-pu"]
SETTINGS = IndentationSettings(mode="2d", mesh="coarse", hold_s=0.0, max_force_N=2.0, threads=1)
FAST = ["--mode", "2d", "--mesh", "coarse", "--hold", "0", "--max-force", "2"]


@pytest.fixture(scope="module")
def cluster() -> str:
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as c:
        yield c.scheduler_address


@pytest.fixture(scope="module")
def local() -> dict:
    """The 2 designs on 2 local worker processes (the default backend)."""
    done = []
    out = run_tasks(indent, [(d, (d, SETTINGS)) for d in DESIGNS], threads=2,
                    on_done=lambda key, ok: done.append((key, ok)))
    assert out.complete and sorted(done) == [(d, True) for d in DESIGNS]
    return out.results


def _unused_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_a_sweep_on_the_cluster_gives_the_local_curves_and_progress_per_task(cluster, local):
    done = []
    out = run_tasks(indent, [(d, (d, SETTINGS)) for d in DESIGNS], cluster=cluster,
                    on_done=lambda key, ok: done.append((key, ok)))
    assert out.complete and not out.interrupted
    assert list(out.results) == DESIGNS  # input order, whatever finished first
    assert sorted(done) == [(d, True) for d in DESIGNS]  # once per task
    for name in DESIGNS:
        a, b = local[name], out.results[name]
        for field in ("time_s", "displacement_mm", "force_N", "hold"):
            assert getattr(a, field).tolist() == getattr(b, field).tolist(), (name, field)


def test_failures_and_warnings_come_back_as_from_local_workers(cluster):
    out = run_tasks(math.sqrt, [("a", (4.0,)), ("b", (-1.0,)), ("c", (9.0,))], cluster=cluster)
    assert out.results == {"a": 2.0, "c": 3.0} and out.missing == []
    assert isinstance(out.errors["b"], TaskError) and out.errors["b"].kind == "ValueError"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        out = run_tasks(warnings.warn, [(i, ("the same in every task",)) for i in range(4)],
                        cluster=cluster)
    assert out.complete
    assert [str(w.message) for w in caught] == ["the same in every task"]  # once per batch


def test_a_bad_cluster_is_refused_before_any_task(monkeypatch):
    started = []
    with pytest.raises(ValueError, match=r"cluster '127\.0\.0\.1:8786': not of the form "
                                         r"SCHEME://HOST:PORT.*tcp://HOST:PORT"):
        run_tasks(math.sqrt, [(1, (1.0,))], cluster="127.0.0.1:8786",
                  on_done=lambda *a: started.append(a))
    monkeypatch.setattr(softhand.parallel, "CLUSTER_TIMEOUT_S", 0.5)
    address = f"tcp://127.0.0.1:{_unused_port()}"
    with pytest.raises(ValueError, match=r"no Dask scheduler answered within 0\.5 s"):
        run_tasks(math.sqrt, [(1, (1.0,))], cluster=address, on_done=lambda *a: started.append(a))
    with socket.socket() as mute:  # accepts connections, never answers (Client's own timeout
        mute.bind(("127.0.0.1", 0))  # did not end this wait)
        mute.listen()
        with pytest.raises(ValueError, match=r"no Dask scheduler answered within 0\.5 s"):
            run_tasks(math.sqrt, [(1, (1.0,))],
                      cluster=f"tcp://127.0.0.1:{mute.getsockname()[1]}")
    with pytest.raises(ValueError, match="tls:// needs the TLS settings"):
        run_tasks(math.sqrt, [(1, (1.0,))], cluster="tls://127.0.0.1:8786")
    with pytest.raises(ValueError, match="allowed one of the two"):
        run_tasks(math.sqrt, [(1, (1.0,))], threads=2, cluster=address)
    assert started == []


@pytest.mark.slow
def test_fe_sweep_on_the_cluster_writes_the_local_curves(cluster, local, tmp_path):
    args = ["fe", "sweep", *FAST, "--cluster", cluster, "--out", str(tmp_path)]
    for d in DESIGNS:
        args += ["--design", d]
    res = CliRunner().invoke(main, args, catch_exceptions=False)
    assert res.exit_code == 0, res.output
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["complete"] and sorted(summary["designs"]) == DESIGNS
    for name in DESIGNS:  # the CSV a local run writes, byte for byte
        assert (tmp_path / f"{name}.csv").read_text() == curve_csv(local[name])


@pytest.fixture
def no_work(monkeypatch):
    def forbidden(*args, **kwargs):
        raise AssertionError("work started before the input was rejected")

    import softhand.fem.sweep
    import softhand.skin.run

    for module in (softhand.parallel, softhand.fem.sweep, softhand.skin.run):
        monkeypatch.setattr(module, "run_tasks", forbidden)


def _rejected(args: list[str], *needles: str) -> str:
    res = CliRunner().invoke(main, args)
    line = res.output.strip()
    assert res.exit_code == 2, (res.exit_code, res.output, res.exception)
    assert "\n" not in line and line.startswith("error: --"), res.output
    assert "Traceback" not in res.output and "Usage:" not in res.output
    for needle in needles:
        assert needle in line, (needle, line)
    return line


@pytest.mark.parametrize("command", [["fe", "sweep", *FAST], ["calibrate"],
                                     ["sensors", "calibrate"], ["population", "--n", "2"]])
def test_every_batch_command_refuses_a_malformed_cluster_in_one_line(command, no_work, tmp_path):
    line = _rejected([*command, "--out", str(tmp_path / "out"), "--cluster", "localhost:8786"],
                     "--cluster 'localhost:8786'", "tcp://HOST:PORT")
    assert line.startswith("error: --cluster 'localhost:8786': not of the form")


def test_an_unreachable_cluster_and_cluster_with_threads_are_refused(no_work, monkeypatch,
                                                                     tmp_path):
    monkeypatch.setattr(softhand.parallel, "CLUSTER_TIMEOUT_S", 0.5)
    address = f"tcp://127.0.0.1:{_unused_port()}"
    _rejected(["fe", "sweep", *FAST, "--out", str(tmp_path), "--cluster", address],
              f"--cluster {address!r}: no Dask scheduler answered within 0.5 s")
    _rejected(["population", "--workers", "1", "--cluster", "tcp://[::1"], "--cluster")
    monkeypatch.setattr(softhand.parallel, "check_cluster", lambda address, name: address)
    _rejected(["population", "--workers", "1", "--cluster", address, "--out", str(tmp_path)],
              f"--workers 1 with --cluster {address!r}", "allowed one of the two")


@pytest.mark.slow
def test_a_population_sweep_on_the_cluster_gives_the_local_results(cluster, tmp_path):
    """2 partners x 2 skins x 1 controller through the command line, on 2 local worker processes
    and on the cluster: the same combinations, partners and per-region peak and mean forces,
    exactly."""
    sweep = ["population", "--n", "2", "--design", "pocket2-sil", "--design", "solid-pu",
             "--controller", "neutral"]
    listed = {}
    for where, flags in (("local", ["--workers", "2"]), ("cluster", ["--cluster", cluster])):
        res = CliRunner().invoke(main, [*sweep, *flags, "--out", str(tmp_path / where)],
                                 catch_exceptions=False)
        assert res.exit_code == 0, res.output
        listed[where] = json.loads((tmp_path / where / "sweep.json").read_text())["combinations"]
    assert listed["local"] == listed["cluster"]
    assert [c["folder"] for c in listed["local"]] == ["pocket2-sil-neutral", "solid-pu-neutral"]
    for combination in listed["local"]:
        local, remote = (json.loads((tmp_path / where / combination["folder"] / "results.json")
                                    .read_text()) for where in ("local", "cluster"))
        assert local["summary"] == remote["summary"]
        assert len(local["partners"]) == 2
        for a, b in zip(local["partners"], remote["partners"], strict=True):
            assert a["partner"] == b["partner"]
            assert a["peak_N"] == b["peak_N"] and a["mean_N"] == b["mean_N"], a["partner"]


@pytest.mark.slow
def test_ctrl_c_keeps_the_finished_task_and_drops_the_running_one(cluster, tmp_path):
    """As locally (test_interrupts), except that the task running on a worker runs on there: a
    thread cannot be stopped. Last in the module: that task holds one of the two workers."""
    script = tmp_path / "batch.py"
    script.write_text(textwrap.dedent(f"""
        import json, sys, time
        from softhand.parallel import run_tasks

        out = run_tasks(time.sleep, [("fast", (0.05,)), ("slow", (600.0,))],
                        cluster={cluster!r}, on_done=lambda key, ok: print("done", key, flush=True))
        print(json.dumps({{"results": out.results, "missing": out.missing,
                          "interrupted": out.interrupted}}), flush=True)
        sys.exit(130 if out.interrupted else 0)
    """))
    proc = start_interruptible([sys.executable, str(script)])
    out, err = interrupt_when(proc, proc.stdout, "done fast")
    assert proc.returncode == 130, err
    outcome = json.loads(out[out.index('{"results"'):].strip())
    assert outcome == {"results": {"fast": None}, "missing": ["slow"], "interrupted": True}
    assert "Traceback" not in err


def test_an_address_that_answers_but_not_as_dask_is_not_a_dask_scheduler(capfd):
    """A peer that answers in another protocol (here a server on the loopback that writes a few
    bytes of HTTP) was refused with "MemoryError: Unable to allocate 3.07 EiB" (its bytes read
    as a frame length), and the half-made client printed a traceback at exit: now one
    ValueError, "not a Dask scheduler", and nothing else on stderr."""
    import gc
    import socket
    import threading

    from softhand.parallel import check_cluster

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    port = server.getsockname()[1]

    def serve() -> None:
        while True:
            try:
                conn, _ = server.accept()
                conn.sendall(b"HTTP/1.1 200 OK\r\n\r\n" + b"\xff" * 64)
            except OSError:
                return

    threading.Thread(target=serve, daemon=True).start()
    try:
        with pytest.raises(ValueError, match=rf"--cluster 'tcp://127.0.0.1:{port}': not a Dask "
                                             r"scheduler \(something answers there"):
            check_cluster(f"tcp://127.0.0.1:{port}", name="--cluster")
        gc.collect()
    finally:
        server.close()
    assert "Traceback" not in capfd.readouterr().err
