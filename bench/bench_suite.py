"""Where the test suite's time goes: ``papf bench suite [--commit REV] [--label L] [--csv F]``.

Clones this repository at ``REV`` into a new directory and runs what ``.ci/run`` runs there,
one step at a time — ``make setup`` (a new venv; empty pip and uv caches unless ``--warm``;
numba's cache is the new clone's own), ``make test`` (the README's test command: every tier
in one pytest run; at a commit from before ``make test-quick`` existed, every tier but the
slow one, and then ``make test-slow``, CI's second step then), ``make lint`` — timing each:
wall seconds, and CPU seconds of the step and every process it reaped (``RUSAGE_CHILDREN``).
The tests' steps run with the plugin :mod:`bench.pytest_cpu`, which charges each test with
its CPU; ``--files-csv`` writes the sums per test file and tier. Run it on a quiet machine:
the suite is CPU-bound on 2 cores, so the load of other jobs is its time too (the 1-minute
load before and after each step is in the CSV). Speed is reported, never asserted;
a failing step is reported and ends the measurement (exit 1).
"""

from __future__ import annotations

import collections
import json
import os
import re
import resource
import shutil
import subprocess
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

from bench.csvrows import check_csv, replace_label
from common.cliparse import ArgumentParser

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
STEPS = (("setup", ["make", "setup"]), ("make test", ["make", "test"]), ("make lint", ["make", "lint"]))
# a commit whose `make test` left the slow tier out (no `test-quick` target): CI ran it second
STEPS_TWO_RUNS = (*STEPS[:2], ("make test-slow", ["make", "test-slow"]), STEPS[2])
FIELDS = ("date", "label", "commit", "step", "wall_s", "cpu_s", "cpu_over_wall", "tests_passed",
          "load_before", "load_after")
FILE_FIELDS = ("date", "label", "commit", "tier", "file", "tests", "cpu_s", "wall_s")
PLUGIN = "papf_bench_cpu_per_test"


def _cpu_children_s() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_step(name: str, cmd: list[str], cwd: Path, env: dict) -> dict:
    """One step of ``.ci/run`` in ``cwd``: its wall and CPU seconds, tests passed, the load."""
    load0, cpu0, t0 = os.getloadavg()[0], _cpu_children_s(), time.perf_counter()
    proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t0, _cpu_children_s() - cpu0
    if proc.returncode != 0:
        lines = (proc.stdout + proc.stderr).strip().splitlines()
        named = [x for x in lines if x.startswith(("FAILED ", "ERROR "))]   # pytest's summary
        raise SystemExit(f"step {name!r} failed (exit {proc.returncode}):\n" +
                         "\n".join([*named, *lines[-5:]]))
    passed = re.findall(r"(\d+) passed", proc.stdout)
    return {"step": name, "wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
            "cpu_over_wall": round(cpu / wall, 2) if wall else "",
            "tests_passed": passed[-1] if passed else "",
            "load_before": round(load0, 2), "load_after": round(os.getloadavg()[0], 2)}


def per_file(work: Path) -> list[dict]:
    """The plugin's per-test rows summed per test file and tier (``slow`` for a test with
    that marker, else the test's folder: unit, bus, e2e); first each tier's sum (file
    ``(all)``), then the files, the costliest first."""
    sums: dict[tuple[str, str], list[float]] = collections.defaultdict(lambda: [0, 0.0, 0.0])
    # the workers' files only: a test that runs pytest itself (a scaffolded planner's test)
    # writes cpu.main.tsv, and its CPU is already its test's
    for tsv in work.glob("cpu*.gw*.tsv"):
        for line in tsv.read_text().splitlines():
            cpu, wall, tier, nodeid = line.split("\t", 3)
            acc = sums[(tier, nodeid.split("::")[0])]
            acc[0] += 1
            acc[1] += float(cpu)
            acc[2] += float(wall)
    for (tier, _f), (n, c, w) in list(sums.items()):   # each tier's sum: file "(all)"
        acc = sums[(tier, "(all)")]
        acc[0] += n
        acc[1] += c
        acc[2] += w
    rows = [{"tier": tier, "file": f, "tests": n, "cpu_s": round(c, 1), "wall_s": round(w, 1)}
            for (tier, f), (n, c, w) in sums.items()]
    return sorted(rows, key=lambda r: (r["file"] != "(all)", -r["cpu_s"]))


def main(argv: list[str] | None = None) -> int:
    ap = ArgumentParser(prog="papf bench suite", description=__doc__.split("\n\n")[0])
    ap.add_argument("--commit", default="HEAD", help="the commit to measure (default HEAD)")
    ap.add_argument("--label", default="", help="this measurement's name in the CSVs (default the commit)")
    ap.add_argument("--warm", action="store_true",
                    help="keep this user's pip and uv caches (default: empty ones, as a new machine)")
    ap.add_argument("--csv", type=Path, help="the steps' rows (this label's rows are replaced)")
    ap.add_argument("--files-csv", type=Path, help="CPU per test file and tier")
    args = ap.parse_args(argv)
    commit = subprocess.run(["git", "rev-parse", "--short", args.commit], cwd=REPO, text=True,
                            capture_output=True).stdout.strip()
    if not commit:
        ap.error(f"--commit: {args.commit!r} is not a commit of {REPO}")
    label = args.label or commit
    for path, fields in ((args.csv, FIELDS), (args.files_csv, FILE_FIELDS)):
        if path:
            check_csv(path, fields)   # before the 10 minutes of work, not after
    work = Path(tempfile.mkdtemp(prefix="papf-bench-suite-"))
    try:
        tree = work / "clone"
        subprocess.run(["git", "clone", "-q", str(REPO), str(tree)], check=True)
        subprocess.run(["git", "checkout", "-q", commit], cwd=tree, check=True)
        env = {**os.environ, "CI": "true", "PYTEST_ADDOPTS": f"-p {PLUGIN}"}
        if not args.warm:
            env.update(PIP_NO_CACHE_DIR="1", UV_CACHE_DIR=str(work / "uv-cache"))
        date = datetime.now(timezone.utc).strftime("%Y-%m-%d")
        rows = []
        one_run = "test-quick:" in (tree / "Makefile").read_text()
        for name, cmd in STEPS if one_run else STEPS_TWO_RUNS:
            env["PAPF_CPU_PER_TEST"] = str(work / ("cpu-slow" if "slow" in name else "cpu"))
            row = {"date": date, "label": label, "commit": commit, **run_step(name, cmd, tree, env)}
            print(json.dumps(row), flush=True)
            rows.append(row)
            if name == "setup":   # the plugin, where every pytest of the clone's venv finds it
                purelib = subprocess.run(
                    [str(tree / ".venv/bin/python"), "-c",
                     "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                    capture_output=True, text=True, check=True).stdout.strip()
                shutil.copy(HERE / "pytest_cpu.py", Path(purelib) / f"{PLUGIN}.py")
        total = {"date": date, "label": label, "commit": commit, "step": "total",
                 "wall_s": round(sum(r["wall_s"] for r in rows), 1),
                 "cpu_s": round(sum(r["cpu_s"] for r in rows), 1)}
        total["cpu_over_wall"] = round(total["cpu_s"] / total["wall_s"], 2)
        print(json.dumps(total), flush=True)
        if args.csv:
            replace_label(args.csv, FIELDS, label, [*rows, total])
        if args.files_csv:
            files = [{"date": date, "commit": commit, **r} for r in per_file(work)]
            replace_label(args.files_csv, FILE_FIELDS, label, files)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
