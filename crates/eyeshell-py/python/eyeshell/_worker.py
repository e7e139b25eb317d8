"""Each run of :func:`eyeshell.sweep` in a worker process, so that a run that aborts fails
alone instead of taking the sweep (and the interpreter) down: an allocation that fails or
a stack overflow makes Rust abort the process, with no exception to catch.

:class:`Workers` is a pool of long-lived worker processes, each serving run after run (so
that starting Python and importing eyeshell is paid once per worker, not per run). A
worker that dies fails its run with one line saying how (``killed by signal 6: SIGABRT;
...``) and its last line on stderr, as ``eyeshell sweep``'s workers do (src/worker/); the
next run gets a fresh worker. A worker's stderr (and its stdout, pointed there) never
reaches the terminal: it goes to an unnamed temporary file, read only for those last words.

A worker is ``sys.executable`` running :func:`serve`, with the folder that holds this
package first on its ``sys.path``: it imports this very package whatever the current
directory or ``PYTHONPATH`` of the caller (which it inherits, with the environment).

# Protocol

Frames (an 8-byte big-endian length, then a pickle) over the worker's stdin and a private
copy of its stdout: the parent sends ``(index, name, values, scene TOML)``, the worker
answers with the :class:`~eyeshell.RunResult`. Pickles travel only between a parent and
the workers it started.

End of input ends a worker at once, even in the middle of a run: that is how a parent
that dies takes its workers with it. A Ctrl-C stops the running runs by killing their
workers. Workers ignore SIGINT and run in a session of their own, so a Ctrl-C at the
terminal reaches the parent alone, which decides.

# Fault injection

``EYESHELL_TEST_ABORT_RUN=<run name>``: a worker aborts (``os.abort``) when asked for that
run, before running it, as the command line's workers do. Tests use it to kill a run
deterministically; nothing else reads it.
"""

from __future__ import annotations

import os
import pickle
import queue
import signal
import struct
import subprocess
import sys
import tempfile
import threading
from typing import IO, Any

ABORT_ENV = "EYESHELL_TEST_ABORT_RUN"

_HEADER = struct.Struct(">Q")

# The worker's program: argv[1] (the folder holding this package) replaces sys.path[0]
# (the current directory, for `-c`), so that the worker imports this very package.
_BOOT = "import sys; sys.path[0] = sys.argv[1]; from eyeshell._worker import serve; serve()"
_PACKAGE_PARENT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# How a worker's end is described, as the command line describes its workers'.
_SIGNAL_HINTS = {
    "SIGABRT": "; out of memory or a stack overflow?",
    "SIGKILL": "; out of memory (the kernel's OOM killer)?",
    "SIGSEGV": "; a stack overflow?",
}


def _write_frame(stream: IO[bytes], obj: Any) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(_HEADER.pack(len(data)))
    stream.write(data)
    stream.flush()


def _read_exactly(stream: IO[bytes], n: int) -> bytes | None:
    chunks, left = [], n
    while left > 0:
        chunk = stream.read(left)
        if not chunk:
            return None
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def _read_frame(stream: IO[bytes]) -> Any:
    """The next object on `stream`; EOFError when the stream ended."""
    header = _read_exactly(stream, _HEADER.size)
    if header is None:
        raise EOFError
    data = _read_exactly(stream, _HEADER.unpack(header)[0])
    if data is None:
        raise EOFError
    return pickle.loads(data)


# ---------------------------------------------------------------------------------------
# The worker's side


def serve() -> None:
    """Serve run requests on stdin until it ends (the worker's main program)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # Replies on a private copy of stdout; fd 1 then points at stderr, so that nothing
    # printed by the run (Python or native) can corrupt a reply.
    replies = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    requests: queue.SimpleQueue[Any] = queue.SimpleQueue()
    threading.Thread(target=_read_requests, args=(sys.stdin.buffer, requests), daemon=True).start()
    from ._api import _run_here

    abort_on = os.environ.get(ABORT_ENV)
    while True:
        index, name, values, scene_toml = requests.get()
        if abort_on is not None and name == abort_on:
            os.abort()
        _write_frame(replies, _run_here(index, name, values, scene_toml))


def _read_requests(stream: IO[bytes], requests: queue.SimpleQueue[Any]) -> None:
    """Read requests until the input ends, then end the process at once: the parent is
    done with this worker, or gone, and a run in progress is of no use to anyone."""
    try:
        while True:
            requests.put(_read_frame(stream))
    except BaseException:
        pass
    os._exit(0)


# ---------------------------------------------------------------------------------------
# The parent's side


class Cancelled(Exception):
    """The pool was closed (Ctrl-C) while the run waited or ran."""


class Lost(Exception):
    """The run's process ended without a reply; the message says how."""


