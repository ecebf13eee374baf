"""Scripted peers: the other end of a real loopback socket or pseudo-terminal for driver tests.

A :class:`ScriptedPeer` (TCP on 127.0.0.1, for VISA drivers over pyvisa-py) or a
:class:`PtyPeer` (a pseudo-terminal, for serial drivers over pyserial) reads exactly the bytes
its script expects and answers the scripted replies, on a thread of its own; the test then
asserts that the driver sent those bytes and nothing else (PyMeasure's ``expected_protocol``
style), and what the driver made of the replies. The ``tcp_peer`` and ``pty_peer`` fixtures of
the fsi-lab pytest plugin make them and stop them at the end of the test.
"""

from __future__ import annotations

import os
import select
import socket
import threading
import time
import tty

#: (expected bytes, reply): the reply is None, bytes, or (delay s, bytes) for a slow instrument.
Script = list[tuple[bytes, "bytes | tuple[float, bytes] | None"]]


class _Peer:
    """Runs a script on a thread: read exactly the expected bytes, then send the reply."""

    def __init__(self, script: Script, timeout: float = 5.0) -> None:
        self.script = script
        self.timeout = timeout
        self.received = bytearray()
        self.errors: list[str] = []
        self._thread = threading.Thread(target=self._run, daemon=True, name="scripted-peer")
        self._stop = threading.Event()

    def start(self):
        self._open()
        self._thread.start()
        return self

    def _run(self) -> None:
        try:
            self._accept()
            if self._stop.is_set():     # stopped before anything connected
                return
            for step, (expected, reply) in enumerate(self.script):
                got = self._read(len(expected))
                self.received += got
                if got != expected:
                    self.errors.append(f"step {step}: expected {expected!r}, got {got!r}")
                    return
                if isinstance(reply, tuple):  # (seconds, bytes): a slow instrument
                    self._stop.wait(reply[0])
                    reply = reply[1]
                if reply:
                    self._send(reply)
            self.received += self._read(1 << 20, quiet=0.2)  # anything sent after the script
        except Exception as exc:  # noqa: BLE001 - reported by finish()
            self.errors.append(f"{type(exc).__name__}: {exc}")

    def _read(self, count: int, quiet: float | None = None) -> bytes:
        data = bytearray()
        deadline = time.monotonic() + (quiet if quiet is not None else self.timeout)
        while len(data) < count and not self._stop.is_set():
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                break
            chunk = self._recv(count - len(data), min(remaining, 0.05))
            if chunk is None:
                break
            data += chunk
        return bytes(data)

    def finish(self) -> bytes:
        """Wait for the script to end; the bytes received."""
        self._thread.join(self.timeout + 2)
        assert not self._thread.is_alive(), "the scripted peer did not finish"
        return bytes(self.received)

    def expect_all(self) -> None:
        """Assert that the driver sent exactly the script's bytes and nothing more."""
        received = self.finish()
        assert not self.errors, self.errors
        assert received == b"".join(expected for expected, _ in self.script)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(self.timeout + 2)
        self._close()


class ScriptedPeer(_Peer):
    """A TCP peer on 127.0.0.1; :attr:`address` is its VISA resource name."""

    def _open(self) -> None:
        self._server = socket.socket()
        self._server.bind(("127.0.0.1", 0))
        self._server.listen(1)
        self._server.settimeout(self.timeout)
        self.address = f"TCPIP0::127.0.0.1::{self._server.getsockname()[1]}::SOCKET"
        self._conn = None

    def _accept(self) -> None:
        # In short waits, so that stop() ends a peer nothing connects to at once (a driver
        # that never opens its socket), not after the whole timeout.
        deadline = time.monotonic() + self.timeout
        while not self._stop.is_set():
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError(f"nothing connected within {self.timeout:g} s")
            readable, _, _ = select.select([self._server], [], [], min(remaining, 0.05))
            if readable:
                self._conn, _ = self._server.accept()
                return

    def _recv(self, count: int, wait: float) -> bytes | None:
        readable, _, _ = select.select([self._conn], [], [], wait)
        if not readable:
            return b""
        try:
            chunk = self._conn.recv(count)
        except ConnectionResetError:  # the driver closed with our reply unread
            return None
        return chunk or None

    def _send(self, data: bytes) -> None:
        self._conn.sendall(data)

    def _close(self) -> None:
        for sock in (self._conn, self._server):
            if sock is not None:
                sock.close()


class PtyPeer(_Peer):
    """A serial peer on a pseudo-terminal; :attr:`address` is the device path."""

    def _open(self) -> None:
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        self.address = os.ttyname(self._slave)

    def _accept(self) -> None:
        pass

    def _recv(self, count: int, wait: float) -> bytes | None:
        readable, _, _ = select.select([self._master], [], [], wait)
        if not readable:
            return b""
        return os.read(self._master, count)

    def _send(self, data: bytes) -> None:
        os.write(self._master, data)

    def _close(self) -> None:
        for fd in (self._master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass
