"""eyeshell.sweep: the command line's sweep, run on threads, in processes and on Dask."""

import concurrent.futures
import concurrent.futures.process
import json
import os
import pathlib
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import eyeshell
from conftest import SCENES, optional, read_csv

# Four short growth runs (the fibre stiffness D), each as the command line would run it.
FIBRES = {"fibres.D": [0, 100, 200, 400]}


def small():
    return eyeshell.Scene.from_file(SCENES / "const.toml", solver__nodes=101, output__history_points=0)


def axial(results):
    return {r.name: r.result.series["axial_length"] for r in results}


def test_a_sweep_file_matches_the_command_lines_sweep(cli, tmp_path):
    cli("sweep", SCENES / "grow.toml", "--set", "solver.nodes=101", "--out", tmp_path / "s",
        "--quiet")
    results = eyeshell.sweep(SCENES / "grow.toml", jobs=2, **{"solver.nodes": 101})
    table = read_csv(tmp_path / "s" / "sweep.csv")
    assert [r.name for r in results] == table["run"]
    for i, r in enumerate(results):
        assert r.ok and list(r.values) == ["growth.Gamma", "growth.delta"]
        for key, value in r.values.items():
            assert float(value) == table[key][i]
        assert np.asarray(r.result.series["axial_length"])[-1] == table["axial_length"][i]
        series = read_csv(tmp_path / "s" / "runs" / r.name / "series.csv")
        for column, values in series.items():
            got = np.asarray(r.result.series[column])
            assert np.array_equal(got, np.asarray(values), equal_nan=got.dtype.kind == "f"), (r.name, column)


def test_grid_and_runs_on_a_scene():
    results = eyeshell.sweep(small(), grid=FIBRES, runs=[{"name": "thin", "material.H0": 0.5}])
    assert [r.name for r in results] == ["thin_D=0", "thin_D=100", "thin_D=200", "thin_D=400"]
    for r, d in zip(results, FIBRES["fibres.D"]):
        alone = eyeshell.grow(small(), frames=False, material__H0=0.5, fibres__D=d)
        assert np.array_equal(r.result.series["axial_length"], alone.series["axial_length"])
    assert all(r.result.scene["material.H0"] == 0.5 for r in results)


def test_results_come_as_they_finish():
    finished = [r.name for r in eyeshell.iter_sweep(small(), grid=FIBRES, jobs=2)]
    assert sorted(finished) == ["D=0", "D=100", "D=200", "D=400"]


def test_a_process_pool_gives_the_local_results():
    local = eyeshell.sweep(small(), grid=FIBRES, jobs=2)
    with concurrent.futures.ProcessPoolExecutor(max_workers=2) as pool:
        remote = eyeshell.sweep(small(), grid=FIBRES, executor=pool)
    assert [r.name for r in remote] == [r.name for r in local]
    for a, b in zip(local, remote):
        for column in ["t", "axial_length", "equatorial_radius"]:
            assert np.array_equal(a.result.series[column], b.result.series[column], equal_nan=np.asarray(a.result.series[column]).dtype.kind == "f")


def test_dask_gives_the_local_results():
    distributed = optional("distributed")
    local = eyeshell.sweep(SCENES / "grow.toml", jobs=2, solver__nodes=101)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, host="127.0.0.1") as cluster, \
            distributed.Client(cluster) as client:
        remote = eyeshell.sweep(SCENES / "grow.toml", executor=client, solver__nodes=101)
    assert [r.name for r in remote] == [r.name for r in local]
    for a, b in zip(local, remote):
        assert a.values == b.values and b.ok
        assert json.dumps(a.result.summary["final"]) == json.dumps(b.result.summary["final"])
        for column in ["t", "axial_length", "equatorial_radius", "retina_minus_blue"]:
            assert np.array_equal(a.result.series[column], b.result.series[column], equal_nan=np.asarray(a.result.series[column]).dtype.kind == "f")
        for t, fields in a.result.snapshots.items():
            assert np.array_equal(fields["r"], b.result.snapshots[t]["r"])


# A run that aborts its process (an allocation that fails, a stack overflow: no exception
# to catch) fails alone. EYESHELL_TEST_ABORT_RUN makes the worker given that run abort.

ABORTED = "the run's process ended abnormally (killed by signal 6: SIGABRT; out of memory or a stack overflow?)"


