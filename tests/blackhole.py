"""A TCP proxy on loopback that can go silent: a network partition without root, iptables or netns.

``Blackhole(target_port)`` listens on a free loopback port and forwards every connection to the
target. :meth:`Blackhole.silence` stops forwarding bytes in both directions *without closing
anything*: it stops reading its sockets, so the peers' writes pile up in kernel buffers exactly
as they do when a firewall drops packets and TCP keeps retransmitting. New connections are
accepted and then left unanswered. :meth:`Blackhole.heal` resumes forwarding, and what was held
is delivered, as TCP's retransmissions would deliver it.

It runs in a process of its own (:func:`blackhole` starts this file as a script and steers it
through its stdin): in a thread of the test's process it forwarded bytes only when the test's own
polling let go of the interpreter, and on a loaded machine a worker's keepalive through it took
longer than the deadman's silence limit (1.6 s, with three pytest workers and two busy loops on
two cores): the link looked cut before the test cut it.
"""

from __future__ import annotations

import asyncio
import contextlib
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path


class Blackhole:
    """A loopback TCP proxy to ``127.0.0.1:target_port`` that can stop forwarding on command."""

    def __init__(self, target_port: int) -> None:
        self.target_port = target_port
        self.port = 0
        self._loop = asyncio.new_event_loop()
        self._open: asyncio.Event | None = None
        self._server: asyncio.Server | None = None
        self._writers: set[asyncio.StreamWriter] = set()
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._run, name="blackhole", daemon=True)

    def start(self) -> Blackhole:
        self._thread.start()
        if not self._ready.wait(10):
            raise RuntimeError("the blackhole proxy did not start")
        return self

    def silence(self) -> None:
        """Drop the link: no byte goes through in either direction; nothing is closed."""
        self._call(lambda: self._gate().clear())

    def heal(self) -> None:
        """Bring the link back: held bytes go through, and forwarding resumes."""
        self._call(lambda: self._gate().set())

    def close(self) -> None:
        """Close every connection and stop the proxy."""

        async def shut() -> None:
            for writer in list(self._writers):
                writer.close()
            if self._server is not None:
                self._server.close()

        asyncio.run_coroutine_threadsafe(shut(), self._loop).result(10)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(10)

    def _gate(self) -> asyncio.Event:
        assert self._open is not None
        return self._open

    def _call(self, action: object) -> None:
        done = threading.Event()

        def run() -> None:
            action()  # type: ignore[operator]
            done.set()

        self._loop.call_soon_threadsafe(run)
        done.wait(10)

    def _run(self) -> None:
        asyncio.set_event_loop(self._loop)
        self._loop.run_until_complete(self._listen())
        self._ready.set()
        self._loop.run_forever()

    async def _listen(self) -> None:
        self._open = asyncio.Event()
        self._open.set()
        self._server = await asyncio.start_server(self._accepted, "127.0.0.1", 0)
        self.port = int(self._server.sockets[0].getsockname()[1])

    async def _accepted(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self._writers.add(writer)
        try:
            await self._gate().wait()  # a connection made during a partition waits for the heal
            up_reader, up_writer = await asyncio.open_connection("127.0.0.1", self.target_port)
        except OSError:
            writer.close()
            self._writers.discard(writer)
            return
        self._writers.add(up_writer)
        await asyncio.gather(self._pipe(reader, up_writer), self._pipe(up_reader, writer))
        for end in (writer, up_writer):
            end.close()
            self._writers.discard(end)

    async def _pipe(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        with contextlib.suppress(ConnectionError, OSError):
            while True:
                await self._gate().wait()  # silent: stop reading, so the sender's bytes pile up
                data = await reader.read(65536)
                if not data:
                    break
                await self._gate().wait()  # read just before the silence: held until the heal
                writer.write(data)
                await writer.drain()
        with contextlib.suppress(ConnectionError, OSError):
            writer.write_eof()


class BlackholeProcess:
    """A :class:`Blackhole` in a child process: ``port``, :meth:`silence` and :meth:`heal` as its own."""

    def __init__(self, child: subprocess.Popen[str]) -> None:
        self._child = child
        self.port = int(self._answer())

    def silence(self) -> None:
        """Drop the link: no byte goes through in either direction; nothing is closed."""
        self._tell("silence")

    def heal(self) -> None:
        """Bring the link back: held bytes go through, and forwarding resumes."""
        self._tell("heal")

    def _tell(self, command: str) -> None:
        assert self._child.stdin is not None
        self._child.stdin.write(command + "\n")
        self._child.stdin.flush()
        if self._answer() != "done":
            raise RuntimeError(f"the blackhole proxy did not {command}")

    def _answer(self) -> str:
        assert self._child.stdout is not None
        line = self._child.stdout.readline().strip()
        if not line:
            raise RuntimeError(f"the blackhole proxy ended (exit code {self._child.poll()})")
        return line


@contextlib.contextmanager
def blackhole(target_port: int) -> Iterator[BlackholeProcess]:
    """A started blackhole proxy to ``target_port`` in a process of its own, stopped at the end."""
    child = subprocess.Popen(
        [sys.executable, str(Path(__file__)), str(target_port)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        yield BlackholeProcess(child)
    finally:
        with contextlib.suppress(OSError):
            assert child.stdin is not None
            child.stdin.close()  # end of commands: the proxy closes every connection and exits
        try:
            child.wait(10)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()


def _serve(target_port: int) -> None:
    """The child: print the port, then obey ``silence`` and ``heal`` lines until stdin ends."""
    proxy = Blackhole(target_port).start()
    print(proxy.port, flush=True)
    for line in sys.stdin:
        command = line.strip()
        if command == "silence":
            proxy.silence()
        elif command == "heal":
            proxy.heal()
        print("done", flush=True)
    proxy.close()


if __name__ == "__main__":
    _serve(int(sys.argv[1]))
