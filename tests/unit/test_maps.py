"""ROS maps as worlds (worlds/maps.py, worlds/kinds/grid.py): Nav2 map_server's reading
rules pixel by pixel, the map's frame (y-flip, origin, yaw), rays and bodies against the
grid, export -> load round trip, bad maps refused in one line before anything starts."""

import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import worlds
from common.errors import WorldError
from common.quiet import import_quietly
from papf.cli import main
from papf.offline import map_gen
from tests.support.cli import papf
from worlds import load_world
from worlds.bullet import build_world
from worlds.geometry import cast_rays, signed_distance
from worlds.kinds.grid import wall_boxes
from worlds.map_world import map_world_file, rasterize
from worlds.maps import OCCUPIED, UNKNOWN, OccupancyMap, load_map, occupancy, save_map

p = import_quietly("pybullet")
META = "resolution: 0.1\norigin: [0.0, 0.0, 0.0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"


def write_yaml(tmp_path, image="m.pgm", extra="negate: 0\n", meta=META, name="m.yaml"):
    path = tmp_path / name
    path.write_text(f"image: {image}\n{meta}{extra}")
    return path


def gray(value):
    return np.dstack([np.full((1, 1), value, np.uint8)] * 3 + [np.full((1, 1), 255, np.uint8)])


@pytest.mark.parametrize(("value", "negate", "want"), [
    (0, False, OCCUPIED), (254, False, 0), (205, False, UNKNOWN),   # map_saver's trinary shades
    (0, True, 0), (255, True, OCCUPIED), (128, True, UNKNOWN),
    (89, False, OCCUPIED),     # occ = 1 - 89/255 = 0.651 > 0.65
    (90, False, UNKNOWN),      # occ = 0.647: not above occupied_thresh
    (206, False, 0),           # occ = 0.192 < 0.196
])
def test_trinary_thresholds_as_map_io(value, negate, want):
    assert occupancy(gray(value), "trinary", negate, 0.196, 0.65)[0, 0] == want


def test_scale_mode_scales_the_middle_and_alpha_is_unknown():
    px = np.array([[[128, 128, 128, 255], [0, 0, 0, 0], [255, 255, 255, 255]]], np.uint8)
    cells = occupancy(px, "scale", False, 0.25, 0.65)[0]
    occ = 1 - 128 / 255
    assert cells.tolist() == [round((occ - 0.25) / 0.4 * 100), UNKNOWN, 0]


def test_raw_mode_is_the_pixel_value_and_ignores_thresholds():
    px = np.array([[[0] * 3 + [255], [42] * 3 + [255], [100] * 3 + [255], [101] * 3 + [255]]],
                  np.uint8)
    assert occupancy(px, "raw", False, 0.25, 0.65)[0].tolist() == [0, 42, 100, UNKNOWN]


def test_trinary_averages_opacity_in_when_the_image_has_alpha():
    """map_io.cpp: with a matte image, trinary averages (MaxRGB - alpha) — the opacity — in."""
    px = np.array([[[0, 0, 0, 0]]], np.uint8)            # black, fully transparent
    assert occupancy(px, "trinary", False, 0.196, 0.65, matte=True)[0, 0] == OCCUPIED
    half = np.array([[[100, 100, 100, 0]]], np.uint8)     # shade (300 + 0) / 4 / 255 = 0.29
    assert occupancy(half, "trinary", False, 0.196, 0.65, matte=True)[0, 0] == OCCUPIED
    assert occupancy(half, "trinary", False, 0.196, 0.65, matte=False)[0, 0] == UNKNOWN


def test_image_row_zero_is_the_top_and_origin_places_cell_zero(tmp_path):
    img = np.full((4, 6), 254, np.uint8)
    img[0, 5] = 0                                          # top-right pixel
    Image.fromarray(img).save(tmp_path / "m.pgm")
    m = load_map(write_yaml(tmp_path, meta=META.replace("[0.0, 0.0, 0.0]", "[-1.0, 2.0, 0.0]")))
    assert m.walls.shape == (4, 6) and m.walls[3, 5] and m.walls.sum() == 1
    assert m.to_world(np.array([[5.5, 3.5]]))[0].tolist() == pytest.approx([-0.45, 2.35])


@pytest.mark.parametrize("mode", ["trinary", "scale", "raw"])
@pytest.mark.parametrize("negate", [False, True])
def test_written_maps_read_back_the_same_walls(tmp_path, mode, negate):
    data = map_gen.rooms(0.1)
    saved, _ = save_map(OccupancyMap(data, 0.1, (1.0, -2.0, 0.3)), tmp_path / "r.yaml",
                        mode=mode, negate=negate)
    back = load_map(saved)
    assert back.origin == (1.0, -2.0, 0.3) and back.resolution == 0.1
    assert np.array_equal(back.walls, OccupancyMap(data, 0.1, (0, 0, 0)).walls)


@pytest.mark.parametrize(("make", "cell"), [(map_gen.corridor, (30.0, 12.0)),
                                            (map_gen.warehouse, (105.0, 40.0))])
def test_yawed_map_rays_and_pybullet_agree(tmp_path, make, cell):
    """A map turned by its origin's yaw: rays and the pybullet meshes see the same walls
    (the warehouse: hundreds of rectangles, more than one pybullet compound could hold)."""
    data = make(0.1)
    saved, _ = save_map(OccupancyMap(data, 0.1, (2.0, 1.0, 0.5)), tmp_path / "c.yaml")
    (tmp_path / "w.toml").write_text('[goal]\nposition = [5.0, 5.0]\n[map]\nfile = "c.yaml"\n')
    world = load_world(tmp_path / "w.toml")
    grid = world.obstacles[0].grid
    assert not grid.walls[int(cell[1]), int(cell[0])]
    x, y = grid.to_world(np.array([cell]))[0]
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    exact = cast_rays(world, x, y, angles, range_max=8.0)
    cid = p.connect(p.DIRECT)
    try:
        build_world(cid, world)
        ends = [(x + 8 * math.cos(a), y + 8 * math.sin(a), 0.2) for a in angles]
        hits = p.rayTestBatch([(x, y, 0.2)] * len(ends), ends, physicsClientId=cid)
    finally:
        p.disconnect(cid)
    seen = np.array([h[2] * 8 if h[0] >= 0 else np.inf for h in hits])
    assert np.isfinite(exact).mean() > 0.5
    hit = np.isfinite(exact)
    assert np.array_equal(hit, np.isfinite(seen))
    assert np.abs(exact[hit] - seen[hit]).max() < 0.01
    pts = np.column_stack([x + exact[hit] * np.cos(angles[hit]), y + exact[hit] * np.sin(angles[hit])])
    assert np.abs(signed_distance(world, pts)).max() <= 0.1 * math.sqrt(0.5) + 1e-9


def test_merged_rectangles_cover_each_wall_cell_once():
    grid = OccupancyMap(map_gen.warehouse(0.1), 0.1, (0.0, 0.0, 0.0))
    cover = np.zeros(grid.shape, int)
    for u, v, w, h in wall_boxes(grid):
        c0, r0 = round((u - w / 2) / 0.1), round((v - h / 2) / 0.1)
        cover[r0:r0 + round(h / 0.1), c0:c0 + round(w / 0.1)] += 1
    assert np.array_equal(cover, grid.walls.astype(int))
    assert len(wall_boxes(grid)) < grid.walls.sum() / 10


def test_export_then_load_is_the_same_world(tmp_path):
    world = load_world("energy")
    saved, pgm = save_map(rasterize(world, 0.05), tmp_path / "e.yaml")
    (tmp_path / "w.toml").write_text('[goal]\nposition = [10.0, 0.0]\n[map]\nfile = "e.yaml"\n')
    back = load_world(tmp_path / "w.toml")
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    a, b = (cast_rays(w, 0.0, 0.0, angles, 12.0) for w in (world, back))
    hit = np.isfinite(a)
    assert hit.sum() > 15 and (b[hit] <= a[hit] + 0.08).all()   # every obstacle is in the map
    close = np.where(hit, np.abs(a - np.where(np.isfinite(b), b, -1.0)) < 0.08, ~np.isfinite(b))
    assert close.mean() > 0.97               # and little more: grazing rays may hit a cell
    with pytest.raises(FileExistsError):
        save_map(rasterize(world, 0.05), saved)


