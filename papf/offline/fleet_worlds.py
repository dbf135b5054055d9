"""The packaged fleet worlds of robots that must pass each other (``worlds/fleet-*.toml``).

Written by ``python -m papf.offline.fleet_worlds [DIR]`` (default ``worlds/``, an existing file
is left alone unless ``--force``), so each layout is a formula and not hand-typed numbers:

- ``fleet-swap``: two ROSbots exactly head-on in the open, 6 m apart (the smallest
  reciprocal case: who gives way, and to which side);
- ``fleet-swap-4``: four, each to the opposite corner of a 4 m square (they meet in the
  middle, two head-on pairs crossing);
- ``fleet-ring-8``, ``fleet-ring-16``: 8 and 16 ROSbots evenly on a 6 m ring (3 m radius),
  each to the opposite side (the classic reciprocal-avoidance test, van den Berg et al.
  2011): every path crosses the centre at once;
- ``fleet-ring-32``: 32 ROSbots on a 12 m ring (6 m radius: the same 1.18 m between
  neighbours as ``fleet-ring-16``), each to the opposite side — the world format's largest
  fleet;
- ``fleet-junction``: two 2 m wide corridors cross; two robots on each arm's centre line
  drive straight across to the opposite arm, the first to its far end, the second behind it
  (8 robots, four streams meeting; 4.8 m each, 48 s at PAPF's 0.1 m/s).

``fleet-corridor-swap`` (two robots in a corridor, each on its right half) is older and
hand-written.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

RING_RADIUS_M = 3.0      # [m] the ring's radius (a 6 m ring)
SQUARE_HALF_M = 2.0      # [m] half side of fleet-swap-4's square
ARM_M = 4.0              # [m] a junction arm's length from the centre
HALF_WIDTH_M = 1.0       # [m] half the corridors' width
WALL_M = 0.1             # [m] wall thickness


def _robot(name: str, x: float, y: float, yaw: float, gx: float, gy: float) -> str:
    yaw = math.atan2(math.sin(yaw), math.cos(yaw))
    return (f'[[robots]]\nname = "{name}"\nstart = [{x:.4f}, {y:.4f}, {yaw:.5f}]\n'
            f'goal = [{gx:.4f}, {gy:.4f}]\n')


def _wall(a, b) -> str:
    return (f'[[obstacles]]\nkind = "wall"\nfrom = [{a[0]:.2f}, {a[1]:.2f}]\n'
            f'to = [{b[0]:.2f}, {b[1]:.2f}]\nthickness = {WALL_M}\n')


def ring(n: int, radius: float = RING_RADIUS_M) -> str:
    """``n`` robots evenly on a circle, each facing and driving to the opposite point."""
    rows = []
    for i in range(n):
        a = 2 * math.pi * i / n
        x, y = radius * math.cos(a), radius * math.sin(a)
        rows.append(_robot(f"r{i + 1}", x, y, a + math.pi, -x, -y))
    return "".join(rows)


def swap() -> str:
    """Two robots exactly head-on, 6 m apart."""
    return _robot("r1", -3.0, 0.0, 0.0, 3.0, 0.0) + _robot("r2", 3.0, 0.0, math.pi, -3.0, 0.0)


def swap_4(h: float = SQUARE_HALF_M) -> str:
    """Four robots at a square's corners, each to the opposite corner."""
    corners = [(-h, -h), (h, -h), (h, h), (-h, h)]
    return "".join(_robot(f"r{i + 1}", x, y, math.atan2(-y, -x), -x, -y)
                   for i, (x, y) in enumerate(corners))


def junction(arm: float = ARM_M, half: float = HALF_WIDTH_M) -> str:
    """A crossroads of two corridors; two robots per arm on its centre line, going across."""
    rows, k = [], 0
    near, far = arm - 2.2, arm - 1.0                    # [m] from the centre
    for a in range(4):                                  # east, north, west, south arms
        ux, uy = round(math.cos(a * math.pi / 2)), round(math.sin(a * math.pi / 2))
        for d, g in ((near, far), (far, near)):         # the first goes farther, the second follows
            k += 1
            rows.append(_robot(f"r{k}", ux * d, uy * d, math.atan2(-uy, -ux), -ux * g, -uy * g))
    for sx in (-1, 1):                                  # the four corners' walls
        for sy in (-1, 1):
            corner = (sx * half, sy * half)
            rows.append(_wall(corner, (sx * arm, sy * half)))
            rows.append(_wall(corner, (sx * half, sy * arm)))
    for a in range(4):                                  # each arm's end
        ux, uy = round(math.cos(a * math.pi / 2)), round(math.sin(a * math.pi / 2))
        rows.append(_wall((ux * arm - uy * half, uy * arm - ux * half),
                          (ux * arm + uy * half, uy * arm + ux * half)))
    return "".join(rows)


WORLDS = {
    "fleet-swap": ("Two ROSbots exactly head-on in the open, 6 m apart, swap places", swap),
    "fleet-swap-4": ("Four ROSbots at a 4 m square's corners, each to the opposite corner", swap_4),
    "fleet-ring-8": ("8 ROSbots on a 6 m ring, each to the opposite side", lambda: ring(8)),
    "fleet-ring-16": ("16 ROSbots on a 6 m ring, each to the opposite side", lambda: ring(16)),
    "fleet-ring-32": ("32 ROSbots on a 12 m ring, each to the opposite side",
                      lambda: ring(32, 2 * RING_RADIUS_M)),
    "fleet-junction": ("Two 2 m corridors cross; two ROSbots on each arm drive straight across",
                       junction),
}


def text(name: str) -> str:
    """The TOML of packaged world ``name``."""
    description, body = WORLDS[name]
    return f'name = "{name}"\ndescription = "{description}"\n' + body()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="write the packaged fleet worlds")
    ap.add_argument("out", nargs="?", type=Path, default=Path(__file__).resolve().parents[2] / "worlds")
    ap.add_argument("--force", action="store_true", help="replace existing files")
    args = ap.parse_args(argv)
    for name in WORLDS:
        path = args.out / f"{name}.toml"
        if path.exists() and not args.force:
            print(f"{path} exists (--force replaces it)")
            continue
        path.write_text(text(name))
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
