"""The socket protocol's framing (PROTOCOL.md): one JSON object per line each way, and after an
image header exactly `bytes` bytes of image data. No command knows about it; the client does."""
from __future__ import annotations

import json
import socket
import time
from typing import Any

import numpy as np

from .errors import RequestTimeout

JsonObject = dict[str, Any]

_RECEIVE_CHUNK = 1 << 16


def deadline_after(seconds: float | None) -> float | None:
    """The monotonic time `seconds` from now; None (no limit) stays None."""
    return None if seconds is None else time.monotonic() + seconds


def _jsonable(value: Any) -> Any:
    """numpy arrays and scalars, which `json` cannot write, as lists and numbers."""
    if isinstance(value, (np.ndarray, np.generic)):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not a JSON value")


def request_line(message: JsonObject) -> bytes:
    """`message` as one protocol line: strict JSON (no NaN or infinity), ended by a newline."""
    return json.dumps(message, separators=(",", ":"), allow_nan=False,
                      default=_jsonable).encode() + b"\n"


def image_header(message: JsonObject) -> JsonObject | None:
    """The image header of a reply or a frame event, whose bytes follow its line; else None."""
    result = message.get("result")
    image = message.get("image") or (result.get("image") if isinstance(result, dict) else None)
    return image if isinstance(image, dict) and "bytes" in image else None


class Connection:
    """One TCP connection to the daemon, read and written with a deadline per call."""

    def __init__(self, host: str, port: int, connect_timeout: float | None) -> None:
        self._socket = socket.create_connection((host, port), timeout=connect_timeout)
        self._socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._buffer = bytearray()

    def close(self) -> None:
        self._socket.close()

    def send(self, line: bytes, deadline: float | None) -> None:
        """Sends one request line (request_line)."""
        self._socket.settimeout(self._remaining(deadline))
        try:
            self._socket.sendall(line)
        except socket.timeout as e:
            raise RequestTimeout("the daemon did not take the request in time") from e

    def receive(self, deadline: float | None) -> tuple[JsonObject, bytearray | None]:
        """The next reply or event, and the image bytes that follow it (None without an image)."""
        message = json.loads(self._read_line(deadline))
        image = image_header(message)
        return message, self._read_exact(int(image["bytes"]), deadline) if image else None

    def _read_line(self, deadline: float | None) -> bytes:
        searched = 0
        while (end := self._buffer.find(b"\n", searched)) < 0:
            searched = len(self._buffer)
            self._buffer += self._receive(_RECEIVE_CHUNK, deadline)
        line = bytes(self._buffer[:end])
        del self._buffer[:end + 1]
        return line

    def _read_exact(self, count: int, deadline: float | None) -> bytearray:
        out = bytearray(count)
        held = min(count, len(self._buffer))
        out[:held] = self._buffer[:held]
        del self._buffer[:held]
        view = memoryview(out)
        while held < count:
            self._socket.settimeout(self._remaining(deadline))
            try:
                received = self._socket.recv_into(view[held:])
            except socket.timeout as e:
                raise RequestTimeout("the daemon's image did not arrive in time") from e
            if received == 0:
                raise ConnectionError("the daemon closed the connection inside an image")
            held += received
        return out

    def _receive(self, size: int, deadline: float | None) -> bytes:
        self._socket.settimeout(self._remaining(deadline))
        try:
            data = self._socket.recv(size)
        except socket.timeout as e:
            raise RequestTimeout("nothing came from the daemon in time") from e
        if not data:
            raise ConnectionError("the daemon closed the connection")
        return data

    @staticmethod
    def _remaining(deadline: float | None) -> float | None:
        if deadline is None:
            return None
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            raise RequestTimeout("the client's timeout ran out")
        return remaining
