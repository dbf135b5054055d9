"""What a node accepts from the bus and how it seals what it puts (pure; no Zenoh).

:class:`Trust` is a node's policy over :mod:`common.seal` (docs/architecture.md "Trust"):

- **No key** (a node started alone): nothing is sealed, everything is accepted (the stamp
  and payload checks of :class:`common.transport.Node` still apply).
- **A fixed run** (the launcher gave the run id, :data:`common.seal.RUN_ID_ENV`: every node
  of ``papf run``, the laptop side): only samples sealed with the key, new from their
  sender, and of this run are accepted; a recording, a charge, a command of another run
  never enter.
- **Following runs** (a key but no run id: the robot side, ``papf launch robot``, serving
  run after run): samples sealed with the key and new are accepted from any run, except
  commands: ``cmd_vel`` only of the run the last ``run_started`` began (outside a run only
  unrun commands, ``papf teleop``'s). A ``run_started`` counts only when sealed less than
  :data:`RUN_START_FRESH_S` ago by the receiver's clock (a captured one put again later to
  a freshly started driver is stale); ``run_ended`` of the run ends it. What such a node
  puts carries the run id of the last run-bearing sample it accepted (the LiDAR's scans
  carry its driver's run).

Every refused sample is counted per topic and reason (:attr:`Trust.refused`); the node's
health answer, ``papf topic list`` and the run's JSON show the counts. A run's node refuses
a sample sealed outside any run as :data:`~common.seal.BEFORE_RUN`, not ``other_run``: its
sender had not joined the run yet (what the robot side put while the run began, still on a
slow link). A follower refuses a command of a run whose ``run_started`` it has not accepted
(it remembers the last :data:`RUNS_KEPT`) as :data:`~common.seal.AHEAD_OF_RUN`, not ``other_run``: a new
run's first command, which overtook its ``run_started`` on another connection of a jittered
link (a command of a run it saw begin is still ``other_run``: an old laptop's). The first
:data:`EXPECTED` of each are :meth:`Trust.expected` at a split run's start; every other
refusal, and a sender that never joins (or a run whose start never comes), is worth a
warning (:meth:`Trust.alarming`).
"""

from __future__ import annotations

import os
import threading
from collections import Counter, deque

from common import runauth, seal

RUN_START_FRESH_S = 120.0   # [s] a run_started sealed longer ago (or ahead) than this is stale
COMMAND_TOPICS = frozenset({"cmd_vel"})   # strict to the current run even when following
# [samples] before_run refusals a node takes as a split run's start (4-6 per node seen over a
# 200 ms link); more are a sender that has not joined the run, worth a warning
BEFORE_RUN_EXPECTED = 50
# [commands] ahead_of_run refusals a follower takes as a run's start (1 per split run seen over
# a link with 150 ms of jitter: commands come at 10 Hz); more are a run whose start never came
AHEAD_OF_RUN_EXPECTED = 10
EXPECTED = {seal.BEFORE_RUN: BEFORE_RUN_EXPECTED, seal.AHEAD_OF_RUN: AHEAD_OF_RUN_EXPECTED}
WHY_EXPECTED = {seal.BEFORE_RUN: "its sender had not joined this run yet",
                seal.AHEAD_OF_RUN: "a new run's command, ahead of its run_started on the link"}
RUNS_KEPT = 64   # [-] run ids a follower remembers having seen begin