class _Worker:
    """One worker process, its pipes and the file that holds its stderr."""

    def __init__(self) -> None:
        if not sys.executable:
            raise OSError("Python's executable is unknown (sys.executable is empty)")
        self.stderr = tempfile.TemporaryFile()
        try:
            self.process = subprocess.Popen(
                [sys.executable, "-c", _BOOT, _PACKAGE_PARENT],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=self.stderr,
                start_new_session=True,
            )
        except BaseException:
            self.stderr.close()
            raise

    def ask(self, request: Any) -> Any:
        """Send `request` and wait for the reply; EOFError when the worker ended first."""
        stdin, stdout = self.process.stdin, self.process.stdout
        assert stdin is not None and stdout is not None
        try:
            _write_frame(stdin, request)
            return _read_frame(stdout)
        except (OSError, ValueError):
            raise EOFError from None

    def kill(self) -> None:
        """End the process now (another thread may be waiting for its reply: it sees the
        end of its output)."""
        try:
            self.process.kill()
        except OSError:
            pass

    def close(self) -> None:
        """End the process (end of its input) and reap it."""
        for pipe in (self.process.stdin, self.process.stdout):
            try:
                if pipe is not None:
                    pipe.close()
            except OSError:
                pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.kill()
            self.process.wait()
        self.stderr.close()

    def ended(self) -> str:
        """The worker is lost: reap it, and say how it ended, on one line."""
        try:
            # Its output ended: it has ended, or is ending (an abort may take a while to
            # write a core file; a kill now would hide how it ended).
            code = self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.kill()
            code = self.process.wait()
        self.stderr.seek(0, os.SEEK_END)
        size = self.stderr.tell()
        self.stderr.seek(max(0, size - 8192))
        words = _last_line(self.stderr.read().decode("utf-8", "replace"))
        self.close()
        how = _describe(code)
        return f"the run's process ended abnormally ({how})" + (f"; its last words: {words}" if words else "")


def _last_line(text: str) -> str:
    """The last non-empty line of `text` before any Rust backtrace (an allocation that
    fails prints its message, then a backtrace whose last line is a note about
    RUST_BACKTRACE), printable and at most 300 characters."""
    lines = text.splitlines()
    for i in range(len(lines) - 1, -1, -1):
        if lines[i].strip() == "stack backtrace:":
            lines = lines[:i]
            break
    for line in reversed(lines):
        line = "".join(c if c.isprintable() else " " for c in line).strip()
        if line and not (line.startswith("note: ") and "RUST_BACKTRACE" in line):
            return line[:300]
    return ""


def _describe(code: int) -> str:
    """How a process that should not have ended did: "killed by signal 6: SIGABRT; out of
    memory or a stack overflow?", "exit status 3"."""
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            return f"killed by signal {-code}"
        return f"killed by signal {-code}: {name}{_SIGNAL_HINTS.get(name, '')}"
    return f"exit status {code}"


class Workers:
    """A pool of worker processes: :meth:`run` runs a request in an idle worker (started if
    none), from any thread; :meth:`close` ends them all."""

    def __init__(self) -> None:
        self.pid = os.getpid()
        self._lock = threading.Lock()
        self._idle: list[_Worker] = []
        self._busy: set[_Worker] = set()
        self._closed = False

    def run(self, request: Any) -> Any:
        """The reply of a worker to `request`. Raises :class:`Lost` when the worker ended
        without one, :class:`Cancelled` when the pool was closed, OSError when no worker
        could be started."""
        worker = self._take()
        try:
            reply = worker.ask(request)
        except EOFError:
            with self._lock:
                self._busy.discard(worker)
                closed = self._closed
            how = worker.ended()
            if closed:
                raise Cancelled from None
            raise Lost(how) from None
        except BaseException:
            # A reply that does not read back (a bug), or a KeyboardInterrupt in this
            # thread: the worker's state is unknown, so it goes.
            with self._lock:
                self._busy.discard(worker)
            worker.kill()
            worker.close()
            raise
        self._put_back(worker)
        return reply

    def _take(self) -> _Worker:
        with self._lock:
            if self._closed:
                raise Cancelled
            if self._idle:
                worker = self._idle.pop()
                self._busy.add(worker)
                return worker
        worker = _Worker()
        with self._lock:
            if not self._closed:
                self._busy.add(worker)
                return worker
        # Closed while this worker started.
        worker.kill()
        worker.close()
        raise Cancelled

    def _put_back(self, worker: _Worker) -> None:
        with self._lock:
            self._busy.discard(worker)
            if not self._closed:
                self._idle.append(worker)
                return
        worker.close()

    def close(self, kill: bool = False) -> None:
        """End every worker: the idle ones at once; the busy ones too with `kill` (their
        runs stop, and the threads waiting for them raise :class:`Cancelled`), else when
        their runs are done."""
        with self._lock:
            self._closed = True
            idle, self._idle = self._idle, []
            busy = list(self._busy)
        if kill:
            for worker in busy + idle:
                worker.kill()
        for worker in idle:
            worker.close()


_shared: Workers | None = None
_shared_lock = threading.Lock()


def shared() -> Workers:
    """The pool of this process, for runs that an executor ships here: its workers serve
    the runs of every sweep and end with this process (the end of their input)."""
    global _shared
    with _shared_lock:
        # A forked child has its parent's pool, whose workers are its parent's.
        if _shared is None or _shared.pid != os.getpid():
            _shared = Workers()
        return _shared
