"""A rosbag2 recorded on the ROSbot, read as one of our recordings (docs/recording.md "Bags").

:func:`open_run` gives :class:`BagRecording` for a rosbag2 and our
:class:`~papf.recording.reader.Recording` for anything else; both answer alike, so
``papf report``, ``animate`` and ``replay`` take either. Topic mapping and stamps:
:class:`BagRecording`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, fields, replace
from pathlib import Path

from rosbags.highlevel import AnyReader

from common import ros2_convert as rc
from common.errors import ConfigError, RecordingError
from nodes.base_driver.rosbot import wheel_states
from papf.recording.reader import RawMessage, RecordedMessage, Recording, key_matches
from schemas.messages import BatteryVoltage, Odometry

NS = "rosbot"
CLOCK_SKEW_MAX_NS = 60_000_000_000   # [ns] header vs receive time beyond this: another clock
SOURCE = "rosbag2"                    # the run metadata's ``source`` of a bag


@dataclass(frozen=True)
class TopicMap:
    """Which bag topic plays which role; the defaults are the ROSbot's names."""

    odom: str = "/odometry/filtered"
    battery: str = "/battery"
    cmd_vel: str = "/cmd_vel"
    scan: str = "/scan"
    tf: str = "/tf"

    @classmethod
    def parse(cls, text: str | None) -> TopicMap | None:
        """``"odom=/odom,battery=/battery_state"`` (roles not named keep the ROSbot's name);
        None when none is given: each bag then gets :meth:`for_bag`'s."""
        if not text:
            return None
        roles, given = [f.name for f in fields(cls)], {}
        for item in text.split(","):
            role, eq, topic = (s.strip() for s in item.partition("="))
            if role not in roles or not eq:
                raise ConfigError(f"--topics {text!r}: {item.strip()!r} is not ROLE=/topic with "
                                  f"ROLE one of {', '.join(roles)}")
            if role in given or not topic.startswith("/") or " " in topic:
                raise ConfigError(f"--topics {text!r}: {role} given twice or {topic!r} is not a "
                                  "ROS 2 topic name (/name)")
            given[role] = topic
        return replace(cls(), **given)


    @classmethod
    def for_bag(cls, have: dict[str, tuple[str, int]]) -> TopicMap:
        """The names of a bag nobody named: the ROSbot's where the bag has them, else the
        ROS 2 face's and ``papf export ros2``'s (:data:`FACE_NAMES`, e.g. ``/odom``) where it
        has those with the role's type. So the stack's own bags read back without flags."""
        given = {}
        for role, names in FACE_NAMES.items():
            default = getattr(cls(), role)
            if default in have:
                continue
            found = [n for n in names if have.get(n, ("",))[0] == ROLE_TYPES[role]]
            if found:
                given[role] = found[0]
        return replace(cls(), **given)


FACE_NAMES = {"odom": ("/odom",)}   # role -> names the face and our export use instead
ROLE_TYPES = {"odom": rc.ODOMETRY, "battery": rc.BATTERY_STATE, "cmd_vel": rc.TWIST,
              "scan": rc.LASER_SCAN, "tf": rc.TF_MESSAGE}
REQUIRED = ("odom", "battery", "cmd_vel", "scan")
ROLE_KEYS = {"odom": ("odom", "wheels"), "battery": ("battery/measured",),
             "cmd_vel": ("cmd_vel",), "scan": ("scan",), "tf": ()}


def is_rosbag(path: str | Path, topics: TopicMap | None = None) -> bool:
    """A rosbag2 from the robot: its directory, its ``.db3``, or its ``.mcap`` (CDR messages,
    and beside its ``metadata.yaml`` or holding the odometry topic). Any other CDR MCAP stays
    a plain MCAP, which ``papf replay`` republishes byte for byte (docs/recording.md)."""
    p = Path(path)
    if p.is_dir():
        return (p / "metadata.yaml").is_file()
    if p.suffix == ".db3":
        return p.is_file()
    if p.suffix != ".mcap" or not p.is_file():
        return False
    try:
        from mcap.reader import make_reader
        with open(p, "rb") as fh:
            summary = make_reader(fh).get_summary()
    except Exception:   # not an MCAP, or a broken one: the recording reader says which
        return False
    if summary is None:
        return False
    cdr = {c.topic for c in summary.channels.values() if c.message_encoding == "cdr"}
    odoms = {topics.odom} if topics else {TopicMap().odom, *FACE_NAMES["odom"]}
    return bool(cdr) and ((p.parent / "metadata.yaml").is_file() or bool(odoms & cdr))