def test_export_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "e.yaml"
    assert main(["export", "map", "energy", str(out)]) == 0
    before = out.read_bytes()
    assert main(["export", "map", "energy", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "exists" in err[0] and out.read_bytes() == before


@pytest.mark.parametrize(("meta", "extra", "says"), [
    (META, "negate: 0\n", "does not exist"),                                     # no image file
    (META.replace("free_thresh: 0.196", "free_thresh: 0.8"), "negate: 0\n", "free_thresh"),
    (META.replace("resolution: 0.1", "resolution: .nan"), "negate: 0\n", "resolution"),
    (META.replace("[0.0, 0.0, 0.0]", "[0.0, 0.0]"), "negate: 0\n", "origin"),
    (META, "", "negate"),
    (META, "negate: 0\nmode: fancy\n", "mode"),
])
def test_bad_map_yaml_is_one_line_exit_2_before_any_process(tmp_path, capsys, meta, extra, says):
    if says != "does not exist":
        Image.fromarray(np.full((4, 4), 254, np.uint8)).save(tmp_path / "m.pgm")
    path = write_yaml(tmp_path, meta=meta, extra=extra)
    with pytest.raises(WorldError, match=says):
        load_map(path)
    assert main(["run", "--world", str(path), "--start=0.5,0.5", "--goal=1,1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and says in err[0]


def test_start_and_goal_go_with_a_map(tmp_path, capsys):
    Image.fromarray(np.full((40, 40), 254, np.uint8)).save(tmp_path / "m.pgm")
    path = write_yaml(tmp_path)
    assert main(["plan", "--world", str(path), "--goal=1,1"]) == 2
    assert main(["plan", "--world", "energy", "--start=0,0", "--goal=1,1"]) == 2
    assert main(["plan", "--world", str(path), "--start=0.5,x", "--goal=1,1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and "--start" in err[0] and "--start=" in err[2]
    world = load_world(map_world_file(str(path), "-0.5,0.5,1.0", "3,3"))
    assert world.start == (-0.5, 0.5, 1.0) and world.goal == (3.0, 3.0)
    assert not any(tmp_path.glob("*.toml"))                    # nothing written beside the map


def test_papf_reaches_a_goal_through_a_door_offline(tmp_path):
    """The offline closed loop (LiDAR and footprint in pybullet) on a map made here."""
    from papf.offline.run import simulate

    save_map(OccupancyMap(map_gen.rooms(0.05), 0.05, (0.0, 0.0, 0.0)), tmp_path / "r.yaml",
             mode="scale", negate=True)
    world = load_world(map_world_file(str(tmp_path / "r.yaml"),
                                      "2.5,2.0", "6.5,3.5"))
    result = simulate(world, "papf", seed=1, max_time_s=120)
    assert (result.outcome, result.collisions) == ("reached", 0), result.reason


@pytest.mark.parametrize("name", ["map-rooms", "map-corridor", "map-warehouse", "map-campus"])
def test_papf_reaches_every_packaged_map_world_offline(name):
    """Each packaged map world, by name, as a user runs it (the campus is a million cells)."""
    from papf.offline.run import simulate

    result = simulate(load_world(name), "papf", seed=0, max_time_s=900)
    assert (result.outcome, result.collisions) == ("reached", 0), result.reason


def test_packaged_maps_are_what_map_gen_draws():
    """worlds/maps/*.pgm are map_gen's drawings at their resolutions (re-drawn, not edited)."""
    folder = Path(worlds.__file__).parent / "maps"
    for name, draw in (("rooms", map_gen.rooms), ("corridor", map_gen.corridor),
                       ("warehouse", map_gen.warehouse), ("campus", map_gen.campus)):
        grid = load_map(folder / f"{name}.yaml")
        assert np.array_equal(grid.data, draw(grid.resolution)), name


def test_export_map_never_writes_through_a_dangling_link_and_checks_its_directory(tmp_path, capsys):
    from papf.cli import main

    target = tmp_path / "target.pgm"
    (tmp_path / "m.pgm").symlink_to(target)
    assert main(["export", "map", "energy", str(tmp_path / "m.yaml")]) == 2
    assert not target.exists() and "exists" in capsys.readouterr().err
    assert main(["export", "map", "energy", str(tmp_path / "no" / "m.yaml")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_a_broken_map_yaml_names_line_and_column(tmp_path):
    bad = tmp_path / "map.yaml"
    bad.write_text("image: x.pgm\nresolution: [0.05\norigin: [0, 0, 0]\n")
    res = papf("plan", "--world", str(bad), "--start", "0,0", "--goal", "1,1")
    assert res.returncode == 2
    assert ("is not valid YAML: line 3, column 7: expected ',' or ']', but got ':' (while "
            "parsing a flow sequence started at line 2, column 13)") in res.stderr
