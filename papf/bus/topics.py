"""``papf topic list | echo | hz`` over a Zenoh session (what ``ros2 topic`` does for DDS).

Zenoh has no topic registry, so :func:`topic_list` listens to every key for a while and
reports what arrived (key, type, encoding, rate), the silent topics of the stack and the
nodes alive; :func:`echo` and :func:`hz` subscribe to one key expression (names:
:func:`resolve_key`; decoding: :mod:`papf.bus.decode`). Used by ``papf topic``.
"""

from __future__ import annotations

import json
import math
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import zenoh

from common.transport import alive_nodes
from papf.bus.decode import MAX_TEXT_CHARS, Decoded, as_text, decode, json_safe, safe_text, stamp_of
from papf.bus.stats import HzStats
from schemas import Keys, LinkHealth
from schemas.keys import TOPICS

Out = Callable[[str], None]
Stop = Callable[[], bool]


def resolve_key(name: str, keys: Keys, ros: str = "bridge", domain: int = 0) -> str:
    """``scan`` -> ``rosbot/scan`` (a stack topic); ``/scan`` -> the bridge's ``scan``, or on
    rmw_zenoh ``<domain>/scan/*/*`` (any type and hash); else as given.

    ``scan`` is our topic ``<ns>/scan``, ``/scan`` is the ROS 2 topic ``/scan`` (the bridge's
    key ``scan``, or with ``--ros rmw_zenoh`` rmw_zenoh's key of it in ``--ros-domain``),
    anything else is verbatim.
    """
    if name in TOPICS:
        return keys.key(name)
    if not name.startswith("/"):
        return name
    return f"{domain}/{name.strip('/')}/*/*" if ros == "rmw_zenoh" else name[1:]


MAX_INBOX_ITEMS = 1000               # samples waiting to be printed or counted
MAX_INBOX_BYTES = 64 * 1024 * 1024   # [bytes] their payloads together


class Inbox:
    """Samples of a key expression queued as (key, payload, arrival monotonic s), bounded.

    A peer may publish faster than a terminal prints (or publish 10 MB messages): past
    ``max_items`` samples or ``max_bytes`` of payload the oldest waiting samples are dropped
    and counted in :attr:`dropped` (the newest one always stays), so memory stays bounded
    whatever the bus carries.
    """

    def __init__(self, session: zenoh.Session | None, expr: str, max_items: int = MAX_INBOX_ITEMS,
                 max_bytes: int = MAX_INBOX_BYTES):
        self.max_items, self.max_bytes = max_items, max_bytes
        self.dropped = 0
        self._items: deque = deque()
        self._bytes = 0
        self._cond = threading.Condition()
        self.sub = None if session is None else session.declare_subscriber(expr, self._on_sample)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        if sample.kind == zenoh.SampleKind.PUT:
            self.put(str(sample.key_expr), sample.payload.to_bytes(), time.monotonic())

    def put(self, key: str, data: bytes, arrival: float) -> None:
        """Queue a sample; drop the oldest waiting ones past the bounds."""
        with self._cond:
            self._items.append((key, data, arrival))
            self._bytes += len(data)
            while len(self._items) > 1 and (len(self._items) > self.max_items
                                            or self._bytes > self.max_bytes):
                self._bytes -= len(self._items.popleft()[1])
                self.dropped += 1
            self._cond.notify()

    def get(self, timeout_s: float):
        """The next sample within ``timeout_s`` [s], else None."""
        with self._cond:
            if not self._items:
                self._cond.wait(max(timeout_s, 0.0))
            if not self._items:
                return None
            item = self._items.popleft()
            self._bytes -= len(item[1])
            return item

    def __len__(self) -> int:
        return len(self._items)

    def close(self) -> None:
        """Undeclare the subscriber."""
        if self.sub is not None:
            self.sub.undeclare()


# -- list ---------------------------------------------------------------------------------------
@dataclass
class TopicRow:
    key: str
    type_name: str = ""
    encoding: str = ""
    stats: HzStats = field(default_factory=HzStats)
    last: Any = None         # the last decoded value of a link report (LinkHealth)

    @property
    def count(self) -> int:
        """Messages seen on the topic."""
        return self.stats.count


