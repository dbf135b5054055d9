"""``papf animate FILE.mcap OUT.gif|OUT.mp4``: a recorded run as a moving picture.

Left: the top view — world, the path so far, the robot's footprint (a fleet's other robots
and the people too), and the planner's mind
of the latest cycle (prediction, abandoned predictions, top quarks, temporary goal, virtual
walls). Right: speed and charge over the run with a cursor at the frame's time. Title:
time, speed, charge. One frame every ``speed / fps`` seconds of sim time.

GIF through Pillow (always there with matplotlib); MP4 through ffmpeg where it is
installed (``matplotlib.animation.FFMpegWriter``) — else a ConfigError says so.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import animation  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Circle, Patch  # noqa: E402

from common.errors import ConfigError  # noqa: E402
from common.outfiles import check_output, output
from papf.console.progress import DecileProgress  # noqa: E402
from papf.plots.mind import (  # noqa: E402
    debug_handle,
    draw_footprint,
    draw_mind,
    draw_moving,
    draw_road,
    rgba,
)
from papf.plots.world import draw_world  # noqa: E402
from papf.recording.rosbag import TopicMap  # noqa: E402
from papf.recording.track import RunTrack, load_track  # noqa: E402

MAX_FRAMES = 1500
LIDAR_COLOUR = "tab:red"
OTHER_COLOUR = "0.45"         # a fleet's other robots
PERSON_COLOUR = "tab:purple"  # [[people]]
WIDE = 2.5                    # [-] a top view wider than this times its height: the wide layout


def _at(times: np.ndarray, t: float) -> int:
    """Index of the last sample at or before ``t`` (0 if none)."""
    return max(int(np.searchsorted(times, t, side="right")) - 1, 0)


def _value(times: np.ndarray, values: np.ndarray, t: float) -> float:
    return float(values[_at(times, t)]) if len(values) else float("nan")


class Animator:
    def __init__(self, track: RunTrack, fps: float, speed: float):
        self.track, self.step_s = track, speed / fps
        self.fig = plt.figure(figsize=(11.0, 5.6))
        grid = self.fig.add_gridspec(2, 2, width_ratios=(1.6, 1.0))
        self.ax = self.fig.add_subplot(grid[:, 0])
        self.ax_v = self.fig.add_subplot(grid[0, 1])
        self.ax_q = self.fig.add_subplot(grid[1, 1], sharex=self.ax_v)
        self.dynamic: list = []
        self.legend_ax = None      # the legend's own row (a long, flat world's layout)
        self._static()
        self._arrange()
        self._legend()

    def _arrange(self) -> None:
        """A long, flat world (wider than :data:`WIDE` times its height) gets the top view
        across the whole figure, the legend under it and the speed and charge side by side
        below: beside the plots it would be a thin strip in a white box."""
        (x0, x1), (y0, y1) = self.ax.get_xlim(), self.ax.get_ylim()
        if (x1 - x0) <= WIDE * (y1 - y0):
            return
        top = min(max(10.0 * (y1 - y0) / (x1 - x0), 1.6), 4.5)   # [in] the top view's height
        top += 0.6                                   # its x label and tick labels
        self.fig.set_size_inches(11.0, top + 0.45 + 2.4 + 0.5)   # + legend, plots, title
        grid = self.fig.add_gridspec(3, 2, height_ratios=(top, 0.45, 2.4))
        self.ax.set_subplotspec(grid[0, :])
        self.ax_v.set_subplotspec(grid[2, 0])
        self.ax_q.set_subplotspec(grid[2, 1])
        self.ax_v.set_xlabel("sim time [s]")
        self.legend_ax = self.fig.add_subplot(grid[1, :])
        self.legend_ax.axis("off")

    def _static(self) -> None:
        tr, ax = self.track, self.ax
        if tr.world is not None and tr.world.dims == 2:   # moving obstacles: in draw()
            draw_world(ax, replace(tr.world, obstacles=tuple(
                ob for ob in tr.world.obstacles if ob.motion is None)))
            draw_road(ax, tr.world)
        xy = tr.xyyaw[:, :2]
        ax.plot(xy[:, 0], xy[:, 1], color="0.8", lw=0.8, zorder=2)   # the whole path, faint
        lo, hi = xy.min(axis=0) - 0.6, xy.max(axis=0) + 0.6
        if tr.world is not None:
            ax.autoscale_view()
            (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
            lo, hi = np.minimum(lo, (x0, y0)), np.maximum(hi, (x1, y1))
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        self.ax_v.plot(tr.v_t, tr.v, color="tab:blue", lw=1.0)
        self.ax_v.set_ylabel("speed [m/s]")
        self.ax_q.plot(tr.q_t, tr.q, color="tab:green", lw=1.2)
        self.ax_q.set_ylabel("charge used [mAh]")
        self.ax_q.set_xlabel("sim time [s]")
        for a in (self.ax_v, self.ax_q):
            a.grid(True, lw=0.3, alpha=0.5)

    def frames(self) -> np.ndarray:
        t0, t1 = float(self.track.t[0]), float(self.track.t[-1])
        n = int((t1 - t0) / self.step_s) + 1
        if n > MAX_FRAMES:
            raise ConfigError(f"{n} frames at --speed/--fps = {self.step_s:g} s per frame; at "
                              f"most {MAX_FRAMES}: raise --speed")
        times = t0 + self.step_s * np.arange(n)
        return times if times[-1] >= t1 - 1e-9 else np.append(times, t1)   # end on the last pose

    def _lidar(self, t: float) -> list:
        """The latest scan at or before ``t``, as points in the world from the pose then."""
        tr = self.track
        if not tr.scans or tr.scan_t[0] > t + 1e-9:
            return []
        pts = tr.scans[_at(tr.scan_t, t)]
        x, y, yaw = tr.xyyaw[_at(tr.t, float(tr.scan_t[_at(tr.scan_t, t)]))]
        ang = yaw + pts[:, 0]
        return [self.ax.scatter(x + pts[:, 1] * np.cos(ang), y + pts[:, 1] * np.sin(ang),
                                s=3, color=LIDAR_COLOUR, lw=0, zorder=4)]

    def _fleet(self, t: float) -> list:
        """A fleet's other robots (their paths so far, their chassis) and the people at ``t``."""
        tr, ax, out = self.track, self.ax, []
        for name, (times, xyyaw) in tr.others.items():
            if not len(times) or times[0] > t + 1e-9:
                continue
            k = _at(times, t)
            out += ax.plot(xyyaw[: k + 1, 0], xyyaw[: k + 1, 1], color=OTHER_COLOUR, lw=1.0,
                           zorder=3)
            out += draw_footprint(ax, *xyyaw[k], filled=False)
            out.append(ax.annotate(name, xyyaw[k, :2], fontsize=7, zorder=7,
                                   xytext=(4, 4), textcoords="offset points"))
        if len(tr.people_t) and tr.people_t[0] <= t + 1e-9:
            k = _at(tr.people_t, t)
            radii = tr.people_radii[k] if len(tr.people_radii) > k else tr.people_r
            for (x, y), r in zip(tr.people_xy[k], radii, strict=True):
                if not r > 0:     # a replayed person not in the scene then
                    continue
                out.append(ax.add_patch(Circle((x, y), r, color=PERSON_COLOUR, alpha=0.6,
                                               zorder=5)))
        return out

    def _debug_handles(self) -> list:
        """Legend entries of the planner's own debug values (one per field it declared)."""
        seen = {d.name: d for s in self.track.states for d in s.debug}
        return [h for h in map(debug_handle, seen.values()) if h is not None]

    def _legend(self) -> None:
        """What the top view's marks are (static: the frames' artists come and go)."""
        handles = [Line2D([], [], color=rgba("robot", 1.0), lw=1.6, label="path so far"),
                   Patch(facecolor=rgba("robot"), edgecolor=rgba("robot", 1.0), label="robot"),
                   Line2D([], [], marker="o", ls="", ms=3, color=LIDAR_COLOUR,
                          label="LiDAR points"),
                   Line2D([], [], color=rgba("prediction"), lw=2.0, label="prediction"),
                   *self._debug_handles(),
                   Line2D([], [], marker="D", ls="", color=rgba("temporary_goal"), mec="k",
                          label="temporary goal")]
        if self.track.others:
            handles.append(Line2D([], [], color=OTHER_COLOUR, lw=1.0, label="other robots"))
        if len(self.track.people_t):
            handles.append(Patch(color=PERSON_COLOUR, alpha=0.6, label="people"))
        if self.track.world is not None and any(
                ob.motion is not None for ob in self.track.world.obstacles):
            handles.append(Patch(color=rgba("moving"), label="moving obstacle"))
        if self.legend_ax is not None:
            self.legend_ax.legend(handles=handles, loc="center", ncol=min(len(handles), 8),
                                  fontsize=8, frameon=False)
            return
        self.ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.34), ncol=4,
                       fontsize=7, frameon=False)

    def draw(self, t: float) -> list:
        for artist in self.dynamic:
            artist.remove()
        tr, ax = self.track, self.ax
        k = _at(tr.t, t)
        out = ax.plot(tr.xyyaw[: k + 1, 0], tr.xyyaw[: k + 1, 1], color=rgba("robot", 1.0),
                      lw=1.6, zorder=3)
        if len(tr.states):
            s = tr.states[_at(tr.state_t, t)]
            if s.stamp_ns / 1e9 <= t + 1e-9:
                out += draw_mind(ax, s, labels=False)
        out += self._lidar(t)
        out += draw_footprint(ax, *tr.xyyaw[k])
        out += self._fleet(t)
        if tr.world is not None and tr.world.dims == 2:
            out += draw_moving(ax, tr.world, t)
        v, q = _value(tr.v_t, tr.v, t), _value(tr.q_t, tr.q, t)
        out += [self.ax_v.axvline(t, color="k", lw=0.8), self.ax_q.axvline(t, color="k", lw=0.8)]
        charge = f"{q:5.2f} mAh" if q == q else "n/a"   # nan: no battery recorded
        out.append(self.fig.suptitle(f"{tr.title}    t = {t:6.1f} s    v = {v:4.2f} m/s    "
                                     f"charge = {charge}", fontsize=11))
        self.dynamic = out
        return out