STACK_KEYS = ("world", "planner", "seed", "energy_model", "profile", "software_version")


def stack_metadata(path: str | Path) -> dict[str, str]:
    """What a bag of ours says about its run (``papf.*`` in ``custom_data`` of its
    ``metadata.yaml``: world, planner, seed …; ``papf run --format ros2``, ``papf export
    ros2``); {} for anyone else's bag or an unreadable file."""
    import yaml

    p = Path(path)
    meta = (p if p.is_dir() else p.parent) / "metadata.yaml"
    try:
        info = yaml.safe_load(meta.read_text(encoding="utf-8"))["rosbag2_bagfile_information"]
        custom = info.get("custom_data") or {}
    except (OSError, ValueError, TypeError, KeyError, AttributeError, yaml.YAMLError):
        return {}
    return {k[5:]: str(v) for k, v in custom.items()
            if isinstance(k, str) and k.startswith("papf.") and k[5:] in STACK_KEYS}


def open_run(path: str | Path, topics: TopicMap | None = None) -> Recording | BagRecording:
    """Our recording, or a rosbag2 read as one (:class:`BagRecording`)."""
    return BagRecording(path, topics) if is_rosbag(path, topics) else Recording(path)


def topics_hint(topics: TopicMap, have: dict[str, tuple[str, int]]) -> str:
    """The fix of a bag whose topic names are not the ROSbot's: the ``--topics`` that reads
    it when each role's type is on one topic of the bag (a ``papf export ros2`` bag: ``odom
    =/odom``), else how to write one."""
    fits = {}
    for role in REQUIRED:
        if have.get(getattr(topics, role), ("",))[0] == ROLE_TYPES[role]:
            continue
        of_type = [t for t, (m, _n) in sorted(have.items()) if m == ROLE_TYPES[role]]
        if len(of_type) != 1:
            return ("Map its topic names with --topics odom=/...,battery=/...,cmd_vel=/...,"
                    "scan=/... (papf info BAG lists them)")
        fits[role] = of_type[0]
    return "Read it with --topics " + ",".join(f"{r}={t}" for r, t in fits.items())