def test_a_run_that_aborts_fails_alone_and_the_others_are_kept(monkeypatch):
    monkeypatch.setenv("EYESHELL_TEST_ABORT_RUN", "D=100")
    results = eyeshell.sweep(small(), grid=FIBRES, jobs=2)
    assert [r.status for r in results] == ["ok", "failed", "ok", "ok"]
    assert results[1].error == ABORTED and results[1].result is None
    assert results[1].values == {"fibres.D": 100.0}
    monkeypatch.delenv("EYESHELL_TEST_ABORT_RUN")
    for r in [results[0], results[2], results[3]]:
        alone = eyeshell.grow(small(), frames=False, fibres__D=float(r.values["fibres.D"]))
        assert np.array_equal(r.result.series["axial_length"], alone.series["axial_length"])


@pytest.mark.parametrize("jobs", [1, 3])
def test_after_an_abort_the_next_runs_get_a_new_process(monkeypatch, jobs):
    # The first run aborts: with one job, every other run goes to the worker started after.
    monkeypatch.setenv("EYESHELL_TEST_ABORT_RUN", "D=0")
    results = eyeshell.sweep(small(), grid=FIBRES, jobs=jobs)
    assert [r.status for r in results] == ["failed", "ok", "ok", "ok"]
    assert results[0].error == ABORTED


def test_a_sweep_whose_only_run_aborts_returns_its_failure(monkeypatch):
    monkeypatch.setenv("EYESHELL_TEST_ABORT_RUN", "lone")
    results = eyeshell.sweep(small(), runs=[{"name": "lone"}], jobs=1)
    assert [(r.name, r.status, r.error) for r in results] == [("lone", "failed", ABORTED)]
    # The iterator yields it as well, and the next sweep starts afresh.
    assert [r.status for r in eyeshell.iter_sweep(small(), runs=[{"name": "lone"}])] == ["failed"]
    monkeypatch.delenv("EYESHELL_TEST_ABORT_RUN")
    assert [r.status for r in eyeshell.sweep(small(), runs=[{"name": "lone"}])] == ["ok"]


def test_an_abort_in_a_process_pool_is_a_failed_run_not_a_broken_pool(monkeypatch):
    monkeypatch.setenv("EYESHELL_TEST_ABORT_RUN", "D=200")
    with concurrent.futures.ProcessPoolExecutor(max_workers=2) as pool:
        results = eyeshell.sweep(small(), grid=FIBRES, executor=pool)
        # The pool is whole: it runs another sweep.
        again = eyeshell.sweep(small(), grid={"fibres.D": [200, 400]}, executor=pool)
    assert [r.status for r in results] == ["ok", "ok", "failed", "ok"]
    assert results[2].error == ABORTED
    assert [r.status for r in again] == ["failed", "ok"]
    assert np.array_equal(again[1].result.series["axial_length"],
                          results[3].result.series["axial_length"])


def test_a_run_the_executor_loses_is_a_failed_run():
    # An executor whose task dies with its process (here: a pool whose process exits).
    class Losing(concurrent.futures.ThreadPoolExecutor):
        def submit(self, fn, *args):
            if args[1] == "D=100":
                return super().submit(lambda: (_ for _ in ()).throw(
                    concurrent.futures.process.BrokenProcessPool("a process died")))
            return super().submit(fn, *args)

    with Losing(max_workers=2) as pool:
        results = eyeshell.sweep(small(), grid=FIBRES, executor=pool)
    assert [r.status for r in results] == ["ok", "failed", "ok", "ok"]
    assert results[1].error == "the executor did not run it: BrokenProcessPool: a process died"


def test_dask_records_an_aborted_run_as_failed(monkeypatch):
    distributed = optional("distributed")
    monkeypatch.setenv("EYESHELL_TEST_ABORT_RUN", "D=100")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=True,
                                  dashboard_address=None, host="127.0.0.1") as cluster, \
            distributed.Client(cluster) as client:
        results = eyeshell.sweep(small(), grid=FIBRES, executor=client)
        assert len(client.scheduler_info()["workers"]) == 1  # the Dask worker lives on
    assert [r.status for r in results] == ["ok", "failed", "ok", "ok"]
    assert results[1].error == ABORTED


def children_of(pid):
    """The pids of the processes whose parent is `pid` (from /proc)."""
    found = []
    for entry in pathlib.Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
    return found


def alive(pid):
    try:
        stat = pathlib.Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


@pytest.mark.skipif(not pathlib.Path("/proc/self/stat").exists(), reason="needs /proc")
def test_the_workers_end_with_a_sweep_that_is_killed():
    # A long sweep killed with SIGKILL (no cleanup runs): its workers see the end of their
    # input and exit, instead of computing on for nobody.
    code = textwrap.dedent(f"""
        import eyeshell
        scene = eyeshell.Scene.from_file({str(SCENES / 'const.toml')!r}, solver__integrator="euler",
                                         solver__steps=100000, solver__nodes=2001)
        print("started", flush=True)
        eyeshell.sweep(scene, grid={{"fibres.D": [0, 100]}}, jobs=2)
    """)
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "started"
    deadline = time.monotonic() + 30
    while len(children_of(child.pid)) < 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    workers = children_of(child.pid)
    assert len(workers) == 2
    time.sleep(1.0)  # the runs are under way
    assert all(alive(w) for w in workers)
    child.kill()
    child.wait()
    deadline = time.monotonic() + 10
    while any(alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(alive(w) for w in workers)


def test_a_worker_s_last_words_are_its_message_not_its_backtrace():
    from eyeshell._worker import _last_line

    text = ("memory allocation of 800000800 bytes failed\nstack backtrace:\n"
            "   0: std::alloc::rust_oom\n             at /rustc/x/alloc.rs:424:5\n"
            "note: Some details are omitted, run with `RUST_BACKTRACE=full` for a verbose backtrace.\n")
    assert _last_line(text) == "memory allocation of 800000800 bytes failed"
    assert _last_line("thread 'main' has overflowed its stack\nfatal runtime error: stack overflow\n\n") \
        == "fatal runtime error: stack overflow"
    assert _last_line("a\x1b[31mred\x07\n") == "a [31mred"
    assert len(_last_line("x" * 1000)) == 300 and _last_line("") == ""


def test_a_run_out_of_memory_fails_alone():
    # A real abort: a run within eyeshell's own bounds (the richardson solve's largest mesh
    # 999,997 nodes, about 2.4 GB) allocates more than the 1 GiB the sweep's processes may
    # map here (the limit is inherited by its workers).
    code = textwrap.dedent("""
        import resource, eyeshell
        resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))
        runs = [{"name": "big", "solver.richardson": True, "solver.nodes": 249997},
                {"name": "small", "solver.nodes": 101}]
        for r in eyeshell.sweep(eyeshell.Scene(), runs=runs, jobs=2):
            print(r.name, r.status, r.error)
    """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    big, small = r.stdout.splitlines()
    assert small == "small ok None"
    assert big.startswith("big failed ")
    # Where the allocation that fails is SUNDIALS', the run fails cleanly in eyeshell's words;
    # where it is Rust's, the worker aborts and the run says how its process ended.
    aborted = "(killed by signal 6: SIGABRT; out of memory or a stack overflow?); its last " \
              "words: memory allocation of "
    assert "out of memory" in big and (aborted not in big or big.endswith(" bytes failed")), big


@pytest.mark.skipif(not pathlib.Path("/proc/self/stat").exists(), reason="needs /proc")
def test_leaving_iter_sweep_early_stops_its_runs_at_once():
    before = set(children_of(os.getpid()))
    scene = eyeshell.Scene.from_file(SCENES / "const.toml", solver__integrator="euler",
                                     solver__nodes=2001, solver__steps=100000)
    runs = [{"name": "quick", "solver.steps": 10, "solver.nodes": 101}] + \
        [{"name": f"long{i}"} for i in range(3)]
    it = eyeshell.iter_sweep(scene, runs=runs, jobs=2)
    assert next(it).name == "quick"
    start = time.perf_counter()
    it.close()
    assert time.perf_counter() - start < 2.0
    # Its workers are ended and reaped: no process of it is left.
    assert set(children_of(os.getpid())) - before == set()


@pytest.mark.parametrize("executable, needle", [
    ("/nonexistent/python", "could not start a process for the run: [Errno 2] No such file or directory"),
    ("/bin/false", "the run's process ended abnormally (exit status 1)"),
    ("", "could not start a process for the run: Python's executable is unknown"),
])
def test_a_worker_that_cannot_start_fails_every_run_with_the_reason(monkeypatch, executable, needle):
    monkeypatch.setattr(sys, "executable", executable)
    results = eyeshell.sweep(small(), grid={"fibres.D": [0, 100]}, jobs=2)
    assert [r.status for r in results] == ["failed", "failed"]
    assert all(r.error.startswith(needle) for r in results), results[0].error


def test_an_unexpected_error_is_a_failed_run_on_one_line():
    class Broken:
        def run(self, request):
            raise ValueError("two\nlines")

    r = eyeshell._api._run_in(Broken(), 3, "x", {"k": "1"}, "")
    assert (r.name, r.status, r.index) == ("x", "failed", 3)
    assert r.error == "internal error (a bug; please report it): ValueError: two lines"