def animate(src: str | Path, out: str | Path, fps: float = 10.0, speed: float = 4.0,
            world: str | None = None, dpi: int = 110, force: bool = False,
            topics: TopicMap | None = None) -> int:
    """Render ``src`` (a recording or a rosbag2, its topics mapped by ``topics``) into ``out``
    (.gif or .mp4; :func:`common.outfiles.output`: an existing ``out`` only with ``force``,
    never ``src`` itself); returns the number of frames."""
    out = Path(out)
    suffix = out.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ConfigError(f"{out}: the output must be a .gif or an .mp4")
    if suffix == ".mp4" and not animation.writers.is_available("ffmpeg"):
        raise ConfigError("an .mp4 needs ffmpeg on PATH (e.g. apt-get install ffmpeg); "
                          "write a .gif instead")
    if not (fps > 0 and speed > 0):
        raise ConfigError(f"--fps {fps} and --speed {speed} must be > 0")
    check_output(out, [src], force)   # before reading the recording
    anim = Animator(load_track(src, world, topics), fps, speed)
    try:
        frames = anim.frames()
        writer = (animation.PillowWriter(fps=fps) if suffix == ".gif"
                  else animation.FFMpegWriter(fps=fps))
        anim.fig.tight_layout(rect=(0, 0.02, 1, 0.95))
        with output(out, [src], force) as tmp, writer.saving(anim.fig, str(tmp), dpi), \
                DecileProgress(f"animate {out.name}") as bar:
            for k, t in enumerate(frames, 1):
                anim.draw(float(t))
                writer.grab_frame()
                bar.fraction(k / len(frames), f"frame {k}/{len(frames)}  t = {t:.1f} s")
    finally:
        plt.close(anim.fig)
    return len(frames)
