"""A delaying TCP forwarder for the split-over-a-slow-link tests (test support, not a product).

``python -m tests.support.delaylink --listen PORT --to PORT [--delay MS] [--jitter MS]
[--outage S@T ...] [--seed N]`` accepts connections on ``127.0.0.1:PORT`` and forwards each to
``127.0.0.1:TO``, both ways, every chunk held ``delay + U(0, jitter)`` ms. Bytes of a TCP
stream cannot overtake each other, so a chunk leaves no earlier than the one before it (as a
real link's TCP delivers them). An outage ``S@T`` holds everything that arrives between ``T``
and ``T + S`` seconds (from the start) until its end, as TCP retransmission does on a link that
went down and came back: the queued bytes then arrive in one burst.

The product's emulator is ``papf link``; this one is a few lines so the tests need nothing else.
"""

from __future__ import annotations

import argparse
import asyncio
import random
import time

CHUNK = 65536


class Shape:
    """When a chunk read at monotonic ``now`` [s] may leave (delay, jitter, outages)."""

    def __init__(self, delay_ms: float, jitter_ms: float, outages: list[tuple[float, float]],
                 seed: int, t0: float):
        self.delay, self.jitter = delay_ms * 1e-3, jitter_ms * 1e-3
        self.outages = [(t0 + start, t0 + start + length) for length, start in outages]
        self.rng = random.Random(seed)
        self.serial = False

    def release_at(self, now: float, previous: float) -> float:
        at = now + self.delay + self.rng.uniform(0.0, self.jitter)
        for start, end in self.outages:
            if start <= now < end:
                at = max(at, end + self.delay)
        return max(at, previous)


async def _serial(reader, writer, shape: Shape) -> None:
    """Read, hold, write, read again: a naive store-and-forward proxy (``--serial``). Bytes that
    come while a chunk is held wait for the next read, so they are held up to two delays."""
    try:
        while data := await reader.read(CHUNK):
            await asyncio.sleep(shape.release_at(time.monotonic(), 0.0) - time.monotonic())
            writer.write(data)
            await writer.drain()
    except (ConnectionError, OSError):
        pass
    writer.close()


async def _pipe(reader, writer, shape: Shape) -> None:
    if shape.serial:
        await _serial(reader, writer, shape)
        return
    queue: asyncio.Queue = asyncio.Queue()

    async def pump() -> None:
        while True:
            at, data = await queue.get()
            if data is None:
                break
            wait = at - time.monotonic()
            if wait > 0:
                await asyncio.sleep(wait)
            writer.write(data)
            await writer.drain()
        writer.close()

    task = asyncio.create_task(pump())
    last = 0.0
    try:
        while data := await reader.read(CHUNK):
            last = shape.release_at(time.monotonic(), last)
            queue.put_nowait((last, data))
    except (ConnectionError, OSError):
        pass
    queue.put_nowait((last, None))
    try:
        await task
    except (ConnectionError, OSError):
        pass


async def serve(listen: int, to: int, shape: Shape) -> None:
    async def handle(r_in, w_in) -> None:
        try:
            r_out, w_out = await asyncio.open_connection("127.0.0.1", to)
        except OSError:
            w_in.close()
            return
        await asyncio.gather(_pipe(r_in, w_out, shape), _pipe(r_out, w_in, shape))

    server = await asyncio.start_server(handle, "127.0.0.1", listen)
    async with server:
        await server.serve_forever()


def _outage(text: str) -> tuple[float, float]:
    length, _, start = text.partition("@")
    return float(length), float(start)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tests.support.delaylink")
    ap.add_argument("--listen", type=int, required=True)
    ap.add_argument("--to", type=int, required=True)
    ap.add_argument("--delay", type=float, default=0.0, help="one way [ms]")
    ap.add_argument("--jitter", type=float, default=0.0, help="uniform 0..J [ms] on top")
    ap.add_argument("--outage", type=_outage, action="append", default=[], metavar="S@T")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--serial", action="store_true", help="a naive read-hold-write proxy")
    args = ap.parse_args(argv)
    shape = Shape(args.delay, args.jitter, args.outage, args.seed, time.monotonic())
    shape.serial = args.serial
    try:
        asyncio.run(serve(args.listen, args.to, shape))
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
