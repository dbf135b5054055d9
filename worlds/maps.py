"""ROS maps (Nav2 ``map_server`` YAML + PGM/PNG image) as occupancy grids, read and written.

Follows ros-navigation/navigation2 ``nav2_map_server/src/map_io.cpp`` exactly:
:func:`load_map` is ``loadMapYaml`` (required keys ``image``, ``resolution``, ``origin``
[x, y, yaw], ``free_thresh``, ``occupied_thresh``, ``negate``; optional ``mode`` trinary |
scale | raw; ``image`` relative to the YAML's folder) + ``loadMapFromFile`` (a pixel's
shade = mean of R, G, B — and of the opacity in trinary mode when the image has an alpha
channel — over 255; occ = shade if negate else 1 - shade; trinary: occ > occupied_thresh occupied,
occ < free_thresh free, else unknown; scale: a not-opaque pixel unknown, else the same
thresholds with the middle scaled to 0..100; raw: round(shade * 255) in 0..100 is that
value, else unknown; image row 0 is the map's top: cell (x, y) = pixel (x, height-1-y)).
:func:`save_map` is ``tryWriteMapToFile`` in trinary mode (free 254, occupied 0,
unknown 205; YAML with ``negate: 0``; ``free_thresh`` 0.196 so unknown reads back unknown). Used by ``worlds`` (``[map]``), ``papf export map``.
Occupied and unknown cells are walls (:attr:`OccupancyMap.walls`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from common.errors import WorldError
from common.syntax import yaml_problem

MAX_YAML_BYTES = 1024 * 1024   # [bytes] a map's YAML (a few lines; as a world file)

MODES = ("trinary", "scale", "raw")
FREE, OCCUPIED, UNKNOWN = 0, 100, -1          # nav2_util/occ_grid_values.hpp
# free_thresh written: ROS 1 map_saver's 0.196, not Nav2's default 0.25 — with 0.25 the
# unknown shade 205 (occ 0.196) reads back as free, and unknown cells must stay walls
FREE_THRESH = 0.196
MAX_CELLS = 100_000_000                       # [-] 10 km² at 1 cm; beyond, memory runs out first


@dataclass(frozen=True, eq=False)
class OccupancyMap:
    """An occupancy grid: ``data`` [row = y, col = x] in -1 | 0..100, row 0 at the origin.

    ``resolution`` [m/cell]; ``origin`` (x [m], y [m], yaw [rad]) of cell (0, 0)'s lower-left
    corner; ``source`` the YAML it came from."""

    data: np.ndarray
    resolution: float
    origin: tuple[float, float, float]
    source: str = ""
    walls: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        walls = (self.data == UNKNOWN) | (self.data >= OCCUPIED)
        object.__setattr__(self, "walls", walls)

    @property
    def shape(self) -> tuple[int, int]:
        return self.data.shape

    def to_cells(self, pts: np.ndarray) -> np.ndarray:
        """(N, 2) world points [m] -> (N, 2) continuous (col, row) cell coordinates."""
        x0, y0, yaw = self.origin
        c, s = math.cos(yaw), math.sin(yaw)
        rx, ry = pts[:, 0] - x0, pts[:, 1] - y0
        return np.column_stack([c * rx + s * ry, -s * rx + c * ry]) / self.resolution

    def to_world(self, cells: np.ndarray) -> np.ndarray:
        """(N, 2) continuous (col, row) cell coordinates -> (N, 2) world points [m]."""
        x0, y0, yaw = self.origin
        c, s = math.cos(yaw), math.sin(yaw)
        u, v = cells[:, 0] * self.resolution, cells[:, 1] * self.resolution
        return np.column_stack([x0 + c * u - s * v, y0 + s * u + c * v])


def load_map(path: str | Path) -> OccupancyMap:
    """The map of a Nav2 map YAML (module doc); WorldError, one line, on any problem."""
    path = Path(path)
    meta = _read_yaml(path)
    image = _image_path(path, meta)
    res = _number(path, meta, "resolution", positive=True)
    origin = meta.get("origin")
    if not isinstance(origin, list) or len(origin) != 3:
        _fail(path, "origin", f"must be [x, y, yaw] (3 numbers), got {origin!r}")
    origin = tuple(_number(path, {"origin": v}, "origin") for v in origin)
    free = _number(path, meta, "free_thresh")
    occupied = _number(path, meta, "occupied_thresh")
    if not 0.0 <= free < occupied <= 1.0:
        _fail(path, "free_thresh/occupied_thresh", f"need 0 <= free_thresh < occupied_thresh <= 1, "
              f"got {free!r} and {occupied!r}")
    mode = meta.get("mode", "trinary")
    if mode not in MODES:
        _fail(path, "mode", f"{mode!r} is not one of {', '.join(MODES)}")
    negate = meta.get("negate", _MISSING)
    if negate is _MISSING or not isinstance(negate, (bool, int)) or negate not in (0, 1):
        _fail(path, "negate", f"must be 0 or 1 (or true/false), got {negate!r}")
    rgba, matte = _pixels(path, image)
    data = occupancy(rgba, mode, bool(negate), free, occupied, matte)
    return OccupancyMap(data, res, origin, source=str(path))


def occupancy(rgba: np.ndarray, mode: str, negate: bool, free: float, occupied: float,
              matte: bool = False) -> np.ndarray:
    """``loadMapFromFile``'s cell values (int8 [row = y up]) of an (H, W, 4) uint8 image
    (alpha 255 = opaque); ``matte``: the image file has an alpha channel."""
    rgb = rgba[..., :3].astype(np.float64)
    alpha = rgba[..., 3].astype(np.float64)
    if mode == "trinary" and matte:
        shade = (rgb.sum(axis=2) + alpha) / 4 / 255.0
    else:
        shade = rgb.sum(axis=2) / 3 / 255.0
    occ = shade if negate else 1.0 - shade
    if mode == "raw":
        pct = np.round(shade * 255)
        out = np.where((pct >= 0) & (pct <= 100), pct, UNKNOWN)
    else:
        scaled = np.rint((occ - free) / (occupied - free) * 100.0)
        middle = UNKNOWN if mode == "trinary" else scaled
        out = np.where(occupied < occ, OCCUPIED, np.where(occ < free, FREE, middle))
        if mode == "scale":
            out = np.where(alpha < 255, UNKNOWN, out)
    return np.ascontiguousarray(out.astype(np.int8)[::-1])      # image row 0 is the map's top


def save_map(grid: OccupancyMap, yaml_path: str | Path, free: float = FREE_THRESH,
             occupied: float = 0.65, mode: str = "trinary", negate: bool = False
             ) -> tuple[Path, Path]:
    """Write ``grid`` as YAML + image beside it (PGM; PNG with alpha in scale mode), pixels as
    ``tryWriteMapToFile`` writes them (``negate``: the same map with shades inverted, which
    Nav2 reads but never writes); FileExistsError, nothing written, if either file exists."""
    from PIL import Image

    from common.outfiles import check_output, output

    yaml_path = Path(yaml_path)
    image = yaml_path.with_suffix(".png" if mode == "scale" else ".pgm")
    for p in (yaml_path, image):
        if os.path.lexists(p):   # a dangling symlink too: never written through
            raise FileExistsError(f"{p} exists; choose another name (nothing is overwritten)")
        check_output(p)          # its directory exists and is writable (OutputError)
    pixels = _encode(grid.data, mode, free, occupied)
    if negate and mode != "raw":                              # raw ignores negate
        pixels[..., :3] = 255 - pixels[..., :3]
    pixels = pixels[::-1]                                       # row 0 is the map's top
    im = Image.fromarray(pixels, "RGBA") if mode == "scale" else Image.fromarray(pixels[..., 0])
    with output(image) as tmp:   # beside, then renamed (common/outfiles.py)
        im.save(tmp)
    x, y, yaw = grid.origin
    with output(yaml_path) as tmp:
        tmp.write_text(f"image: {image.name}\nmode: {mode}\nresolution: {grid.resolution!r}\n"
                       f"origin: [{x!r}, {y!r}, {yaw!r}]\nnegate: {int(negate)}\n"
                       f"occupied_thresh: {occupied!r}\nfree_thresh: {free!r}\n", encoding="utf-8")
    return yaml_path, image


def _encode(d: np.ndarray, mode: str, free: float, occupied: float) -> np.ndarray:
    """(H, W, 4) uint8 RGBA of cell values, per ``tryWriteMapToFile``'s switch on the mode."""
    known = (d >= 0) & (d <= 100)
    if mode == "trinary":
        gray = np.full(d.shape, 205, np.uint8)
        gray[known & (d <= round(free * 100))] = 254
        gray[known & (d >= round(occupied * 100))] = 0
    elif mode == "scale":
        gray = np.where(known, np.rint((100.0 - d) / 100.0 * 255), 128).astype(np.uint8)
    elif mode == "raw":
        gray = np.where(known, d, 255).astype(np.uint8)
    else:
        raise ValueError(f"mode {mode!r} is not one of {', '.join(MODES)}")
    alpha = np.where(known | (mode != "scale"), 255, 0).astype(np.uint8)
    return np.dstack([gray, gray, gray, alpha])


