"""The GIL is released while eyeshell computes, and Ctrl-C stops a long grow or sweep."""

import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest

import eyeshell
from conftest import SCENES


def longest_pause_of_a_ticking_thread(work):
    """Run `work` while a second Python thread ticks every millisecond; return the work's
    duration and the longest time the ticking thread went without a tick meanwhile."""
    ticks, stop = [], threading.Event()

    def tick():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    thread = threading.Thread(target=tick)
    thread.start()
    time.sleep(0.05)
    start = time.perf_counter()
    work()
    end = time.perf_counter()
    stop.set()
    thread.join()
    inside = [start] + [t for t in ticks if start < t < end] + [end]
    return end - start, max(b - a for a, b in zip(inside, inside[1:]))


def test_a_second_thread_runs_during_a_solve():
    scene = eyeshell.Scene.from_file(SCENES / "fibres-nonuniform.toml", solver__nodes=60001)
    duration, pause = longest_pause_of_a_ticking_thread(lambda: eyeshell.solve(scene))
    # Holding the GIL, the solve would stop the other thread for its whole duration (long
    # enough to tell: 0.19 s at N = 40001 on an idle machine, so N = 60001 and > 0.1 s).
    assert duration > 0.1 and pause < duration / 3, (duration, pause)


def test_a_second_thread_runs_during_a_grow_with_progress():
    scene = eyeshell.Scene.from_file(SCENES / "const.toml", solver__nodes=1001, solver__rtol=1e-9)
    duration, pause = longest_pause_of_a_ticking_thread(
        lambda: eyeshell.grow(scene, progress=lambda t, t_end: None, frames=False))
    assert duration > 0.2 and pause < duration / 3, (duration, pause)


# A growth run of several seconds: explicit Euler, many steps on a fine mesh.
LONG = {"solver.integrator": "euler", "solver.steps": 4000, "solver.nodes": 2001}


# The child's first line: Python raises KeyboardInterrupt on SIGINT only if SIGINT was not
# ignored when it started, and a shell running the suite in the background (`cmd &`) starts
# it with SIGINT ignored (then every run here "finished" before it noticed a Ctrl-C).
DEFAULT_SIGINT = "import signal; signal.signal(signal.SIGINT, signal.default_int_handler)\n"


def interrupt(script, signal_after=0.3):
    """Run `script` in a child Python (with Python's own SIGINT handler, whatever this
    process inherited), send it SIGINT `signal_after` seconds after it prints 'started'
    (None: the script signals itself), and return (seconds from then to the child's exit,
    its stdout, its stderr, its exit code)."""
    code = DEFAULT_SIGINT + textwrap.dedent(script)
    child = subprocess.Popen([sys.executable, "-c", code],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "started", child.stderr.read()
    if signal_after is not None:
        time.sleep(signal_after)
    sent = time.perf_counter()
    if signal_after is not None:
        child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=60)
    return time.perf_counter() - sent, out, err, child.returncode


def test_ctrl_c_stops_a_long_grow():
    seconds, out, err, code = interrupt(f"""
        import sys, time, eyeshell
        LONG = {LONG!r}
        started = False
        def progress(t, t_end):
            global started
            if not started:
                print("started", flush=True); started = True
        start = time.perf_counter()
        try:
            eyeshell.grow({str(SCENES / 'const.toml')!r}, progress=progress, **LONG)
            print("finished")
        except KeyboardInterrupt:
            print(f"interrupted after {{time.perf_counter() - start:.2f}} s")
    """)
    assert code == 0 and out.startswith("interrupted"), (out, err)
    assert seconds < 2.0


def test_ctrl_c_stops_a_long_sweep():
    seconds, out, err, code = interrupt(f"""
        import os, threading, eyeshell
        LONG = {LONG!r}
        scene = eyeshell.Scene.from_file({str(SCENES / 'const.toml')!r}, **LONG)
        print("started", flush=True)
        try:
            eyeshell.sweep(scene, grid={{"fibres.D": [0, 100, 200, 400]}}, jobs=2)
            print("finished")
        except KeyboardInterrupt:
            try:
                os.waitpid(-1, os.WNOHANG)
                children = "some"
            except ChildProcessError:
                children = "none"
            print("interrupted", threading.active_count(), children)
    """)
    # The running runs stopped at once: no thread is left behind, and no process (the
    # runs' workers are ended and reaped).
    assert code == 0 and out.split() == ["interrupted", "1", "none"], (out, err)
    assert seconds < 2.0


