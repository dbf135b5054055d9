"""``papf experiment link``: what a bad link costs — APF and PAPF split over emulated links.

Each run is ``papf run --link`` (:mod:`papf.launch.split`): the robot side and the laptop
side on their own routers, joined through ``papf link``, in real time, on the energy world.
Two studies:

- **profiles**: every planner × link (``lan``, ``wifi``, ``wifi-bad``, ``lte``, 200 ms +
  0-150 ms) × outage (none; one of 10 s, 20 s into the drive): outcome, time, path, mAh,
  and what the link did (delays, outage time, the driver's watchdog stops and late commands);
- **sweep**: every planner × a fixed one-way delay (0 … 500 ms, no jitter): the latency up
  to which each planner still reaches its goal.

Writes ``OUT/link.csv``, ``OUT/link-sweep.csv``, ``OUT/link.md`` and ``OUT/link.png``; each
finished run is kept in ``OUT/runs/`` as it ends (:mod:`papf.experiments.journal`), so the
same command after Ctrl-C makes only the others.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from common.outfiles import replace_text
from nodes.planner.registry import one_with_role
from papf.experiments.journal import Journal, run_key
from papf.experiments.trials import markdown_table, write_csv
from worlds import load_world, world_path

WORLD = "energy"
PLANNERS = (one_with_role("papf-baseline"), one_with_role("papf-proposed"))
LINKS = (("lan", "lan"), ("wifi", "wifi"), ("wifi-bad", "wifi-bad"), ("lte", "lte"),
         ("200+0-150ms", "delay=200,jitter=150"))      # label, SPEC (the loaded Wi-Fi)
OUTAGES = (("none", ""), ("10s@20s", "outage=10@20"))
SWEEP_MS = (0, 50, 100, 200, 300, 500)                  # one-way delays of the sweep [ms]
TIMEOUT_S = 300.0       # [s run time] per run: APF takes ~145 s on the energy world over loopback
NAMESPACE = "linkexp"   # its own: a `papf launch` in `rosbot` is not disturbed


@dataclass(frozen=True)
class Case:
    study: str          # profiles | sweep
    planner: str
    link: str           # label
    spec: str           # papf run --link SPEC
    outage: str = "none"

    @property
    def name(self) -> str:
        return f"{self.planner}-{self.link}-{self.outage}"


def cases(planners: Sequence[str] = PLANNERS, links=LINKS, outages=OUTAGES,
          sweep_ms: Sequence[int] = SWEEP_MS) -> list[Case]:
    """Every run of both studies, profiles first."""
    out = [Case("profiles", p, label, ",".join(s for s in (spec, extra) if s), o)
           for p in planners for label, spec in links for o, extra in outages]
    out += [Case("sweep", p, f"{ms}ms", f"delay={ms},jitter=0,jitter_period=0") for p in planners
            for ms in sweep_ms]
    return out


def row_of(case: Case, result) -> dict:
    """The CSV row of one run (:class:`papf.launch.outcome.RunResult` over the link): the
    run's figures, what the emulator did (delays it applied, time down) and what the robot
    side measured (the run JSON's ``link``: round trip, commands refused as too late or
    stale; the driver's watchdog stops from ``link_emulator.robot_side``)."""
    emu = result.link_emulator or {}
    dirs = emu.get("directions", {})
    side = emu.get("robot_side", {})
    health = getattr(result, "link", None) or {}

    def delay(d: str, p: str):
        return (dirs.get(d, {}).get("delay_ms") or {}).get(p)

    def num(x, nd=3):
        return round(x, nd) if isinstance(x, float) and math.isfinite(x) else x
    refused = (None if "late_commands" not in health else
               health["late_commands"] + health.get("stale_commands", 0))
    return {"study": case.study, "planner": case.planner, "link": case.link, "spec": case.spec,
            "outage": case.outage, "outcome": result.outcome,
            "duration_s": num(result.duration_s, 2), "path_m": num(result.path_length_m),
            "charge_mAh": num(result.charge_mAh), "energy_J": num(result.energy_J, 1),
            "collisions": result.collisions,
            "delay_out_p50_ms": delay("out", "p50"), "delay_out_p99_ms": delay("out", "p99"),
            "delay_back_p50_ms": delay("back", "p50"), "delay_back_p99_ms": delay("back", "p99"),
            "rtt_p50_ms": health.get("rtt_p50_ms"), "rtt_p99_ms": health.get("rtt_p99_ms"),
            "commands": health.get("commands"), "refused_commands": refused,
            "outage_s": emu.get("outage_s"), "watchdog_stops": side.get("watchdog_stops"),
            "late_commands": side.get("late_commands"),
            "wall_time_s": num(result.wall_time_s, 1), "reason": result.reason}


def run_case(case: Case, seed: int, timeout_s: float, record: Path | None, world: str = WORLD,
             namespace: str = NAMESPACE):
    """One split run over ``case``'s link; its RunResult."""
    from papf.launch.run import RunConfig  # zenoh: only when a run is made
    from papf.launch.split import run_split

    return run_split(RunConfig(world=world, planner=case.planner, seed=seed, timeout_s=timeout_s,
                               record=str(record) if record else None, namespace=namespace,
                               link=case.spec, progress=False))


def run_link_experiment(out: str | Path, todo: Sequence[Case], seed: int = 0,
                        timeout_s: float = TIMEOUT_S, record: bool = False,
                        echo: Callable[[str], None] = print,
                        progress: bool | None = None, world: str = WORLD,
                        namespace: str = NAMESPACE) -> list[dict]:
    """Run ``todo`` (:func:`cases`) on ``world`` one after the other (real time: no two at
    once, they would load each other's links); write the CSVs, the Markdown and the plot."""
    from papf.console.progress import StepProgress

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    journal = Journal(out)
    world_text = world_path(world).read_text(encoding="utf-8")
    rows = []
    with StepProgress("link", len(todo), enabled=progress, out=echo) as bar:
        for case in todo:
            key = run_key("link", world_text, case.planner, case.spec, seed, timeout_s)
            row = journal.get(key)
            if row is None:
                bar.doing(f"{case.planner} over {case.link}, outage {case.outage}")
                mcap = out / "recordings" / f"{case.name}.mcap" if record else None
                if mcap is not None:
                    mcap.parent.mkdir(parents=True, exist_ok=True)
                    mcap.unlink(missing_ok=True)   # this run's, made again
                result = run_case(case, seed, timeout_s, mcap, world, namespace)
                if result.reason == "interrupted":   # Ctrl-C reached the run's launcher:
                    raise KeyboardInterrupt          # the experiment stops, finished runs kept
                row = row_of(case, result)
                row["load_avg"] = round(os.getloadavg()[0], 1)   # real time on a shared machine
                journal.put(key, row)
            rows.append(row)
            bar.step(f"{case.planner} over {case.link}, outage {case.outage}: {row['outcome']} "
                     f"{row['duration_s']} s {row['charge_mAh']} mAh")
    if journal.taken:
        echo(f"link: {journal.taken} of {len(rows)} runs finished before, taken from "
             f"{journal.dir} (delete it to make them again)")
    write_outputs(out, rows, load_world(world).name)
    return rows


def write_outputs(out: Path, rows: Sequence[dict], world: str = WORLD) -> None:
    """``link.csv``, ``link-sweep.csv``, ``link.md``, ``link.png`` from the runs' rows."""
    from papf.plots.link import plot_link

    profiles = [r for r in rows if r["study"] == "profiles"]
    sweep = [r for r in rows if r["study"] == "sweep"]
    vs = charge_vs_lan(profiles)
    profiles = [{**r, "charge_vs_lan_pct": vs[i]} for i, r in enumerate(profiles)]
    if profiles:
        write_csv(profiles, out / "link.csv")
    if sweep:
        write_csv(sweep, out / "link-sweep.csv")
    replace_text(out / "link.md", markdown(profiles, sweep, world))
    plot_link(profiles, sweep, out / "link.png")


def charge_vs_lan(rows: Sequence[dict]) -> dict[int, float | None]:
    """Each row's charge against its planner's LAN run without outage [%] (None: no such run,
    or one of the two did not reach)."""
    base = {r["planner"]: r["charge_mAh"] for r in rows
            if r["link"] == "lan" and r["outage"] == "none" and r["outcome"] == "reached"}
    return {i: (round(100.0 * (r["charge_mAh"] / base[r["planner"]] - 1.0), 1)
                if r["planner"] in base and r["outcome"] == "reached" else None)
            for i, r in enumerate(rows)}


def reached_up_to(sweep: Sequence[dict]) -> dict[str, str]:
    """Per planner: the largest swept delay up to which every run reached its goal."""
    out = {}
    for planner in dict.fromkeys(r["planner"] for r in sweep):
        ok = None
        for r in sorted((r for r in sweep if r["planner"] == planner),
                        key=lambda r: int(r["link"].removesuffix("ms"))):
            if r["outcome"] != "reached":
                break
            ok = r["link"]
        out[planner] = ok or "none of the delays swept"
    return out


def _refused(r: dict) -> str:
    """``refused / commands`` as the robot counted them, else the driver log's late count."""
    if r.get("refused_commands") not in (None, ""):
        return f"{r['refused_commands']} / {r.get('commands')}"
    return "" if r.get("late_commands") in (None, "") else f"{r['late_commands']} late"


def markdown(profiles: Sequence[dict], sweep: Sequence[dict], world: str = WORLD) -> str:
    """The experiment's tables: the profiles (with charge vs LAN) and the sweep."""
    def num(x, nd=1):
        return "" if x is None or x == "" else f"{x:.{nd}f}" if isinstance(x, float) else str(x)

    text = (f"# What a bad link costs (world {world}, `papf run --link`, real time)\n\n"
            "One run per cell; delays are one way, as the emulator applied them "
            "(laptop->robot / robot->laptop, p50).\n\n")
    if profiles:
        vs = charge_vs_lan(profiles)
        text += markdown_table(
            ["planner", "link", "outage", "outcome", "time [s]", "path [m]", "charge [mAh]",
             "vs LAN [%]", "delay p50 [ms]", "rtt p50 [ms]", "refused / commands",
             "outage [s]", "watchdog stops"],
            [[r["planner"], r["link"], r["outage"], r["outcome"], num(r["duration_s"]),
              num(r["path_m"], 2), num(r["charge_mAh"], 2), num(vs[i]),
              f"{num(r['delay_out_p50_ms'])} / {num(r['delay_back_p50_ms'])}",
              num(r.get("rtt_p50_ms")), _refused(r), num(r["outage_s"]), num(r["watchdog_stops"])]
             for i, r in enumerate(profiles)]) + "\n"
    if sweep:
        text += "\nDelay sweep (fixed one-way delay, no jitter):\n\n" + markdown_table(
            ["planner", "one-way delay", "outcome", "time [s]", "charge [mAh]",
             "refused / commands", "reason"],
            [[r["planner"], r["link"], r["outcome"], num(r["duration_s"]), num(r["charge_mAh"], 2),
              _refused(r), r["reason"]] for r in sweep]) + "\n\n"
        text += "Reaches its goal up to: " + ", ".join(
            f"{p} {d}" for p, d in reached_up_to(sweep).items()) + "\n"
    return text