_MISSING = object()


def _fail(path: Path, key: str, problem: str):
    raise WorldError(f"map {str(path)!r}: {key}: {problem}")


def _read_yaml(path: Path) -> dict:
    import yaml

    try:
        if path.stat().st_size > MAX_YAML_BYTES:   # a map's YAML is a few lines
            raise WorldError(f"map {str(path)!r}: {path.stat().st_size:,} bytes; a map's YAML "
                             f"has at most {MAX_YAML_BYTES:,}")
        text = path.read_text(encoding="utf-8")
        meta = yaml.safe_load(text)
    except (OSError, UnicodeDecodeError) as exc:
        raise WorldError(f"cannot read map {str(path)!r}: {exc}") from None
    except RecursionError:   # thousands of nested brackets
        raise WorldError(f"map {str(path)!r}: nested too deeply to be a map's YAML") from None
    except yaml.YAMLError as exc:
        raise WorldError(f"map {str(path)!r} is not valid YAML: "
                         f"{yaml_problem(exc, text)}") from None
    if not isinstance(meta, dict):
        _fail(path, "(top)", "must be a mapping with image, resolution, origin, negate, "
              "occupied_thresh, free_thresh")
    return meta


def _number(path: Path, meta: dict, key: str, positive: bool = False) -> float:
    v = meta.get(key, _MISSING)
    if v is _MISSING:
        _fail(path, key, "is missing")
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        _fail(path, key, f"must be a finite number, got {v!r}")
    if positive and v <= 0:
        _fail(path, key, f"must be > 0, got {v!r}")
    return float(v)


