"""`nephele serve` on this machine, started from a config file, for scripts and tests that run
their own daemon."""
from __future__ import annotations

import os
import signal
import subprocess
from typing import IO, Any

from .client import Client

_READY = "nephele ready"


class LocalDaemon:
    """A `nephele serve -c CONFIG` process, ready once constructed.

    The daemon prints `nephele ready socket=PORT modbus=PORT metrics=PORT cigi=PORT` when it
    listens (a port of 0 in the config is chosen by the system); `ports` holds those ports by
    name and `port` the socket protocol's. `stderr` (a file, or subprocess.DEVNULL) takes the
    daemon's log; by default it goes to this process's. `stop()`, or leaving a `with` block,
    sends SIGTERM and waits for the daemon to end.
    """

    def __init__(self, config: str | os.PathLike[str], binary: str | os.PathLike[str] = "nephele",
                 stderr: IO[Any] | int | None = None) -> None:
        self._process = subprocess.Popen([os.fspath(binary), "serve", "-c", os.fspath(config)],
                                         stdout=subprocess.PIPE, stderr=stderr, text=True)
        assert self._process.stdout is not None
        line = self._process.stdout.readline()  # blocks until ready, or EOF when it fails
        if not line.startswith(_READY):
            code = self._process.wait()
            raise RuntimeError(f"{os.fspath(binary)} serve -c {os.fspath(config)} did not start "
                               f"(exit status {code})")
        self.ports = {key: int(value)
                      for key, value in (item.split("=") for item in line[len(_READY):].split())}
        self.port = self.ports["socket"]

    def __enter__(self) -> LocalDaemon:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.stop()

    def client(self, **options: Any) -> Client:
        """A Client connected to this daemon; `options` are Client's keyword arguments."""
        return Client("127.0.0.1", self.port, **options)

    def stop(self) -> int:
        """Stops the daemon with SIGTERM (if it still runs) and returns its exit status."""
        if self._process.poll() is None:
            self._process.send_signal(signal.SIGTERM)
        code = self._process.wait()
        if self._process.stdout is not None:
            self._process.stdout.close()
        return code
