"""Zenoh plumbing shared by every node process (docs/architecture.md "Transport").

- :func:`add_zenoh_args` / :func:`config_from_args`: ``--mode/--connect/--listen/
  --namespace/--zenoh-config`` -> ``zenoh.Config`` (multicast scouting off unless asked).
- :class:`Node`: one node's session — typed publishers, decoding subscribers that
  count and drop bad payloads, an inbox the node's main thread drains (so a node's
  core runs on one thread, in arrival order), and the liveliness token
  ``<ns>/alive/<node>`` declared once the node is ready.
- :func:`wait_alive`: block until named nodes' liveliness tokens exist.

No maths here; algorithms never import this module.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import os
import queue
import select
import signal
import socket
import sys
import threading
import time
from collections import Counter
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

import zenoh

from common.errors import ConfigError, SchemaError
from common.intake import WHY_EXPECTED, Trust
from common.reach import session_error
from common.text import install_log_filter
from common.units import StampGuard
from schemas import Keys
from schemas.base import Message
from schemas.keys import STAMP_ORDERED, TOPICS

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
MODES = ("client", "peer", "router")
BATCH_POLL_S = 0.01      # [s wall] a node with batched topics drains them this often
BATCH_IDLE_POLL_S = 0.04  # [s wall] ... at most this seldom after drains that found nothing
BATCH_CAPACITY = 65536   # [samples] per batched topic between drains (then Zenoh waits)


def add_zenoh_args(parser: argparse.ArgumentParser) -> None:
    """The Zenoh options every node and command shares."""
    g = parser.add_argument_group("zenoh")
    g.add_argument("--mode", choices=MODES, default="client",
                   help="Zenoh session mode (default: client of a router)")
    g.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                   help=f"endpoint to connect to, repeatable (default for client: {DEFAULT_ENDPOINT})")
    g.add_argument("--listen", action="append", default=[], metavar="ENDPOINT",
                   help="endpoint to listen on, repeatable")
    g.add_argument("--namespace", default="rosbot", help="robot key namespace (default: rosbot)")
    g.add_argument("--zenoh-config", metavar="FILE",
                   help="Zenoh JSON5 config file (TLS, auth, access control); CLI options override it")
    g.add_argument("--multicast-scouting", action="store_true",
                   help="enable multicast scouting (off by default)")


def zenoh_config(mode: str = "client", connect: Iterable[str] = (), listen: Iterable[str] = (),
                 multicast: bool = False, config_file: str | None = None,
                 scout_delay_ms: int | None = None) -> zenoh.Config:
    """Build a ``zenoh.Config``; a client with no ``connect`` goes to the embedded router.

    ``scout_delay_ms``: Zenoh's ``scouting/delay``, how long ``zenoh.open`` of a peer or
    router waits for other peers before it returns (500 ms by default). A router with no
    multicast scouting and nothing to connect to has no one to wait for: give it 0.
    """
    if mode not in MODES:
        raise ConfigError(f"Zenoh mode {mode!r} is not one of {MODES}")
    try:
        conf = load_config_file(config_file) if config_file else zenoh.Config()
    except Exception as exc:  # zenoh raises ZError with the parser's message
        raise ConfigError(f"cannot read Zenoh config {config_file!r}: {exc}") from None
    connect, listen = list(connect), list(listen)
    if mode == "client" and not connect and not config_file:
        connect = [DEFAULT_ENDPOINT]
    conf.insert_json5("mode", json.dumps(mode))
    if connect:
        conf.insert_json5("connect/endpoints", json.dumps(connect))
    if listen:
        conf.insert_json5("listen/endpoints", json.dumps(listen))
    conf.insert_json5("scouting/multicast/enabled", json.dumps(bool(multicast)))
    if scout_delay_ms is not None:
        conf.insert_json5("scouting/delay", json.dumps(int(scout_delay_ms)))
    return conf


# Zenoh config fields that name files (TLS certificates and keys, the password dictionary)
PATH_FIELDS = ("root_ca_certificate", "listen_private_key", "listen_certificate",
               "connect_private_key", "connect_certificate", "dictionary_file")


def load_config_file(path: str) -> zenoh.Config:
    """A Zenoh config file whose relative file paths are relative to the file itself (so
    a bundle of certificates and configs works wherever it is copied). A JSON5 file that
    is not plain JSON is handed to Zenoh as it is (its paths relative to the working dir)."""
    text = Path(path).read_text(encoding="utf-8")
    try:
        data = json.loads(text)
    except ValueError:
        return zenoh.Config.from_file(path)
    _resolve_paths(data, Path(path).resolve().parent)
    return zenoh.Config.from_json5(json.dumps(data))


def _resolve_paths(node, base: Path) -> None:
    if isinstance(node, dict):
        for k, v in node.items():
            if k in PATH_FIELDS and isinstance(v, str) and not Path(v).is_absolute():
                node[k] = str(base / v)
            else:
                _resolve_paths(v, base)
    elif isinstance(node, list):
        for v in node:
            _resolve_paths(v, base)


def config_from_args(args: argparse.Namespace) -> zenoh.Config:
    """The Zenoh config of the bus options in ``args`` (mode, connect, listen, scouting, file)."""
    return zenoh_config(args.mode, args.connect, args.listen, args.multicast_scouting,
                        args.zenoh_config)


def connect_endpoints(conf: zenoh.Config) -> list[str]:
    """The endpoints a session of ``conf`` connects to (``--connect`` or its config file's)."""
    try:
        eps = json.loads(conf.get_json("connect/endpoints"))
    except (ValueError, zenoh.ZError):
        return []
    return [str(ep) for ep in eps] if isinstance(eps, list) else []


@contextmanager
def open_session(args: argparse.Namespace, where: str = ""):
    """``zenoh.open`` for a command's ``args``; a session that does not open (no router, or
    one that refused our credentials) is a ConfigError (one line, exit 2: :mod:`common.reach`)
    instead of a Zenoh traceback."""
    conf = config_from_args(args)
    try:
        session = zenoh.open(conf)
    except zenoh.ZError as exc:
        endpoints = connect_endpoints(conf)
        raise session_error(exc, endpoints, getattr(args, "zenoh_config", None),
                            where or ", ".join(endpoints) or DEFAULT_ENDPOINT) from None
    with session:
        yield session


def direct(callback) -> zenoh.handlers.Callback:
    """``callback`` as a subscriber handler run on Zenoh's receiving thread itself.

    A plain callable is run by zenoh-python on a Python thread of its own per subscriber
    (``indirect``): every sample then wakes that thread, which wakes the node's main
    thread — two hops. Our callbacks only decode and queue (they never block or put), so
    they run where the sample arrives: one hop, and samples keep their arrival order
    across topics.
    """
    return zenoh.handlers.Callback(callback, indirect=False)


def exit_fast(code: int | None) -> None:
    """End a node process whose work is done (its session closed, its files and pybullet
    clients closed by their ``with`` blocks): flush the logs and the standard streams, then
    ``os._exit`` — skipping the interpreter's teardown of every module and object, which
    takes 0.1–1 s with numpy, pybullet and numba loaded and which the launcher would wait
    for at the end of every run. ``if __name__ == "__main__": exit_fast(main())``."""
    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(code or 0)


def setup_logging(name: str, level: str = "INFO") -> logging.Logger:
    """The node's logger, its lines stamped with the time and ``name``."""
    logging.basicConfig(level=level, format=f"%(asctime)s {name:>12} %(levelname)-7s %(message)s",
                        datefmt="%H:%M:%S")
    install_log_filter()   # a peer's text in a log line is shown, never run (common.text)
    return logging.getLogger(name)


STOP_BOUND_S = 5.0       # [s wall] a node still running this long after a stop request exits
PARENT_POLL_S = 0.5      # [s wall] how often a node looks whether its launcher still lives
ALARM_EXTRA_S = 2        # [s wall] the kernel's SIGALRM comes this long after the bound
NODE_ENV = "PAPF_NODE_PROCESS"   # set by the launcher's Supervisor: a node process, bounded
                                 # (never a test's own process that builds a Node)


class StopRequested:
    """SIGINT/SIGTERM -> a flag the main loop polls (the session then closes cleanly).

    ``wake`` (optional) is called right after, from the signal handler, to wake a main
    thread that sleeps on a queue (a ``SimpleQueue.put``, which is reentrant): the node
    then stops at once instead of at its next idle tick.

    ``bound_s`` (nodes): the stop is bounded — a process still alive that long after the
    request leaves at once (``os._exit``). Closing a Zenoh session whose router is gone can
    block for minutes; a node must not outlive its launcher that way (issue 30: a meter
    lived on for 5 minutes with its router gone, keeping its liveliness token). Every
    instance of a process hears the signal (a fleet driver has one node per robot).

    A signal is seen even when Python does not run its handler: the interpreter's C-level
    handler also writes the signal's number to a wakeup socket (``signal.set_wakeup_fd``),
    which :meth:`__bool__` and :meth:`wait` read. On CPython 3.11 a signal that reaches the
    process while a helper thread (a log pump, a Zenoh thread) holds the interpreter can have
    its Python handler put off indefinitely — the main thread waiting in ``Event.wait(0.2)``
    loops on, never told (issue 31: ``papf launch robot`` hung on Ctrl-C about 1 launch in
    60; ``bench/ctrlc_loop.py`` reproduces it).
    """

    _instances: list[StopRequested] = []
    _wakeup: socket.socket | None = None     # the read end of the process's wakeup socket

    def __init__(self, wake=None, bound_s: float | None = None) -> None:
        self.event = threading.Event()
        self._wake = wake
        self.bound_s = bound_s
        self._timer: threading.Timer | None = None
        StopRequested._instances.append(self)
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                signal.signal(sig, StopRequested._on_signal)
            StopRequested._install_wakeup()

    @classmethod
    def _install_wakeup(cls) -> None:
        if cls._wakeup is not None:
            return
        read, write = socket.socketpair()
        read.setblocking(False)
        write.setblocking(False)
        try:
            signal.set_wakeup_fd(write.fileno(), warn_on_full_buffer=False)
        except ValueError:   # not the main thread of the main interpreter: handlers only
            read.close()
            write.close()
            return
        cls._wakeup, cls._wakeup_write = read, write   # both kept open for the process's life

    @staticmethod
    def _on_signal(*_) -> None:
        for stop in list(StopRequested._instances):
            stop.request()

    @classmethod
    def _poll_wakeup(cls) -> None:
        """A SIGINT/SIGTERM the C handler noted: every instance stops."""
        if cls._wakeup is None:
            return
        try:
            data = cls._wakeup.recv(256)
        except (BlockingIOError, InterruptedError, OSError):
            return
        if any(b in (signal.SIGINT, signal.SIGTERM) for b in data):
            cls._on_signal()

    def request(self, why: str = "") -> None:
        """Stop (from a signal handler or any thread); arms the bound once.

        The kernel's bound is armed first, before anything that takes a lock or needs another
        thread: SIGALRM's default action ends the process even when a Zenoh call holds the
        interpreter while it waits for a runtime thread that waits for the interpreter — then
        neither the timer below nor this very call (its ``Thread.start`` waits for the new
        thread) could go on. Seen: a planner whose launcher was SIGKILLed, every thread in a
        futex wait, alive 15 s later because the alarm came after the timer's start."""
        bounded = self.bound_s is not None and self._timer is None and os.environ.get(NODE_ENV)
        if bounded:
            signal.alarm(int(self.bound_s) + ALARM_EXTRA_S)
        self.event.set()
        if self._wake is not None:
            self._wake()
        if bounded and self._timer is None:
            self._timer = threading.Timer(self.bound_s, _bounded_exit, args=(self.bound_s, why))
            self._timer.daemon = True
            self._timer.start()

    def wait(self, timeout_s: float) -> bool:
        """Sleep up to ``timeout_s`` or until stopped (a signal wakes it at once); stopped?"""
        if not self:
            read = StopRequested._wakeup
            if read is not None and threading.current_thread() is threading.main_thread():
                select.select([read], [], [], timeout_s)
            else:
                self.event.wait(timeout_s)
        return bool(self)

    def __bool__(self) -> bool:
        if not self.event.is_set():
            StopRequested._poll_wakeup()
        return self.event.is_set()


def _bounded_exit(bound_s: float, why: str) -> None:
    """The stop took longer than its bound: say so and leave without closing anything. No
    lock is taken here (not logging's: the thread that holds one may be the one stuck)."""
    with contextlib.suppress(OSError):
        os.write(2, (f"still running {bound_s:g} s after the stop request"
                     f"{f' ({why})' if why else ''} (a Zenoh close waiting for a router that is "
                     "gone?): exiting now\n").encode())
    os._exit(1)


def watch_parent(stop: StopRequested, poll_s: float = PARENT_POLL_S) -> threading.Thread:
    """Stop when the process that started this one is gone (its parent id changes): the
    launcher's ``PR_SET_PDEATHSIG`` does it on Linux from the kernel, this on any system and
    for a node whose signal was lost. Returns the (daemon) watcher thread."""
    parent = os.getppid()

    def watch() -> None:
        while not stop.event.wait(poll_s):
            if os.getppid() != parent:
                logging.getLogger("papf.node").warning(
                    "the launcher (process %d) is gone: stopping", parent)
                stop.request("launcher gone")
                return

    thread = threading.Thread(target=watch, daemon=True, name="parent-watch")
    thread.start()
    return thread


def round_robin(channels) -> Iterator[tuple[str, type, bytes, bytes | None]]:
    """``(topic, message type, payload, attachment)`` of every sample waiting in ``channels``
    (tuples of topic, message type and a subscriber with a ``FifoChannel``), taken one per
    channel in turn, so streams published in step (odom(t), wheels(t)) come out in step too."""
    live = list(channels)
    while live:
        for entry in list(live):
            topic, msg_type, sub = entry
            sample = sub.try_recv()
            if sample is None:
                live.remove(entry)
            else:
                yield topic, msg_type, sample.payload.to_bytes(), attachment_of(sample)


def attachment_of(sample: zenoh.Sample) -> bytes | None:
    """A sample's attachment as bytes (a seal: :mod:`common.seal`), or None."""
    att = sample.attachment
    return None if att is None else att.to_bytes()


def _copy(counts: dict) -> dict:
    """A copy of a dict another thread writes to (Zenoh's): empty if it grew meanwhile."""
    try:
        return dict(counts.copy())
    except RuntimeError:   # written on Zenoh's thread right now: next time
        return {}


class Node:
    """A node's Zenoh session with typed, fault-tolerant pub/sub.

    Received messages are decoded in Zenoh's callback thread and queued as
    ``(topic, message)`` in a C-level ``SimpleQueue`` (one lock-free put per message, and the
    main thread sleeps until data comes); :meth:`messages` hands them to the main thread.
    A *batched* topic (``subscribe(..., batched=True)``) skips both hand-offs: Zenoh keeps
    its samples in its own channel, and :meth:`messages` drains them every
    :data:`BATCH_POLL_S` on the main thread — for a node that watches a stream and is not on
    the lockstep's path (the meter), where one wake per batch replaces two per message. A
    drain that finds nothing doubles the wait (up to :data:`BATCH_IDLE_POLL_S`), one that
    finds samples resets it: in lockstep the samples come in one burst per cycle, and a
    fleet's sixteen meters polling every 10 ms between bursts cost more than their work.
    A payload that fails to decode, or whose stamp is out of range or goes back on a
    stamp-ordered topic (:class:`common.units.StampGuard`), is logged (rate-limited),
    counted in :attr:`bad_messages` and dropped: a bad peer never crashes a node.

    Seals (:mod:`common.seal`, policy :class:`common.intake.Trust`): with the run's key in
    its environment the node seals every put and accepts only sealed samples of its run
    that are new; the others are counted per topic and reason (``trust.refused``) and
    dropped. ``<ns>/health/<name>`` answers what it refused and dropped (``papf topic list``,
    the launcher's run JSON).
    """

    def __init__(self, name: str, session: zenoh.Session, keys: Keys, log: logging.Logger,
                 trust: Trust | None = None):
        self.name, self.session, self.keys, self.log = name, session, keys, log
        self.inbox: queue.SimpleQueue = queue.SimpleQueue()
        self.bad_messages: Counter[str] = Counter()
        self.stamps = StampGuard(STAMP_ORDERED)
        self.trust = trust if trust is not None else Trust.from_env()
        self._key_exprs: dict[str, str] = {}
        self._health = None
        self.extra_health: dict = {}   # what a node adds to its health answer (the recorder's file)
        self.stop = StopRequested(wake=lambda: self.inbox.put((None, None)),  # a tick, at once
                                  bound_s=STOP_BOUND_S)
        self._publishers: dict[str, zenoh.Publisher] = {}
        self._subscribers: list[zenoh.Subscriber] = []
        self._batched: list[tuple[str, type[Message], zenoh.Subscriber]] = []
        self._gathered: list[Node] = []            # shares drained with this node's (gather)
        self._listeners: list = []                 # matching listeners of on-demand topics
        self._unheard: set[str] = set()            # on-demand topics no subscriber matches now
        self._token = None
        self._last: tuple[Message | None, bytes] = (None, b"")   # last message put, encoded
        # the stamp of the last sample taken and put per topic: the health answer's, for a
        # run that names where a held lockstep cycle waits (papf/launch/sequence.py)
        self.heard: dict[str, int] = {}
        self.sent: dict[str, int] = {}

    # -- publishing -------------------------------------------------------
    def publish(self, topic: str, msg: Message) -> None:
        """Put ``msg`` on ``<ns>/<topic>``; the topic's type is checked (TOPICS)."""
        expected = TOPICS.get(topic)
        if expected is not None and not isinstance(msg, expected):
            raise TypeError(f"{topic} carries {expected.__name__}, not {type(msg).__name__}")
        if topic in self._unheard:   # an on-demand topic nobody subscribes to: no encode, no put
            return
        pub = self._publishers.get(topic)
        if pub is None:
            pub = self._declare(topic)
        if msg is not self._last[0]:  # the same message on two keys (sim/pose, odom): encode once
            self._last = (msg, msg.to_bytes())
        payload = self._last[1]
        self.sent[topic] = getattr(msg, "stamp_ns", -1)
        if self.trust.keyed:
            pub.put(payload, attachment=self.trust.seal(self.key_expr(topic), payload))
        else:
            pub.put(payload)

    def key_expr(self, topic: str) -> str:
        """``<ns>/<topic>`` (cached: the seal covers the key)."""
        key = self._key_exprs.get(topic)
        if key is None:
            key = self._key_exprs[topic] = self.keys.key(topic)
        return key

    def declare_publishers(self, *topics: str, on_demand: Iterable[str] = ()) -> None:
        """Declare publishers up front (before :meth:`ready`) so first puts are not late.

        ``on_demand``: debug topics put only while a subscriber matches them (Zenoh's
        matching status, kept by a listener): :meth:`publish` drops their messages
        unencoded while nobody listens, and :meth:`listened` tells the node so it need not
        build them at all. A put nobody matches reaches no one either way.
        """
        for topic in (*topics, *on_demand):
            if topic not in self._publishers:
                self._declare(topic)
        for topic in on_demand:
            self._watch_matching(topic)

    def listened(self, topic: str) -> bool:
        """False only for an on-demand topic no subscriber matches now."""
        return topic not in self._unheard

    def _watch_matching(self, topic: str) -> None:
        pub = self._publishers[topic]

        def on_change(status) -> None:   # Zenoh's thread; a set add/discard is atomic
            (self._unheard.discard if status.matching else self._unheard.add)(topic)

        self._unheard.add(topic)   # unheard until Zenoh says otherwise; a race can only
        self._listeners.append(pub.declare_matching_listener(direct(on_change)))  # leave it
        if pub.matching_status.matching:                                         # heard
            self._unheard.discard(topic)

    def _declare(self, topic: str) -> zenoh.Publisher:
        # BLOCK: a full queue waits rather than drops (lockstep and recordings need every
        # message). Not express: batching costs no latency on an idle link, and express
        # puts cost ~10 us each against ~1.3 us (measured on loopback through the router).
        pub = self.session.declare_publisher(self.keys.key(topic),
                                             congestion_control=zenoh.CongestionControl.BLOCK)
        self._publishers[topic] = pub
        return pub

    # -- subscribing ------------------------------------------------------
    def subscribe(self, topic: str, msg_type: type[Message] | None = None, *,
                  handler=None, batched: bool = False) -> None:
        """Decode ``<ns>/<topic>`` as ``msg_type`` (default: TOPICS) into the inbox or
        ``handler``; ``batched``: kept in Zenoh's channel and drained by :meth:`messages`."""
        msg_type = msg_type or TOPICS[topic]
        if batched:
            sub = self.session.declare_subscriber(self.keys.key(topic),
                                                  zenoh.handlers.FifoChannel(BATCH_CAPACITY))
            self._batched.append((topic, msg_type, sub))
            self._subscribers.append(sub)
            return
        deliver = handler or (lambda m, t=topic: self.inbox.put((t, m)))

        def on_sample(sample: zenoh.Sample) -> None:
            msg = self.accept(topic, sample.payload.to_bytes(), msg_type, attachment_of(sample))
            if msg is not None:
                deliver(msg)

        self._subscribers.append(self.session.declare_subscriber(self.keys.key(topic),
                                                                 direct(on_sample)))

    def accept(self, topic: str, payload: bytes, msg_type: type[Message] | None = None,
               attachment: bytes | None = None):
        """``payload`` decoded as ``topic``'s message, or None: a bad payload or stamp is
        counted in :attr:`bad_messages`, a sample without this run's seal in
        ``trust.refused``, and dropped (never an exception). The seal is checked before the
        stamp: what a keyless peer sends moves no stamp window."""
        try:
            msg = (msg_type or TOPICS[topic]).from_bytes(payload)
        except SchemaError as exc:
            self._count_bad(topic, exc)
            return None
        verdict = self.trust.check(topic, self.key_expr(topic), payload, attachment, msg)
        if verdict != "ok":
            self._count_refused(topic, verdict)
            return None
        why = self.stamps.check(topic, msg)
        if why:
            self._count_bad(topic, why)
            return None
        self.heard[topic] = getattr(msg, "stamp_ns", -1)
        return msg

    def _count_bad(self, topic: str, exc: Exception | str) -> None:
        self.bad_messages[topic] += 1
        n = self.bad_messages[topic]
        if n <= 5 or n % 100 == 0:
            self.log.warning("dropped bad message #%d on %s: %s", n, self.keys.key(topic), exc)

    def _count_refused(self, topic: str, verdict: str) -> None:
        if self.trust.expected(verdict):   # a split run's start: counted, said once per topic
            if self.trust.refused[(topic, verdict)] == 1:
                self.log.info("dropped %s at a run's start (%s: %s)", self.keys.key(topic),
                              verdict, WHY_EXPECTED[verdict])
            return
        n = self.trust.alarming()
        if n <= 5 or n % 100 == 0:
            self.log.warning("refused #%d on %s: %s (not sealed with this run's key, a replay, "
                             "or another run's)", n, self.keys.key(topic), verdict)

    def messages(self, tick_s: float = 0.1) -> Iterator[tuple[str | None, Message | None]]:
        """Yield inbox items (and batched topics' samples) until stop; ``(None, None)``
        every ``tick_s`` of silence.

        Batched samples waiting when an inbox item comes are yielded before it (they mostly
        arrived first). Nothing a lockstep cycle waits for is batched (docs/architecture.md).
        """
        if not (self._batched or self._gathered):
            while not self.stop:
                try:
                    yield self.inbox.get(timeout=tick_s)
                except queue.Empty:
                    yield None, None
            return
        silent_s, idle_s = 0.0, BATCH_POLL_S
        while not self.stop:
            got = False
            for item in self._drain_batched():
                got = True
                yield item
            # nothing came: wait longer next time (an inbox item still wakes at once)
            idle_s = BATCH_POLL_S if got else min(2 * idle_s, BATCH_IDLE_POLL_S, tick_s)
            try:
                item = self.inbox.get(timeout=idle_s)
            except queue.Empty:
                silent_s = 0.0 if got else silent_s + idle_s
                if silent_s >= tick_s:
                    silent_s = 0.0
                    yield None, None
                continue
            silent_s = 0.0
            yield from self._drain_batched()
            yield item

    def _drain_batched(self) -> Iterator[tuple[str, Message]]:
        """Every sample waiting in the batched topics' channels, decoded and checked, in
        :func:`round_robin` order; then the gathered shares', as ``<namespace>/<topic>``."""
        for topic, msg_type, payload, attachment in round_robin(self._batched):
            msg = self.accept(topic, payload, msg_type, attachment)
            if msg is not None:
                yield topic, msg
        for share in self._gathered:
            for topic, msg in share._drain_batched():
                yield f"{share.keys.ns}/{topic}", msg

    def share(self, robot: str, log: logging.Logger | None = None) -> Node:
        """The node robot ``robot`` of a process serving a fleet is seen as: a :class:`Node`
        of this one's name on this session under the robot's namespace (its own keys, seals,
        stamps, health answer and token), its batched topics drained by this node's
        :meth:`messages` (:meth:`gather`); for ``""`` (no ``--robots``), this node itself."""
        if not robot:
            return self
        share = Node(self.name, self.session, Keys(robot), log or self.log)
        self.gather(share)
        return share

    def gather(self, share: Node) -> None:
        """Drain ``share``'s batched topics in this node's :meth:`messages` (a process that
        serves several robots, one :class:`Node` per robot on this session: one loop, one
        wake per batch for all of them). Its samples are checked by ``share`` (its keys, its
        seals, its stamps) and come out as ``<share's namespace>/<topic>``."""
        self._gathered.append(share)

    # -- health -----------------------------------------------------------
    def ready(self) -> None:
        """Declare the liveliness token (subscriptions and publishers now exist) and the
        health queryable ``<ns>/health/<name>``."""
        self._health = self.session.declare_queryable(self.keys.key(f"health/{self.name}"),
                                                      self._answer_health)
        self._token = self.session.liveliness().declare_token(self.keys.alive(self.name))
        self.log.info("ready as %s", self.keys.alive(self.name))

    def health(self) -> dict:
        """What this node refused and dropped so far, its run, and the stamp it last took and
        put on each topic (JSON-ready)."""
        return {"node": self.name, "run": self.trust.run_hex(), "keyed": self.trust.keyed,
                "refused": self.trust.counts(), "bad": _copy(self.bad_messages),
                "stamp_resyncs": self.stamps.resyncs, "heard": _copy(self.heard),
                "sent": _copy(self.sent), "peers": self._peers(), **self.extra_health}

    def _peers(self) -> int | None:
        """How many Zenoh peers this node's session links to directly now (None: unknown)."""
        try:
            return sum(1 for _ in self.session.info.peers_zid())
        except Exception:   # no session (a test's node), or one closing
            return None

    def _answer_health(self, query) -> None:   # Zenoh's thread: a copy of counters, one reply
        try:
            query.reply(self.keys.key(f"health/{self.name}"), json.dumps(self.health()).encode())
        except Exception as exc:   # a closing session: nothing to answer with
            self.log.debug("health query not answered: %s", exc)

    def close(self) -> None:
        """Undeclare the node's liveliness token and subscribers."""
        if self._token is not None:
            self._token.undeclare()
        if self._health is not None:
            self._health.undeclare()
            self._health = None
        for sub in self._subscribers:
            sub.undeclare()
        self._batched.clear()
        self._gathered.clear()
        for listener in self._listeners:
            listener.undeclare()
        self._listeners.clear()
        for pub in self._publishers.values():
            pub.undeclare()
        self._subscribers.clear()
        self._publishers.clear()


def fleet_names(robots: str | None) -> list[str]:
    """A node's ``--robots r1,r2,...`` as the namespaces it serves (``[""]`` without it: the
    one of ``--namespace``); ConfigError for a name that is no plain key, or a repeated one.
    A node serving several robots gives each a :class:`Node` of its own on its session."""
    if robots is None:
        return [""]
    names = robots.split(",")
    try:
        for name in names:
            Keys(name)
    except ValueError as exc:
        raise ConfigError(f"--robots {robots!r}: {exc}") from None
    if "/" in robots or len(set(names)) != len(names):
        raise ConfigError(f"--robots {robots!r}: robot names (plain keys without /), "
                          "each once, comma-separated")
    return names


@contextmanager
def open_node(name: str, args: argparse.Namespace, log: logging.Logger | None = None):
    """``with open_node("planner", args) as node:`` — session closed on exit, always."""
    log = log or setup_logging(name, getattr(args, "log_level", "INFO"))
    with open_session(args) as session:   # no router: one line (ConfigError), no traceback
        node = Node(name, session, Keys(args.namespace), log)
        watch_parent(node.stop)
        try:
            yield node
        finally:
            node.stop.request()   # from here on the exit is bounded (STOP_BOUND_S)
            node.close()
            if node.bad_messages:
                log.info("bad messages dropped: %s", dict(node.bad_messages))
            if node.trust.refused:
                log.info("refused (seal): %s", node.trust.counts())


def alive_nodes(session: zenoh.Session, keys: Keys, timeout_s: float = 1.0) -> set[str]:
    """Names of the nodes whose liveliness tokens exist now (the query's replies within
    ``timeout_s``; the router answers at once unless the machine is very busy)."""
    prefix = keys.alive("")
    names = set()
    for reply in session.liveliness().get(keys.alive("*"), timeout=timeout_s):
        if reply.ok is not None:
            names.add(str(reply.ok.key_expr)[len(prefix):])
    return names


def wait_alive(session: zenoh.Session, keys: Keys, names: Iterable[str], timeout_s: float,
               poll_s: float = 0.05, abort=lambda: False) -> set[str]:
    """Wait until every named node is alive; return the missing ones on timeout/abort.

    Woken by a liveliness subscriber (tokens already declared come as its history), so a
    node counts the moment its token arrives; ``abort`` is checked every ``poll_s``.
    """
    wanted, alive = set(names), set()
    prefix = keys.alive("")
    changed = threading.Condition()

    def on_token(sample: zenoh.Sample) -> None:
        with changed:
            name = str(sample.key_expr)[len(prefix):]
            (alive.add if sample.kind == zenoh.SampleKind.PUT else alive.discard)(name)
            changed.notify_all()

    sub = session.liveliness().declare_subscriber(keys.alive("*"), direct(on_token), history=True)
    deadline = time.monotonic() + timeout_s
    try:
        with changed:
            while wanted - alive and time.monotonic() <= deadline and not abort():
                changed.wait(poll_s)
            return wanted - alive
    finally:
        sub.undeclare()
