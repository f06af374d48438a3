"""The league's web pages started from the app: `racer-tui serve` as a child process.

A child, not a thread: the web server (Starlette, uvicorn) stays out of the app's process
and its start-up, a slow viewer never holds the interface, and the app's crash cannot take
the pages down mid-heat without the child noticing (it is stopped with the app: SIGTERM
from the kernel if the app dies, `stop` when it quits).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

from sim.foundation.remedies import RemedyError

STOP_SECONDS = 5.0  # for the requests in hand, then it is killed
# The command line's port first (an address a host can give out before the night), then
# any free one rather than none when another program has it.
PORTS = (8080, 0)
_ADDRESS_MARK = "http://"


class WebPagesError(RemedyError):
    """The server could not start; the message is the command's own sentence."""


class WebPages:
    """One `racer-tui serve` child and the address it said it listens on."""

    def __init__(self) -> None:
        self.process: subprocess.Popen[str] | None = None
        self.announcement = ""  # its first line: where it listens, and who can open it
        # Start runs in a worker thread while the screen may be left (and `stop` called):
        # a server that comes up after its stop is stopped at once, never left running.
        self._lock = threading.Lock()
        self.starting = False
        self._stop_asked = False

    @property
    def running(self) -> bool:
        return self.process is not None and self.process.poll() is None

    @property
    def address(self) -> str:
        start = self.announcement.find(_ADDRESS_MARK)
        return self.announcement[start:].split()[0] if start >= 0 else ""

    @property
    def who(self) -> str:
        """Who can open the pages, by the address the server listens on."""
        host = self.address.removeprefix(_ADDRESS_MARK).rsplit(":", 1)[0]
        if host.startswith("127.") or host in ("[::1]", "localhost"):
            return "only this machine can open them"
        return "anyone on the network who can reach this machine can open them"

    def start(self, db_path: Path | None) -> str:
        """Start the server (blocking until it says where it listens: call it from a worker
        thread) and return that line, or "" if `stop` was called meanwhile. WebPagesError
        with its sentence if it cannot start."""
        with self._lock:
            if self.starting or self.running:
                return self.announcement
            self.starting, self._stop_asked = True, False
        try:
            for port in PORTS[:-1]:
                try:
                    return self._start(db_path, port)
                except WebPagesError:
                    pass  # the port is taken (or worse, which the last try says)
            return self._start(db_path, PORTS[-1])
        finally:
            with self._lock:
                self.starting = False
            if self._stop_asked:
                self.stop()

    def _start(self, db_path: Path | None, port: int) -> str:
        command = [sys.executable, "-m", "racer_tui.cli.main", "serve", "--die-with-parent"]
        command += ["--port", str(port)]
        if db_path is not None:
            command += ["--db", str(db_path)]
        # Its errors to a file, not a pipe nobody reads after start-up: a full pipe would
        # stall the server.
        with tempfile.TemporaryFile("w+", encoding="utf-8") as errors:
            process = subprocess.Popen(
                command,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=errors,
                text=True,
                start_new_session=True,  # the terminal's Ctrl+C is the app's, not its
            )
            assert process.stdout is not None
            line = process.stdout.readline().strip()
            if _ADDRESS_MARK not in line:
                process.wait()
                errors.seek(0)
                said = errors.read().strip().splitlines()
                sentence = said[-1].removeprefix("racer-tui: ") if said else ""
                raise WebPagesError(
                    sentence or f"the web server stopped (exit status {process.returncode})."
                )
        with self._lock:
            self.process, self.announcement = process, line
            return "" if self._stop_asked else line

    def stop(self) -> None:
        """Stop the server: its requests in hand finish, then it ends (killed if it will
        not)."""
        with self._lock:
            self._stop_asked = self.starting
            process, self.process, self.announcement = self.process, None, ""
        if process is None or process.poll() is not None:
            return
        os.killpg(process.pid, signal.SIGTERM)
        try:
            process.wait(STOP_SECONDS)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
        if process.stdout is not None:
            process.stdout.close()