def test_ctrl_c_stops_a_long_fit():
    # Every growth run of a fit polls for Ctrl-C after each step, as grow does: the fit
    # stops within a step, not after its last iteration. This fit takes far longer than
    # the test waits (its first run alone: ~1 s per 0.1 of t at this mesh and rtol).
    seconds, out, err, code = interrupt(f"""
        import time, eyeshell
        data = {{"t": [0.25, 0.5, 0.75, 1.0], "axial_length": [23.0, 23.5, 24.0, 24.5]}}
        print("started", flush=True)
        start = time.perf_counter()
        try:
            eyeshell.fit({str(SCENES / 'const.toml')!r}, data,
                         fit=["growth.eta0", "growth.Gamma", "growth.delta"],
                         solver__nodes=4001, solver__rtol=1e-10)
            print(f"finished after {{time.perf_counter() - start:.2f}} s")
        except KeyboardInterrupt:
            print(f"interrupted after {{time.perf_counter() - start:.2f}} s")
    """, signal_after=1.0)
    assert code == 0 and out.startswith("interrupted"), (out, err)
    assert seconds < 2.0, (seconds, out)


def test_ctrl_c_at_random_moments_never_hangs_a_sweep():
    # A KeyboardInterrupt landing inside a lock's `with` leaves the lock held; a sweep that
    # polled its futures' locks could then deadlock (a worker blocked on a future's lock,
    # shutdown() waiting for it: seen once in CI). Ctrl-C many times at random moments,
    # with any sleep of the sweep's waiting loop made a busy wait (so that the old
    # polling spent its time in futures' locks: it hung within 30 trials).
    seconds, out, err, code = interrupt(f"""
        import os, random, signal, threading, time, types, eyeshell, eyeshell._api
        eyeshell._api.time = types.SimpleNamespace(sleep=lambda s: None,
            perf_counter=time.perf_counter, monotonic=time.monotonic)
        scene = eyeshell.Scene.from_file({str(SCENES / 'const.toml')!r},
            **{{"solver.integrator": "euler", "solver.steps": 200, "solver.nodes": 201}})
        print("started", flush=True)
        random.seed(7)
        for trial in range(60):
            threading.Timer(random.uniform(0.0, 0.15), os.kill, (os.getpid(), signal.SIGINT)).start()
            try:
                eyeshell.sweep(scene, grid={{"fibres.D": [0, 100, 200, 400]}}, jobs=2)
                time.sleep(0.2)  # the timer fires here instead
            except KeyboardInterrupt:
                pass
        time.sleep(0.3)
        try:
            os.waitpid(-1, os.WNOHANG)
            children = "some"
        except ChildProcessError:
            children = "none"
        print("done", threading.active_count(), children)
        """, signal_after=None)
    # No thread, and no worker process, is left behind.
    assert code == 0 and out.split() == ["done", "1", "none"], (out, err)


@pytest.mark.parametrize("after", [0.05, 0.4, 1.2, 2.5])
def test_ctrl_c_stops_a_fit_at_3001_nodes_within_half_a_second_at_any_moment(after):
    # In every phase: the first growth run and the later ones. An interrupted trial is no
    # rejected step: taken as one, the fit would go on damping trial after trial (tens of
    # seconds at this mesh) before raising KeyboardInterrupt.
    seconds, out, err, code = interrupt(f"""
        import time, eyeshell
        data = {{"t": [0.1, 0.15, 0.2], "axial_length": [22.0, 22.3, 22.5]}}
        print("started", flush=True)
        try:
            eyeshell.fit({str(SCENES / 'const.toml')!r}, data,
                         fit=["growth.eta0", "growth.Gamma"],
                         solver__nodes=3001, growth__t_end=0.2, output__times=[0.2])
            print("finished")
        except KeyboardInterrupt:
            print("interrupted")
    """, signal_after=after)
    assert code == 0 and out.startswith("interrupted"), (out, err)
    assert seconds < 0.5, (seconds, after)
