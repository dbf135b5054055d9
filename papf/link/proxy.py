"""``papf link``: forward TCP (Zenoh's links) between two endpoints with a link's behaviour.

A thin asyncio wrapper around :mod:`papf.link.schedule`: each accepted connection gets one
to ``--to``; per direction a reader stamps each chunk as it arrives and asks the schedule
when it leaves, a writer sends it then. A sender that outruns the link (rate limit, an
outage) fills at most :data:`MAX_QUEUED` bytes, then the reader stops reading, so TCP's
own flow control pushes back on it, as a full network queue does. Outages: ``stall`` keeps
the connections and holds the data (a connection attempt waits for the link too);
``reset`` resets every connection (RST) when the outage begins and refuses new ones
until it ends. Stats at exit (stderr; ``--stats FILE``: JSON). SIGINT/SIGTERM: clean stop
(connections reset, stats written); SIGUSR1: the outage schedule's t0 is now.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import re
import signal
import socket
import struct
import sys
import time
from collections import deque
from dataclasses import dataclass

from common.errors import ConfigError
from common.outfiles import check_output, output
from papf.link.schedule import Direction, OutageSchedule, resume_after
from papf.link.spec import LinkSpec
from papf.link.stats import LinkStats

MAX_QUEUED = 16 * 1024 * 1024   # [bytes] held per direction and connection before reading stops
READ_SIZE = 65536               # [bytes] one read from a socket
CONNECT_TIMEOUT_S = 10.0        # [s] for the --to side to accept
RESOLUTION_S = 0.0005         # [s] a chunk due this soon goes now: asyncio sleeps in whole ms
SYN_RTO_S = 1.0                 # Linux's initial SYN retransmission timeout (TCP_TIMEOUT_INIT)
NOT_YET = float("inf")          # an outage schedule waiting for SIGUSR1


def parse_endpoint(text: str, what: str) -> tuple[str, int]:
    """``tcp/HOST:PORT`` (or ``HOST:PORT``; ``[::1]`` for IPv6) -> (host, port). ``tls/`` is
    taken too: the emulator forwards TCP bytes as they are, so TLS stays end to end."""
    m = re.fullmatch(r"(?:tcp/|tls/)?(\[[0-9a-fA-F:.]+\]|[A-Za-z0-9_.-]+):(\d{1,5})", text.strip())
    if m is None or int(m.group(2)) > 65535:
        raise ConfigError(f"{what} {text!r}: must be a TCP endpoint tcp/HOST:PORT, e.g. "
                          "tcp/127.0.0.1:7448")
    return m.group(1).strip("[]"), int(m.group(2))


def _nodelay(writer: asyncio.StreamWriter) -> None:
    sock = writer.get_extra_info("socket")
    if sock is not None:   # Zenoh sets it on its own sockets: we must not add Nagle's wait
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


def _reset(writer: asyncio.StreamWriter) -> None:
    """Close with an RST (SO_LINGER 0), as a connection a network dropped is seen."""
    sock = writer.get_extra_info("socket")
    if sock is not None:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    writer.transport.abort()


class Pump:
    """One direction of one connection: read, schedule, hold, write."""

    def __init__(self, emu: LinkEmulator, direction: str, reader, writer):
        self.emu, self.direction = emu, direction
        self.reader, self.writer = reader, writer
        self.sched: Direction = emu.dirs[direction]
        self.stats = emu.stats.directions[direction]
        self.items: deque = deque()      # (arrival, delivery, data or None = EOF)
        self.queued = 0
        self.wake, self.room = asyncio.Event(), asyncio.Event()
        self.room.set()

    async def read(self) -> None:
        while True:
            data = await self.reader.read(READ_SIZE)
            now = self.emu.clock()
            if not data:   # EOF: passed on after what is still held
                self.items.append((now, max(now, self.sched.last), None))
                self.wake.set()
                return
            delivery = self.sched.depart(now, len(data))
            if delivery is None:   # a reset-mode outage: the connection is being reset
                self.stats.dropped += 1
                continue
            self.items.append((now, delivery, data))
            self.queued += len(data)
            self.stats.max_queued_bytes = max(self.stats.max_queued_bytes, self.queued)
            self.wake.set()
            if self.queued > MAX_QUEUED:
                self.room.clear()
                await self.room.wait()

    async def write(self) -> None:
        while True:
            while not self.items:
                self.wake.clear()
                await self.wake.wait()
            wait = self.items[0][1] - self.emu.clock()
            if wait > RESOLUTION_S:   # asyncio's timers are whole milliseconds (epoll)
                await asyncio.sleep(wait)
            now = self.emu.clock()
            while self.items and self.items[0][1] <= now + RESOLUTION_S:   # all due: one drain
                if self.writer.transport.is_closing():   # the far side went (a reset, a lease)
                    raise ConnectionResetError(f"{self.direction}: the receiving side closed")
                arrival, _, data = self.items.popleft()
                if data is None:
                    if self.writer.can_write_eof():
                        self.writer.write_eof()
                    return
                self.writer.write(data)
                self.queued -= len(data)
                self.stats.add(len(data), now - arrival)
            await self.writer.drain()
            if self.queued <= MAX_QUEUED // 2:
                self.room.set()


class Connection:
    """A connection through the link: two pumps; reset both sides on any error."""

    def __init__(self, emu: LinkEmulator, a: tuple, b: tuple):
        self.emu = emu
        self.writers = (a[1], b[1])
        self.pumps = (Pump(emu, "out", a[0], b[1]), Pump(emu, "back", b[0], a[1]))
        self.tasks: list[asyncio.Task] = []

    async def run(self) -> None:
        self.tasks = [asyncio.ensure_future(c) for p in self.pumps for c in (p.read(), p.write())]
        writes = {self.tasks[1], self.tasks[3]}
        pending = set(self.tasks)
        failed = False
        while pending and not failed:
            done, pending = await asyncio.wait(pending, return_when=asyncio.FIRST_COMPLETED)
            failed = any(t.exception() is not None for t in done if not t.cancelled())
            if writes <= {t for t in self.tasks if t.done()}:
                break   # both directions passed their EOF on
        self.close(reset=failed)

    def close(self, reset: bool) -> None:
        for t in self.tasks:
            t.cancel()
        for w in self.writers:
            if reset:
                _reset(w)
            else:
                w.close()


@dataclass
class Endpoints:
    listen: tuple[str, int]
    to: tuple[str, int]


class LinkEmulator:
    """The link: its schedule (both directions share the outages), its connections, its stats."""

    def __init__(self, spec: LinkSpec, ends: Endpoints, t0_on_signal: bool = False,
                 clock=time.monotonic, say=None):
        self.spec, self.ends, self.clock = spec, ends, clock
        self.say = say or (lambda text: print(f"papf link: {text}", file=sys.stderr, flush=True))
        self.outages = OutageSchedule(spec, origin=NOT_YET if t0_on_signal else clock())
        self.dirs = {d: Direction(spec, d, self.outages) for d in ("out", "back")}
        self.stats = LinkStats()
        self.conns: set[Connection] = set()
        self.handlers: set[asyncio.Task] = set()   # one per accepted connection
        self.events: list[dict] = []      # outages as they happened (clock and wall ns)
        self.t0_set = asyncio.Event()
        self.started = (time.monotonic_ns(), time.time_ns())
        self.t0: tuple[int, int] | None = None if t0_on_signal else self.started
        self.port = ends.listen[1]

    def restart_clock(self) -> None:
        """SIGUSR1: the outage schedule counts from now."""
        self.outages.origin = self.clock()
        self.t0 = (time.monotonic_ns(), time.time_ns())
        self.say("t0: the outage schedule counts from now")
        self.t0_set.set()

    async def accept(self, reader, writer) -> None:
        """A connection from the listening side (asyncio's handler: a stop cancels it)."""
        task = asyncio.current_task()
        self.handlers.add(task)
        try:
            with contextlib.suppress(asyncio.CancelledError):
                await self._accept(reader, writer)
        finally:
            self.handlers.discard(task)

    async def _accept(self, reader, writer) -> None:
        self.stats.connections += 1
        _nodelay(writer)
        outage = self.outages.at(self.clock())
        if outage is not None and self.spec.outage_mode == "reset":
            self.stats.refused += 1
            _reset(writer)
            return
        if outage is not None:   # stall: the handshake gets through at TCP's next SYN retry
            await asyncio.sleep(max(0.0, self.outages.clock(resume_after(outage, SYN_RTO_S))
                                    - self.clock()))
        try:
            b = await asyncio.wait_for(asyncio.open_connection(*self.ends.to), CONNECT_TIMEOUT_S)
        except (OSError, asyncio.TimeoutError):
            self.stats.connect_failures += 1
            _reset(writer)
            return
        _nodelay(b[1])
        conn = Connection(self, (reader, writer), b)
        self.conns.add(conn)
        try:
            await conn.run()
        finally:
            self.conns.discard(conn)

    async def watch_outages(self) -> None:
        """Say each outage when it begins and ends; reset-mode: reset every connection."""
        while True:
            now = self.clock()
            nxt = self.outages.between(now, now + 3600.0) if self.outages.origin != NOT_YET else None
            if nxt is None:
                self.t0_set.clear()
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(self.t0_set.wait(), 60.0)
                continue
            start, end = self.outages.clock(nxt.start), self.outages.clock(nxt.end)
            await asyncio.sleep(max(0.0, start - self.clock()))
            event = {"start_s": round(nxt.start, 3), "end_s": round(nxt.end, 3),
                     "random": nxt.random, "mode": self.spec.outage_mode,
                     "start_monotonic_ns": time.monotonic_ns(), "start_wall_ns": time.time_ns()}
            self.events.append(event)
            self.say(f"outage: the link is down for {nxt.length:.1f} s ({self.spec.outage_mode})")
            if self.spec.outage_mode == "reset":
                for conn in list(self.conns):
                    self.stats.resets += 1
                    conn.close(reset=True)
            while self.clock() < end:   # a timer may fire a hair early: not the same outage twice
                await asyncio.sleep(max(0.001, end - self.clock()))
            event.update(end_monotonic_ns=time.monotonic_ns(), end_wall_ns=time.time_ns())
            self.say("outage over: the link is up")

    async def serve(self, stop: asyncio.Event) -> None:
        host, port = self.ends.listen
        try:
            server = await asyncio.start_server(self.accept, host, port, reuse_address=True)
        except OSError as exc:
            raise ConfigError(f"--listen tcp/{host}:{port}: cannot listen there ({exc.strerror}); "
                              "give a free port") from None
        self.port = server.sockets[0].getsockname()[1]
        to = self.ends.to
        self.say(f"ready: tcp/{host}:{self.port} -> tcp/{to[0]}:{to[1]}, {self.spec.describe()}")
        watcher = asyncio.ensure_future(self.watch_outages())
        try:
            await stop.wait()
        finally:
            watcher.cancel()
            server.close()
            for conn in list(self.conns):
                conn.close(reset=True)
            for task in list(self.handlers):
                task.cancel()
            await asyncio.gather(watcher, *self.handlers, return_exceptions=True)

    def report(self) -> dict:
        """The stats as JSON (``--stats``, ``papf run --link``'s ``link_emulator``)."""
        now_ns = time.monotonic_ns()
        out = {"spec": self.spec.to_json(), "description": self.spec.describe(),
               "listen": f"tcp/{self.ends.listen[0]}:{self.port}",
               "to": f"tcp/{self.ends.to[0]}:{self.ends.to[1]}",
               "duration_s": round((now_ns - self.started[0]) / 1e9, 3),
               "t0_monotonic_ns": self.t0[0] if self.t0 else None,
               "t0_wall_ns": self.t0[1] if self.t0 else None,
               **self.stats.to_json(), "outages": self.events,
               "outage_s": round(sum(((e.get("end_monotonic_ns") or now_ns)
                                      - e["start_monotonic_ns"]) / 1e9 for e in self.events), 3)}
        for name, sched in self.dirs.items():
            out["directions"][name]["lost"] = sched.lost
            out["directions"][name]["dropped"] = max(sched.dropped,
                                                     out["directions"][name]["dropped"])
        return out


def run_link(spec: LinkSpec, listen: str, to: str, stats_file: str | None = None,
             force: bool = False, t0_on_signal: bool = False) -> int:
    """``papf link`` until SIGINT/SIGTERM; 0, or ConfigError before anything listens."""
    ends = Endpoints(parse_endpoint(listen, "--listen"), parse_endpoint(to, "--to"))
    if stats_file:
        check_output(stats_file, force=force)   # refused now, not after the run
    emu = LinkEmulator(spec, ends, t0_on_signal)
    asyncio.run(_main(emu))
    emu.say("stopped; " + emu.stats.summary()
            + (f"; {len(emu.events)} outage(s), {emu.report()['outage_s']:.1f} s down"
               if emu.events else ""))
    if stats_file:
        with output(stats_file, force=force) as tmp:
            tmp.write_text(json.dumps(emu.report(), indent=1) + "\n", encoding="utf-8")
    return 0


async def _main(emu: LinkEmulator) -> None:
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    loop.add_signal_handler(signal.SIGUSR1, emu.restart_clock)
    await emu.serve(stop)