class Trust:
    """One node's seal policy (module doc). ``check`` runs on Zenoh's thread; the counters
    are read from others (:meth:`counts` copies under a lock)."""

    def __init__(self, key: bytes | None, run: bytes | None):
        self.key, self.fixed = key, run
        self.current: bytes | None = run          # the run a follower is in (None: none)
        self.sealer = seal.Sealer(key, run) if key else None
        self.opener = seal.Opener(key, None) if key else None
        self.refused: Counter[tuple[str, str]] = Counter()
        self._lock = threading.Lock()
        self._begun: deque[bytes] = deque(maxlen=RUNS_KEPT)   # a follower's runs seen begin

    @classmethod
    def from_env(cls, environ=os.environ) -> Trust:
        """The policy of a process the launcher started (key and run id from the environment)."""
        return cls(runauth.key_from_env(environ), seal.run_from_env(environ))

    @property
    def keyed(self) -> bool:
        return self.key is not None

    def seal(self, key_expr: str, payload: bytes) -> bytes | None:
        """The attachment for a put (None without a key)."""
        return None if self.sealer is None else self.sealer.seal(key_expr, payload)

    def _expected(self, topic: str, msg) -> bytes | None:
        """The run a sample must be of (None: any run)."""
        if self.fixed is not None:
            return self.fixed
        if topic in COMMAND_TOPICS:
            return self.current or seal.NO_RUN
        return None

    def check(self, topic: str, key_expr: str, payload: bytes, attachment: bytes | None,
              msg=None) -> str:
        """``"ok"`` or why the sample is refused (a :mod:`common.seal` verdict or ``stale``);
        a refusal is counted. ``msg``: the decoded message (events: run_started/ended)."""
        if self.opener is None:
            return seal.OK
        kind = getattr(msg, "kind", "") if topic == "events" else ""
        expected = None if kind == "run_started" else self._expected(topic, msg)
        verdict, run = self.opener.check(key_expr, payload, attachment, expected)
        if verdict == seal.OTHER_RUN and run == seal.NO_RUN and self.fixed is not None:
            verdict = seal.BEFORE_RUN   # its sender had not joined this run yet
        elif verdict == seal.OTHER_RUN and self.fixed is None and run not in (None, seal.NO_RUN) \
                and run not in self._begun:
            verdict = seal.AHEAD_OF_RUN   # a new run's command before its run_started
        if verdict == seal.OK and kind == "run_started" and self.fixed is None:
            age = seal.seq_age_s(attachment)
            if age is None or abs(age) > RUN_START_FRESH_S:
                verdict = "stale"
        if verdict != seal.OK:
            with self._lock:
                self.refused[(topic, verdict)] += 1
            return verdict
        self._follow(kind, run)
        return verdict

    def _follow(self, kind: str, run: bytes | None) -> None:
        if self.fixed is not None or run is None:
            return
        if kind == "run_started":
            self.current = run
            if run not in self._begun:
                self._begun.append(run)
        elif kind == "run_ended" and run == self.current:
            self.current = None
        if run != seal.NO_RUN and self.sealer is not None:
            self.sealer.run = run

    def expected(self, verdict: str) -> bool:
        """Whether a refusal of ``verdict`` (just counted) is one a run's start brings: a
        :data:`~common.seal.BEFORE_RUN` or :data:`~common.seal.AHEAD_OF_RUN` within the first
        :data:`EXPECTED` of its kind."""
        return verdict in EXPECTED and self._by_reason()[verdict] <= EXPECTED[verdict]

    def alarming(self) -> int:
        """How many refusals so far are worth a warning (all but the expected ones)."""
        by = self._by_reason()
        return sum(by.values()) - sum(min(by[verdict], n) for verdict, n in EXPECTED.items())

    def _by_reason(self) -> Counter[str]:
        """The refusals so far per reason, every topic together."""
        out: Counter[str] = Counter()
        with self._lock:
            for (_topic, why), n in self.refused.items():
                out[why] += n
        return out

    def counts(self) -> dict[str, dict[str, int]]:
        """``{topic: {reason: n}}`` of the refused samples so far."""
        with self._lock:
            items = list(self.refused.items())
        out: dict[str, dict[str, int]] = {}
        for (topic, verdict), n in items:
            out.setdefault(topic, {})[verdict] = n
        return out

    def run_hex(self) -> str:
        """The run this node is in, hex ("" for none)."""
        run = self.current if self.fixed is None else self.fixed
        return "" if run is None or run == seal.NO_RUN else run.hex()
