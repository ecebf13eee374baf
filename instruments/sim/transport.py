"""The wires of the simulated bench: TCP sockets on 127.0.0.1 and pseudo-terminals.

One asyncio event loop on one background thread serves every connection of a bench. Messages
are framed by :class:`~.scpi.Framer` (newline-terminated, binary blocks kept whole) and
handed to an ``exchange(message, connection) -> (reply, drop)`` callable, which applies fault
injection and returns the reply bytes (or None) and whether to close the connection instead.

A pseudo-terminal stands for an RS-232 port: the client opens the slave device (its path is the
address) with pyserial. The bench checks the line settings the client put on the port; a client
at another baud rate or frame format than the instrument's receives framing garbage, as it would
on a real serial line.
"""

from __future__ import annotations

import asyncio
import os
import socket
import struct
import termios
import threading
import tty
from typing import Awaitable, Callable

from fsi_lab.instruments.sim.scpi import Framer
from fsi_lab.instruments.sim.specs import SERIAL_BAUD

#: ``exchange(message, connection)``: ``connection`` tells the connections apart (an instrument
#: may bind state to the one that set it, as a watchdog does).
Exchange = Callable[[bytes, object], "tuple[bytes | None, bool]"]
HOST = "127.0.0.1"
BAUD_CONSTANTS = {115200: termios.B115200, 9600: termios.B9600, 19200: termios.B19200,
                  38400: termios.B38400, 57600: termios.B57600}
#: What a UART at the wrong speed or format delivers instead of a reply.
FRAMING_GARBAGE = b"\xfe\x80\xf8\x00\x86\xe0\n"


class LoopThread:
    """An asyncio event loop running on a daemon thread until :meth:`stop`."""

    def __init__(self, name: str) -> None:
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _run(self) -> None:
        asyncio.set_event_loop(self.loop)
        self.loop.run_forever()

    def run(self, coroutine: Awaitable, timeout: float = 10.0):
        """Run ``coroutine`` on the loop and wait for its result (at most ``timeout`` s)."""
        return asyncio.run_coroutine_threadsafe(coroutine, self.loop).result(timeout)

    def stop(self, timeout: float = 10.0) -> None:
        """Stop the loop, join the thread and close the loop."""
        if self._thread.is_alive():
            self.loop.call_soon_threadsafe(self.loop.stop)
            self._thread.join(timeout)
            if self._thread.is_alive():
                raise RuntimeError(f"the simulated bench's loop did not stop within {timeout} s")
        if not self.loop.is_closed():
            self.loop.close()


class TcpEndpoint:
    """A TCP server on 127.0.0.1 for one instrument (port 0: the system picks one)."""

    def __init__(self, exchange: Exchange, port: int = 0) -> None:
        self.exchange = exchange
        self.port = port
        self._server: asyncio.base_events.Server | None = None
        self._tasks: set[asyncio.Task] = set()
        self._writers: set[asyncio.StreamWriter] = set()

    async def start(self) -> None:
        self._server = await asyncio.start_server(self._serve, HOST, self.port)
        self.port = self._server.sockets[0].getsockname()[1]

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        self._tasks.add(task)
        self._writers.add(writer)
        framer = Framer()
        try:
            while True:
                data = await reader.read(1 << 16)
                if not data:
                    break
                for message in framer.feed(data):
                    reply, drop = self.exchange(message, task)
                    if drop:
                        self._drop_all()
                        return
                    if reply:
                        writer.write(reply)
                        await writer.drain()
        except (ConnectionError, asyncio.CancelledError):
            pass
        finally:
            self._writers.discard(writer)
            self._tasks.discard(task)
            writer.close()

    def _drop_all(self) -> None:
        """Reset every connection (RST, as an instrument that reboots): the client's next read
        or write fails at once."""
        for writer in list(self._writers):
            transport = writer.transport
            if transport is None:
                continue
            sock = transport.get_extra_info("socket")
            if sock is not None:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            transport.abort()

    async def stop(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
        for writer in list(self._writers):
            writer.close()
        tasks = [t for t in self._tasks if t is not asyncio.current_task()]
        for task in tasks:
            task.cancel()
        if tasks:
            await asyncio.gather(*tasks, return_exceptions=True)


class PtyEndpoint:
    """A pseudo-terminal standing for an RS-232 port at ``baud`` 8N1."""

    def __init__(self, exchange: Exchange, baud: int = SERIAL_BAUD) -> None:
        self.exchange = exchange
        self.baud = baud
        self.master = self.slave = -1
        self.path = ""
        self._loop: asyncio.AbstractEventLoop | None = None
        self._framer = Framer()
        self._outbox = bytearray()

    async def start(self) -> None:
        self._loop = asyncio.get_running_loop()
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self.slave)
        self._loop.add_reader(self.master, self._readable)

    def line_settings_ok(self) -> bool:
        """Whether the port is set to ``baud`` 8N1 (by the client that opened it)."""
        iflag, oflag, cflag, lflag, ispeed, ospeed, cc = termios.tcgetattr(self.slave)
        wanted = BAUD_CONSTANTS.get(self.baud)
        return (ospeed == wanted and (cflag & termios.CSIZE) == termios.CS8
                and not cflag & termios.PARENB and not cflag & termios.CSTOPB)

    def _readable(self) -> None:
        try:
            data = os.read(self.master, 4096)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            return
        for message in self._framer.feed(data):
            if not self.line_settings_ok():
                self._send(FRAMING_GARBAGE)
                continue
            reply, drop = self.exchange(message, self)
            if drop:
                self._close()
                return
            if reply:
                self._send(reply)

    def _send(self, data: bytes) -> None:
        self._outbox += data
        self._flush()

    def _flush(self) -> None:
        while self._outbox and self.master >= 0:
            try:
                written = os.write(self.master, self._outbox)
            except BlockingIOError:
                self._loop.add_writer(self.master, self._writable)
                return
            except OSError:
                self._outbox.clear()
                return
            del self._outbox[:written]

    def _writable(self) -> None:
        self._loop.remove_writer(self.master)
        self._flush()

    def _close(self) -> None:
        """The port vanishes (an unplugged USB adapter): the client's next read fails."""
        if self.master >= 0:
            self._loop.remove_reader(self.master)
            self._loop.remove_writer(self.master)
            os.close(self.master)
            os.close(self.slave)
            self.master = self.slave = -1

    async def stop(self) -> None:
        self._close()

