"""The crowd pictures draw the people (papf/plots/crowd.py): walkers' tracks while in the
scene, standing people as filled discs, a group's space dashed; the experiment's two PNGs."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402

from papf.plots.crowd import draw_people, plot_crowd, plot_crowd_scenes, plot_crowd_summary  # noqa: E402
from worlds import load_world, parse_world  # noqa: E402


def test_standing_people_walkers_and_a_groups_space_are_drawn():
    w = load_world("crowd-standing")                     # 3 standing in a group, 1 alone
    people = np.repeat(np.array([[p.start for p in w.people]], float), 5, axis=0)
    fig, ax = plt.subplots()
    handles = draw_people(ax, w, people, np.full(4, 0.25))
    circles = [p for p in ax.patches if isinstance(p, Circle)]
    hulls = [p for p in ax.patches if isinstance(p, Polygon)]
    assert len(circles) == 4 and len(hulls) == 1 and hulls[0].get_linestyle() == "--"
    assert {h.get_label() for h in handles} == {"people walking", "standing", "group's space"}
    plt.close(fig)


def test_a_person_never_in_the_scene_is_not_drawn_and_a_walker_only_while_there():
    w = parse_world({"goal": {"position": [5.0, 0.0]}})
    people = np.array([[[0.0, 1.0], [9.0, 9.0]], [[1.0, 1.0], [9.0, 9.0]],
                       [[2.0, 1.0], [9.0, 9.0]]])
    shown = np.array([[0.25, 0.0], [0.25, 0.0], [0.0, 0.0]])
    fig, ax = plt.subplots()
    draw_people(ax, w, people, np.array([0.25, 0.25]), shown)
    (track, dot) = ax.lines
    assert list(track.get_xdata()) == [0.0, 1.0]         # the third sample: gone
    assert [tuple(c.center) for c in ax.patches] == [(1.0, 1.0)]
    plt.close(fig)


def test_the_plan_picture_and_the_experiments_pictures_are_written(tmp_path):
    w = load_world("crowd-standing")
    people = np.repeat(np.array([[p.start for p in w.people]], float), 3, axis=0)
    out = plot_crowd(w, {"papf": np.array([[0.0, 0.0], [8.0, 0.0]])}, people,
                     np.full(4, 0.25), tmp_path / "plan.png")
    assert out.stat().st_size > 10_000
    scenes = [{"world": w, "label": "groups", "paths": {"papf": [[0, 0], [8, 0]]},
               "people": people.tolist(), "shown": np.full((3, 4), 0.25).tolist()}]
    assert plot_crowd_scenes(scenes, tmp_path / "scenes.png").stat().st_size > 10_000
    summary = [{"planner": p, "scene": "groups", "reached": 50.0, "reached_lo": 20.0,
                "reached_hi": 80.0, "min_separation_m": 0.1, "min_separation_m_ci": 0.02,
                "personal_s": 3.0, "personal_s_ci": "", "group_intrusions": 0.0,
                "group_intrusions_ci": 0.0, "min_ttc_s": "", "min_ttc_s_ci": "",
                "people_time_ext_s": 0.5, "people_time_ext_s_ci": 0.4} for p in ("apf", "orca")]
    assert plot_crowd_summary(summary, tmp_path / "sum.png").stat().st_size > 10_000
