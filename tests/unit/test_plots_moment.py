"""The planner's-mind figure picks the moment the planner acted (papf/plots/moment.py)."""

from __future__ import annotations

import numpy as np

from papf.plots.moment import MomentPanel, moment_png, planner_events, telling_moment
from schemas.messages import PlannerState
from tests.support.messages import planner_debug
from worlds import load_world

S = 1_000_000_000


def _state(t_s: float, **kw) -> PlannerState:
    return PlannerState(stamp_ns=int(t_s * S), algorithm="papf", **kw)


STATES = [_state(0.0, temporary_goal=(1.0, 0.0)),            # set at start: not telling
          _state(1.0, temporary_goal=(1.02, 0.0)),           # moved 2 cm: not a move
          _state(2.0, temporary_goal=(1.5, 0.3)),            # moved
          _state(3.0, temporary_goal=(1.5, 0.3),                             # a quark placed
                 debug=planner_debug("papf", top_quarks=[(2.0, 0.5)])),
          _state(4.0, temporary_goal=(1.5, 0.3), debug=planner_debug("papf", top_quarks=[(2.0, 0.5)]))]


def test_events_are_what_the_planner_did():
    assert [(e.t_s, e.what) for e in planner_events(STATES)] == [
        (0.0, "temporary goal set"), (2.0, "temporary goal moved"), (3.0, "new top quark")]


def test_the_quark_beats_the_goal_move_and_nothing_before_motion_counts():
    assert telling_moment(STATES, t_moving_s=0.5).what == "new top quark"
    assert telling_moment(STATES[:3], t_moving_s=0.5).t_s == 2.0
    assert telling_moment(STATES[:2], t_moving_s=0.5) is None


def test_moment_png_draws_one_panel_per_run(tmp_path):
    t = np.linspace(0.0, 4.0, 41)
    xyyaw = np.column_stack([0.5 * t, np.zeros_like(t), np.zeros_like(t)])
    panel = MomentPanel("papf seed 0 (reached)", "papf", t, xyyaw, np.full_like(t, 0.5), STATES)
    out = moment_png([panel, panel], load_world("energy"), tmp_path / "mind.png")
    from PIL import Image

    with Image.open(out) as im:
        assert im.size[0] > 1000 and im.size[1] > 500


def test_a_road_panel_shows_its_lines_and_no_empty_half():
    """road-cut-in: the window holds the road's lines around the robot, not a square of
    empty floor below them (the before picture: 60 % empty)."""
    from papf.plots.moment import choose_view

    world = load_world("road-cut-in")
    t = np.linspace(0.0, 6.0, 61)
    xyyaw = np.column_stack([0.2 * t, np.zeros_like(t), np.zeros_like(t)])
    states = [_state(1.0, predicted_path=((0.2, 0.0), (1.5, 0.0), (2.4, 0.0)), v_target=0.2),
              _state(2.0, predicted_path=((0.4, 0.0), (1.5, 0.0), (2.4, 0.0)), v_target=0.02),
              _state(3.0, predicted_path=((0.6, 0.0), (1.5, 0.0), (2.4, 0.0)), v_target=0.2)]
    view = choose_view(MomentPanel("iapf", "iapf", t, xyyaw, np.full_like(t, 0.2), states), world)
    assert view.event is not None and view.event.t_s == 2.0 and "slowest" in view.event.what
    (_, my), (hx, hy) = view.mid, view.half
    lines = [line.y for line in world.road.lines()]
    assert all(my - hy < y < my + hy for y in lines)            # every line in the picture
    assert my - hy > min(lines) - 0.65 and hx > hy                # no band of floor below it


def test_animate_lays_a_long_world_across_the_frame(tmp_path):
    """energy (10 m x 2 m): the top view spans the frame, the legend has its own row, speed
    and charge sit side by side (beside the plots it was a thin strip in a white box)."""
    from papf.recording.track import load_track
    from papf.report.animation import Animator
    from tests.support.recordings import write_drive

    rec = tmp_path / "run.mcap"
    write_drive(rec, 50, {"world": "energy", "planner": "papf", "seed": 0})
    anim = Animator(load_track(rec), fps=10, speed=4)
    try:
        anim.fig.tight_layout(rect=(0, 0.02, 1, 0.95))
        top, v, q = (a.get_position() for a in (anim.ax, anim.ax_v, anim.ax_q))
        assert anim.legend_ax is not None and top.width > 0.8
        assert v.y1 < top.y0 and abs(v.y0 - q.y0) < 1e-6 and v.x1 < q.x0   # below, side by side
    finally:
        import matplotlib.pyplot as plt

        plt.close(anim.fig)