class BagRecording:
    """A rosbag2 as a read-only recording of our messages on ``rosbot/...`` keys.

    ``open_run(path)`` gives :class:`BagRecording` for a rosbag2 (its directory with
    ``metadata.yaml``, its ``.mcap`` with ``cdr`` messages, or its sqlite3 ``.db3``) and our
    :class:`~papf.recording.reader.Recording` for anything else; both answer ``messages()``,
    ``raw()``, ``counts()``, ``keys()`` and ``run_metadata`` alike, so ``papf report``,
    ``animate`` and ``replay`` take either. The bag is read with rosbags' ``AnyReader``
    (message definitions from the bag, else ROS 2 Jazzy's) and converted back to our messages
    on our keys (namespace ``rosbot``):

    - ``/odometry/filtered`` -> ``odom`` and ``wheels`` (wheel speeds and torques from the
      odometry, as the live ROSbot driver derives them: :func:`nodes.base_driver.rosbot.wheel_states`);
    - ``/battery`` -> ``battery/measured`` (its voltage, as the live driver publishes it); its
      current, where it carries one, is the measured charge (:func:`measured_charge_mAh`);
    - ``/cmd_vel`` -> ``cmd_vel``; ``/scan`` -> ``scan`` (the LiDAR at its mount, common.robot);
      ``/tf`` (optional) is only counted.

    Stamps: a message's header stamp (the bag's receive time for ``/cmd_vel``, and for a
    topic whose header stamps are unset or more than a minute from the receive time: another
    clock), in ns since the bag's first stamp, so a bag's time starts near 0 like a run's.
    ``--topics odom=/odom,battery=/battery_state`` maps another robot's names; without it a
    bag that has no ``/odometry/filtered`` but the face's ``/odom`` (``papf export ros2``,
    ``--format ros2``) is read by those (:meth:`TopicMap.for_bag`).
    """

    def __init__(self, path: str | Path, topics: TopicMap | None = None):
        self.path = Path(path)
        try:
            self._reader = AnyReader([self.path], default_typestore=rc.typestore())
            self._reader.open()
        except Exception as exc:   # rosbags raises its own errors for unreadable bags
            raise RecordingError(f"{self.path}: not a readable rosbag2 ({exc})") from None
        self.topics = topics or TopicMap.for_bag(self.bag_topics())
        try:
            self.conns = self._connections()
            self._header_clock = {r: self._uses_header(c) for r, c in self.conns.items()}
            self.t0_ns = self._first_stamp()
        except BaseException:
            self.close()
            raise
        self.metadata = {"run": {"namespace": NS, "source": SOURCE, "planner": "robot",
                                 "world": f"bag {self.path.name}", "bag": str(self.path),
                                 **stack_metadata(self.path)}}

    def __enter__(self) -> BagRecording:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the bag."""
        if self._reader.stack is not None:
            self._reader.close()

    # -- the bag's topics -----------------------------------------------------------------------
    def bag_topics(self) -> dict[str, tuple[str, int]]:
        """Every topic of the bag: name -> (type, messages)."""
        out: dict[str, tuple[str, int]] = {}
        for c in self._reader.connections:
            _type, n = out.get(c.topic, (c.msgtype, 0))
            out[c.topic] = (c.msgtype, n + c.msgcount)
        return out

    def _connections(self) -> dict[str, list]:
        have = self.bag_topics()
        missing = [f"{getattr(self.topics, r)} ({ROLE_TYPES[r]})" for r in REQUIRED
                   if getattr(self.topics, r) not in have]
        wrong = [f"{getattr(self.topics, r)} is {have[getattr(self.topics, r)][0]}, not "
                 f"{ROLE_TYPES[r]}" for r in ROLE_TYPES
                 if getattr(self.topics, r) in have and have[getattr(self.topics, r)][0]
                 != ROLE_TYPES[r]]
        if missing or wrong:
            listed = ", ".join(f"{t} ({m})" for t, (m, _n) in sorted(have.items())) or "none"
            what = "; ".join(([f"no {', '.join(missing)}"] if missing else []) + wrong)
            raise ConfigError(f"{self.path}: {what} in the bag; it has {listed}. "
                              + topics_hint(self.topics, have))
        return {r: [c for c in self._reader.connections if c.topic == getattr(self.topics, r)]
                for r in ROLE_TYPES if getattr(self.topics, r) in have}

    def _uses_header(self, conns: list) -> bool:
        """Whether a topic's header stamps are on the bag's clock (see the class doc)."""
        if not conns or conns[0].msgtype in (rc.TWIST, rc.TF_MESSAGE):
            return False
        for conn, log_ns, data in self._reader.messages(connections=conns):
            stamp = rc.stamp_of(self._reader.deserialize(data, conn.msgtype).header)
            return stamp > 0 and abs(stamp - log_ns) <= CLOCK_SKEW_MAX_NS
        return False

    def _first_stamp(self) -> int:
        starts = [self._reader.start_time]
        for role, conns in self.conns.items():
            if self._header_clock[role]:
                for conn, _log, data in self._reader.messages(connections=conns):
                    starts.append(rc.stamp_of(self._reader.deserialize(data, conn.msgtype).header))
                    break
        return min(starts)

    # -- as one of our recordings ---------------------------------------------------------------
    @property
    def run_metadata(self) -> dict[str, str]:
        """The run's metadata (as a recording of ours would carry it)."""
        return self.metadata["run"]

    def counts(self) -> dict[str, int]:
        """Our messages per key (``battery/measured``: at most the bag's battery messages)."""
        out = {}
        for role, conns in self.conns.items():
            for suffix in ROLE_KEYS[role]:
                out[f"{NS}/{suffix}"] = sum(c.msgcount for c in conns)
        return out

    def keys(self, expr: str | Iterable[str] | None = None) -> list[str]:
        """Our keys in the bag, those matching ``expr`` if given."""
        exprs = [expr] if isinstance(expr, str) else expr
        keys = sorted(self.counts())
        return keys if exprs is None else [k for k in keys if any(key_matches(e, k) for e in exprs)]

    def time_span_ns(self) -> tuple[int, int]:
        """(0, span of the bag [ns]) relative to its first message."""
        return 0, max(self._reader.end_time - self.t0_ns, 0)

    def messages(self, keys: str | Iterable[str] | None = None,
                 log_time_order: bool = True) -> Iterator[RecordedMessage]:
        """Our messages in the bag's order; each one's log time is its stamp."""
        wanted = set(self.keys(keys))
        roles = [r for r in self.conns if any(f"{NS}/{s}" in wanted for s in ROLE_KEYS[r])]
        conns = [c for r in roles for c in self.conns[r]]
        role_of = {c.id: r for r in roles for c in self.conns[r]}
        prev: Odometry | None = None
        for conn, log_ns, data in self._reader.messages(connections=conns) if conns else ():
            role = role_of[conn.id]
            msg = self._reader.deserialize(data, conn.msgtype)
            stamp = self._stamp(role, msg, log_ns)
            for suffix, ours in self._convert(role, msg, stamp, prev):
                if isinstance(ours, Odometry):
                    prev = ours
                key = f"{NS}/{suffix}"
                if key in wanted:
                    yield RecordedMessage(key, ours, ours.stamp_ns)

    def raw(self, keys: str | Iterable[str] | None = None,
            log_time_order: bool = True) -> Iterator[RawMessage]:
        """Our messages as msgpack payloads (what ``papf replay`` publishes)."""
        for key, msg, log_ns in self.messages(keys):
            yield RawMessage(key, msg.to_bytes(), log_ns, self.t0_ns + log_ns, msg.TYPE, "msgpack")

    def _stamp(self, role: str, msg, log_ns: int) -> int:
        stamp = rc.stamp_of(msg.header) if self._header_clock.get(role) else log_ns
        return max(stamp - self.t0_ns, 0)

    @staticmethod
    def _convert(role: str, msg, stamp: int, prev: Odometry | None) -> list[tuple[str, object]]:
        if role == "odom":
            odom = rc.odometry_of(msg, stamp)
            return [("odom", odom), ("wheels", wheel_states(prev, odom))]
        if role == "battery":
            v = float(msg.voltage)
            ok = math.isfinite(v) and v > 0.0
            return [("battery/measured", BatteryVoltage(stamp_ns=stamp, voltage=v,
                                                        source=SOURCE))] if ok else []
        if role == "cmd_vel":
            return [("cmd_vel", rc.twist_of(msg, stamp))]
        if role == "scan":
            return [("scan", rc.scan_of(msg, stamp))]
        return []

    # -- the measured charge ---------------------------------------------------------------------
    def battery_currents(self) -> list[tuple[int, float | None]]:
        """(stamp [ns], discharge current [A] or None where the message carries none)."""
        out = []
        for conn, log_ns, data in self._reader.messages(connections=self.conns["battery"]):
            msg = self._reader.deserialize(data, conn.msgtype)
            out.append((self._stamp("battery", msg, log_ns), rc.discharge_current_of(msg)))
        return out


def measured_charge_mAh(samples: list[tuple[int, float | None]], t_from_ns: int,
                        t_to_ns: int) -> float | None:
    """∫ I dt [mAh] over [t_from, t_to] (trapezoids between consecutive samples that both
    carry a current, clipped to the window); None when no sample carries one."""
    if not any(i is not None for _t, i in samples):
        return None
    total = 0.0   # [A s]
    for (t0, i0), (t1, i1) in zip(samples, samples[1:], strict=False):
        if i0 is None or i1 is None or t1 <= t0:
            continue
        a, b = max(t0, t_from_ns), min(t1, t_to_ns)
        if b <= a:
            continue
        ia = i0 + (i1 - i0) * (a - t0) / (t1 - t0)
        ib = i0 + (i1 - i0) * (b - t0) / (t1 - t0)
        total += 0.5 * (ia + ib) * (b - a) * 1e-9
    return total / 3.6