def listen(session: zenoh.Session, expr: str, duration_s: float, stop: Stop = lambda: False,
           ros_type: str | None = None) -> dict[str, TopicRow]:
    """Every key that carried a message within ``duration_s``, with its type and rate."""
    rows: dict[str, TopicRow] = {}
    inbox = Inbox(session, expr)
    deadline = time.monotonic() + duration_s
    try:
        while not stop() and (left := deadline - time.monotonic()) > 0:
            item = inbox.get(min(left, 0.1))
            if item is None:
                continue
            key, data, arrival = item
            d = decode(key, data, ros_type)
            row = rows.setdefault(key, TopicRow(key))
            row.type_name = row.type_name or d.type_name
            row.encoding = row.encoding or d.encoding
            row.stats.add(arrival, d.stamp_ns)
            if d.type_name == LinkHealth.TYPE and isinstance(d.value, dict):
                row.last = d.value
    finally:
        inbox.close()
    return rows


def fleet_alive(session: zenoh.Session, timeout_s: float = 1.0) -> dict[str, list[str]]:
    """namespace -> its live nodes, for every namespace of the network (a fleet's robots)."""
    found: dict[str, list[str]] = {}
    for reply in session.liveliness().get("**/alive/*", timeout=timeout_s):
        if reply.ok is not None:
            ns, _, node = str(reply.ok.key_expr).rpartition("/alive/")
            found.setdefault(ns, []).append(node)
    return {ns: sorted(nodes) for ns, nodes in sorted(found.items())}


def topic_list(session: zenoh.Session, keys: Keys, duration_s: float, out: Out,
               stop: Stop = lambda: False, as_json: bool = False, only: bool = False,
               table: Callable | None = None) -> int:
    """Print what the bus carries (see the module doc); returns how many keys were heard.
    Every key of the network and every namespace's live nodes (a fleet); ``only``: the
    keys and nodes of ``keys``' namespace alone (one robot of a fleet). ``table``: given a
    rich ``Table`` of the keys, prints it (a terminal: :func:`papf.console.tables.print_table`,
    which fits it); without, one line per key (piped: whole lines a script reads)."""
    rows = listen(session, keys.key("**") if only else "**", duration_s, stop)
    for suffix, msg_type in TOPICS.items():   # the stack's topics that stayed silent
        rows.setdefault(keys.key(suffix), TopicRow(keys.key(suffix), msg_type.TYPE, "msgpack"))
    nodes = sorted(alive_nodes(session, keys))
    others = {} if only else {ns: n for ns, n in fleet_alive(session).items() if ns != keys.ns}
    heard = sum(1 for r in rows.values() if r.count)
    if as_json:
        for r in sorted(rows.values(), key=lambda r: r.key):
            rate = r.stats.rate()
            out(json.dumps(json_safe({"key": r.key, "type": r.type_name, "encoding": r.encoding,
                                      "messages": r.count, "hz": rate.hz,
                                      "stamp_hz": rate.stamp_hz})))
        for r in _link_rows(rows):
            out(json.dumps(json_safe({"link": r.key, **r.last})))
        refused = node_refusals(session, keys)
        out(json.dumps({"alive": nodes, **({"alive_elsewhere": others} if others else {}),
                        **({"refused": refused} if refused else {})}))
        return heard
    shown = {r.key: safe_text(r.key, MAX_KEY_CHARS) for r in rows.values()}   # a peer's key
    lines = [(shown[r.key], safe_text(r.type_name or "?", 60), safe_text(r.encoding, 20),
              _rate_text(r), str(r.count))
             for r in sorted(rows.values(), key=lambda r: (r.count == 0, r.key))]
    if table is not None:
        table(_keys_table(lines, duration_s))
    else:
        width = max(len(k) for k in shown.values())
        out(f"{'KEY':<{width}}  {'TYPE':<28} {'ENCODING':<8} {'RATE':>10}  MESSAGES "
            f"(heard for {duration_s:g} s)")
        for key, type_name, encoding, rate, count in lines:
            out(f"{key:<{width}}  {type_name:<28} {encoding:<8} {rate:>10}  {count}")
    for r in _link_rows(rows):
        out(link_line(shown[r.key], r.last))
    out(f"alive ({safe_text(keys.alive())}): {_names(nodes)}")
    for ns, names in others.items():   # the fleet's other namespaces
        out(f"alive ({safe_text(Keys(ns).alive() if _plain(ns) else ns)}): {_names(names)}")
    refused = node_refusals(session, keys)
    for node, topics in sorted(refused.items()):
        what = ", ".join(f"{safe_text(t, 80)} {safe_text(r, 20)} {n}"
                         for t, reasons in sorted(topics.items()) for r, n in sorted(reasons.items()))
        out(f"refused by {safe_text(node, 80)}: {what}")
    if nodes and not refused:
        out("refused: none (no node dropped a sample: unsealed, replayed, another run's, malformed)")
    return heard