def _image_path(path: Path, meta: dict) -> Path:
    image = meta.get("image")
    if not isinstance(image, str) or not image:
        _fail(path, "image", f"must name the map's image file, got {image!r}")
    image = Path(image) if image.startswith("/") else path.parent / image
    if not image.is_file():
        _fail(path, "image", f"{str(image)!r} does not exist")
    return image


def _pixels(path: Path, image: Path) -> tuple[np.ndarray, bool]:
    """(H, W, 4) uint8 RGBA of the image, and whether the file has an alpha channel."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(image) as im:
            if im.width * im.height > MAX_CELLS:
                _fail(path, "image", f"{im.width} x {im.height} cells is more than {MAX_CELLS:,}")
            if im.mode in ("I;16", "I;16B", "I"):   # 16-bit PGM: scale to 8 bits as Magick does
                arr = np.asarray(im, dtype=np.float64) / 257.0
                return np.dstack([np.round(arr).astype(np.uint8)] * 3
                                 + [np.full(arr.shape, 255, np.uint8)]), False
            matte = "A" in im.getbands() or "transparency" in im.info
            return np.asarray(im.convert("RGBA")), matte
    except (OSError, UnidentifiedImageError, Image.DecompressionBombError) as exc:
        _fail(path, "image", f"cannot read {str(image)!r}: {exc}")