HEALTH_S = 1.0   # [s] for the nodes' health answers


def node_refusals(session: zenoh.Session, keys: Keys) -> dict[str, dict[str, dict[str, int]]]:
    """``{node: {topic: {reason: n}}}``: what each live node of ``keys``' namespace refused
    (its health answer, :meth:`common.transport.Node.health`): samples without this run's
    seal, replays, another run's, and ``malformed`` ones (undecodable, a bad stamp)."""
    prefix = keys.key("health/")
    out: dict[str, dict[str, dict[str, int]]] = {}
    for reply in session.get(keys.key("health/*"), timeout=HEALTH_S):
        if reply.ok is None:
            continue
        try:
            data = json.loads(reply.ok.payload.to_bytes())
            counts = {str(t): {str(r): int(n) for r, n in why.items()}
                      for t, why in (data.get("refused") or {}).items()}
            for topic, n in (data.get("bad") or {}).items():
                counts.setdefault(str(topic), {})["malformed"] = int(n)
        except (ValueError, AttributeError, TypeError):
            continue   # not a node's answer: nothing to show
        if counts:
            out[str(reply.ok.key_expr)[len(prefix):]] = counts
    return out


def _link_rows(rows: dict[str, TopicRow]) -> list[TopicRow]:
    return [r for r in sorted(rows.values(), key=lambda r: r.key) if r.last is not None]


def link_line(key: str, h: dict) -> str:
    """The link as its last report says (docs/link-driving.md), one line."""
    def ms(name: str) -> str:
        v = h.get(name)
        return "?" if not isinstance(v, (int, float)) or v != v else f"{v:.0f}"
    refused = int(h.get("late", 0) or 0) + int(h.get("stale", 0) or 0)
    return (f"link ({key}, {safe_text(str(h.get('side', '?')), 20)} side): "
            f"{safe_text(str(h.get('state', '?')), 20)}, round trip p50 {ms('rtt_p50_ms')} / "
            f"p99 {ms('rtt_p99_ms')} ms, {refused} of {h.get('commands', 0)} commands refused, "
            f"{h.get('outages', 0)} outages ({float(h.get('outage_s', 0.0) or 0.0):.1f} s)")


MAX_KEY_CHARS = 120   # [chars] of a key shown in the table (a peer's 10 MB key stays one line)


def _rate_text(r: TopicRow) -> str:
    hz = r.stats.rate().hz
    return "silent" if not r.count else ("once" if math.isnan(hz) else f"{hz:.1f} Hz")


def _keys_table(lines: list[tuple[str, ...]], duration_s: float):
    """The keys as a rich ``Table`` (cells are text: a peer's "[...]" is no style tag)."""
    from rich.table import Table
    from rich.text import Text

    t = Table(title=f"heard for {duration_s:g} s", title_justify="left", box=None)
    for col in ("KEY", "TYPE", "ENCODING", "RATE", "MESSAGES"):
        t.add_column(col, justify="right" if col in ("RATE", "MESSAGES") else "left")
    for line in lines:
        t.add_row(*(Text(c) for c in line))
    return t


def _names(names) -> str:
    """Node names as a peer announced them, terminal-safe."""
    return ", ".join(safe_text(n, 80) for n in names) if names else "none"


def _plain(ns: str) -> bool:
    try:
        Keys(ns)
    except ValueError:
        return False
    return True


# -- echo ---------------------------------------------------------------------------------------
def echo(session: zenoh.Session, expr: str, out: Out, *, count: int = 0, timeout_s: float = 0.0,
         ros_type: str | None = None, max_items: int | None = 8, as_json: bool = False,
         stop: Stop = lambda: False, note: Out = lambda _line: None,
         duration_s: float = 0.0) -> int:
    """Print each message on ``expr`` until ``count`` (0: forever), ``duration_s`` (0:
    forever) or stop; returns how many.

    ``timeout_s`` > 0: give up when the first message has not come within that long.
    Messages that came faster than they could be printed are dropped, oldest first
    (:class:`Inbox`); ``note`` (stderr) says so the first time and how many at the end.
    """
    inbox = Inbox(session, expr)
    try:
        end = time.monotonic() + duration_s if duration_s > 0 else math.inf
        return _echo(inbox, out, count, timeout_s, ros_type, max_items, as_json,
                     lambda: stop() or time.monotonic() >= end, note)
    finally:
        inbox.close()
        if inbox.dropped:
            note(f"{inbox.dropped} messages dropped in all: they came faster than they could "
                 f"be printed (the {inbox.max_items} newest are kept)")


def _echo(inbox: Inbox, out: Out, count: int, timeout_s: float, ros_type: str | None,
          max_items: int | None, as_json: bool, stop: Stop, note: Out) -> int:
    shown = 0
    told = False
    deadline = time.monotonic() + timeout_s if timeout_s > 0 else math.inf
    while not stop() and (count <= 0 or shown < count):
        item = inbox.get(0.1)
        if item is None:
            if shown == 0 and time.monotonic() > deadline:
                break
            continue
        if inbox.dropped and not told:
            told = True
            note("messages come faster than they can be printed: the oldest waiting are "
                 "dropped (counted at the end)")
        key, data, _ = item
        out(format_sample(key, decode(key, data, ros_type), max_items, as_json))
        shown += 1
    return shown


def format_sample(key: str, d: Decoded, max_items: int | None, as_json: bool) -> str:
    """A decoded sample as ``papf topic echo`` prints it (text or a JSON line)."""
    if as_json:
        return json.dumps(json_safe({"key": key, "type": d.type_name, "encoding": d.encoding,
                                     "message": d.value, **({"error": d.error} if d.error else {})},
                                    None if max_items is None else MAX_TEXT_CHARS))
    head = f"# {safe_text(key)}  [{safe_text(d.type_name or '?')}, {safe_text(d.encoding)}]"
    if d.error:
        head += f"  INVALID: {safe_text(d.error)}"
    return f"{head}\n{as_text(d.value, max_items)}\n---"


# -- hz -----------------------------------------------------------------------------------------
def hz(session: zenoh.Session, expr: str, out: Out, *, window: int = 1000,
       period_s: float = 1.0, duration_s: float = 0.0, stop: Stop = lambda: False,
       ros_type: str | None = None, count: int = 0,
       reports: int = 0) -> dict[str, HzStats]:
    """Print each key's rate every ``period_s`` until ``duration_s`` (0: forever), ``count``
    messages (0: any number), ``reports`` printed reports (0: any number) or stop; then the
    rates once more (unless the last report was just that)."""
    stats: dict[str, HzStats] = {}
    inbox = Inbox(session, expr)
    t0 = time.monotonic()
    next_print, printed, heard = t0 + period_s, 0, 0
    try:
        while not stop() and not (count and heard >= count):
            now = time.monotonic()
            if duration_s > 0 and now - t0 >= duration_s:
                break
            if now >= next_print:
                next_print += period_s
                _print_rates(stats, expr, out)
                printed += 1
                if reports and printed >= reports:
                    return stats
            item = inbox.get(min(next_print - now, 0.1))
            if item is not None:
                key, data, arrival = item
                heard += 1
                stats.setdefault(key, HzStats(window)).add(arrival, stamp_of(key, data, ros_type))
    finally:
        inbox.close()
    _print_rates(stats, expr, out)
    return stats


def _print_rates(stats: dict[str, HzStats], expr: str, out: Out) -> None:
    if not stats:
        out(f"{expr}: no messages yet")
    for key in sorted(stats):
        out(stats[key].rate().line(key))
