"""Obstacle tracker: LiDAR scan + pose -> tracked objects (pure core; no zenoh).

:class:`Tracker` clusters each scan (Borges & Aldon's adaptive breakpoints), associates
clusters with tracks (Hungarian method), measures them as boxes (:mod:`nodes.tracker.box`)
and filters them (constant-velocity Kalman). Used by the tracker node's loop
(:mod:`nodes.tracker.loop`) and ``papf bench tracker``; the why: nodes/tracker/README.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from common.errors import ConfigError
from common.units import NS_PER_S
from nodes.tracker import box, kernels
from schemas.messages import Objects, ObjectTrack, Odometry, Scan

GATED_COST = 1e6   # assignment cost of a pair beyond the gate (rejected afterwards)
DISC_SIZE_GAIN = 0.2   # [-] weight of a new diameter in a disc track's size
DISC_HITS = 2          # [-] arcs matched before a track is a disc for good


@dataclass(frozen=True)
class TrackerParams:
    """Clustering, association and filter settings (units in comments)."""

    max_range: float = 6.0         # [m] points farther from the sensor are ignored
    cluster_radius: float = 0.15   # [m] successive returns closer than this are one object
    breakpoint_angle: float = math.radians(30.0)   # [rad] lambda of the adaptive breakpoint
    range_sd: float = 0.01         # [m] range noise of the LiDAR (the sim's default)
    max_beam_gap: int = 2          # [-] beams without a return that still join two returns
    min_points: int = 3            # [-] smaller clusters are noise
    max_extent: float = 2.0        # [m] longer clusters are structure (walls), not objects
    gate: float = 0.5              # [m] max distance of a cluster to a predicted track
    accel_sd: float = 0.5          # [m/s^2] white-noise acceleration of the CV model (road cars)
    meas_sd: float = 0.05          # [m] position measurement noise of a cluster centre
    init_speed_sd: float = 1.0     # [m/s] velocity uncertainty of a new track
    confirm_hits: int = 3          # [-] hits before a track is published
    max_misses: int = 5            # [-] scans without a hit before a track is dropped
    moving_speed: float = 0.05     # [m/s] slower tracks keep their heading
    disc_max_radius: float = 0.6   # [m] arcs up to this radius are discs (people), not boxes
    disc_max_rms: float = 0.025    # [m] largest RMS miss of an arc's points to its circle
    use_numba: bool = True         # the compiled clustering pass when numba is installed

    def __post_init__(self) -> None:
        for name in ("max_range", "cluster_radius", "breakpoint_angle", "range_sd", "max_extent", "gate", "accel_sd", "meas_sd",
                     "init_speed_sd", "moving_speed", "disc_max_radius", "disc_max_rms"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ConfigError(f"tracker {name} = {value!r} must be a finite number > 0")
        for name in ("min_points", "confirm_hits", "max_misses", "max_beam_gap"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise ConfigError(f"tracker {name} = {value!r} must be an integer >= 1")


@dataclass(frozen=True)
class Cluster:
    """One cluster's measurement: centre [m], principal-axis angle [rad], extents [m]."""

    x: float
    y: float
    axis: float
    length: float   # along ``axis``
    width: float    # across it
    points: np.ndarray | None = field(default=None, compare=False, repr=False)   # (m, 2) [m]
    disc: bool = False   # an arc measured as a circle (box.disc): centre and diameter


@dataclass(frozen=True)
class ScanPoints:
    """The valid returns of one scan: world-frame points, their ranges and beam indices."""

    xy: np.ndarray        # (K, 2) [m]
    ranges: np.ndarray    # (K,) [m]
    beams: np.ndarray     # (K,) beam index, increasing
    beam_count: int       # beams per revolution
    increment: float      # [rad] angle between successive beams
    origin: tuple[float, float] = (0.0, 0.0)   # [m] the sensor, world frame


def scan_points(scan: Scan, odom: Odometry, max_range: float) -> ScanPoints:
    """The valid beams within ``max_range`` [m] of the sensor, in world coordinates."""
    ranges = np.asarray(scan.ranges, dtype=float)
    # comparisons with nan are False (no warning): nan and inf drop out here
    ok = (ranges >= scan.range_min) & (ranges <= min(scan.range_max, max_range))
    c, s = math.cos(odom.yaw), math.sin(odom.yaw)
    ox = odom.x + c * scan.sensor_x - s * scan.sensor_y
    oy = odom.y + s * scan.sensor_x + c * scan.sensor_y
    beams = np.flatnonzero(ok)
    a = odom.yaw + scan.sensor_yaw + scan.angle_min + scan.angle_increment * beams
    r = ranges[beams]
    xy = np.empty((len(beams), 2))
    xy[:, 0] = ox + r * np.cos(a)
    xy[:, 1] = oy + r * np.sin(a)
    return ScanPoints(xy, r, beams, len(ranges), abs(scan.angle_increment), (ox, oy))


def _breaks(sp: ScanPoints, p: TrackerParams) -> tuple[np.ndarray, np.ndarray]:
    """(order, starts): the points rotated so that no segment crosses the array's end, and
    the index in ``order`` where each segment starts (:class:`Tracker`, step 2)."""
    n = len(sp.beams)
    nxt = np.arange(1, n + 1)
    nxt[-1] = 0                                           # the seam: last point -> first
    gap = (sp.beams[nxt] - sp.beams) % sp.beam_count      # beams between successive returns
    gap[gap == 0] = sp.beam_count                         # a single return
    dphi = gap * sp.increment
    lam = p.breakpoint_angle
    joinable = (dphi < lam) & (gap <= p.max_beam_gap + 1)
    limit = np.zeros(n)
    adaptive = sp.ranges[joinable] * np.sin(dphi[joinable]) / np.sin(lam - dphi[joinable])
    limit[joinable] = np.maximum(p.cluster_radius, adaptive + 3 * p.range_sd)
    d = sp.xy[nxt] - sp.xy
    cut = np.flatnonzero(d[:, 0] ** 2 + d[:, 1] ** 2 > limit ** 2)   # a break after point i
    if len(cut) == 0:
        return np.arange(n), np.zeros(1, dtype=int)
    first = (cut[-1] + 1) % n                             # start after the last break
    order = (np.arange(n) + first) % n
    return order, np.sort((cut + 1 - first) % n)


def segments(sp: ScanPoints, p: TrackerParams) -> list[np.ndarray]:
    """Index arrays (into ``sp.xy``) of the scan-order segments (:class:`Tracker`, step 2)."""
    if len(sp.beams) == 0:
        return []
    order, starts = _breaks(sp, p)
    return np.split(order, starts[1:])


def cluster_points(sp: ScanPoints, p: TrackerParams) -> list[Cluster]:
    """Object-sized clusters of a scan (:class:`Tracker`, step 2), in scan order.

    With numba (and ``use_numba``) one compiled pass (:mod:`nodes.tracker.kernels`),
    else :func:`_breaks` and :func:`_measure` for all segments at once in numpy.
    """
    n = len(sp.beams)
    if n < p.min_points:
        return []
    if p.use_numba and kernels.HAVE_NUMBA:
        boxes, counts, first = kernels.segment_boxes(
            sp.xy, sp.ranges, sp.beams.astype(np.int64), sp.beam_count, sp.increment,
            p.cluster_radius, p.breakpoint_angle, p.range_sd, p.max_beam_gap)
        order = (np.arange(n) + first) % n
    else:
        order, starts = _breaks(sp, p)
        counts = np.diff(starts, append=n)
        boxes = _measure(sp.xy[order], starts, counts)
    ends = np.cumsum(counts).tolist()
    return [Cluster(*box, points=sp.xy[order[end - count:end]])
            for box, count, end in zip(boxes.tolist(), counts.tolist(), ends, strict=True)
            if count >= p.min_points and box[3] <= p.max_extent]


def _measure(xy: np.ndarray, starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Per segment (``xy[starts[i]:starts[i] + counts[i]]``): the bounding box of its points
    in their principal axes (the eigenvectors of the covariance) as rows
    ``(x, y, axis, length, width)`` — centre [m], major-axis angle [rad], extents [m]."""
    mean = np.add.reduceat(xy, starts) / counts[:, None]
    d = xy - np.repeat(mean, counts, axis=0)
    sxx = np.add.reduceat(d[:, 0] * d[:, 0], starts)
    syy = np.add.reduceat(d[:, 1] * d[:, 1], starts)
    sxy = np.add.reduceat(d[:, 0] * d[:, 1], starts)
    axis = 0.5 * np.arctan2(2 * sxy, sxx - syy)
    c, s = np.cos(axis), np.sin(axis)
    cp, sp_ = np.repeat(c, counts), np.repeat(s, counts)
    u = d[:, 0] * cp + d[:, 1] * sp_
    v = d[:, 1] * cp - d[:, 0] * sp_
    umax, umin = np.maximum.reduceat(u, starts), np.minimum.reduceat(u, starts)
    vmax, vmin = np.maximum.reduceat(v, starts), np.minimum.reduceat(v, starts)
    cu, cv = (umax + umin) / 2, (vmax + vmin) / 2
    return np.column_stack([mean[:, 0] + c * cu - s * cv, mean[:, 1] + s * cu + c * cv, axis,
                            umax - umin, vmax - vmin])


@dataclass
class _Tracks:
    """All live tracks as arrays (row i = track i)."""

    ids: list[int] = field(default_factory=list)
    x: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))        # x, y, vx, vy
    P: np.ndarray = field(default_factory=lambda: np.zeros((0, 4, 4)))     # covariances
    hits: list[int] = field(default_factory=list)
    misses: list[int] = field(default_factory=list)
    yaw: list[float] = field(default_factory=list)
    size: list[tuple[float, float]] = field(default_factory=list)          # length, width
    discs: list[int] = field(default_factory=list)    # arcs matched (measured as discs)

    def keep(self, mask: np.ndarray) -> None:
        self.x, self.P = self.x[mask], self.P[mask]
        for name in ("ids", "hits", "misses", "yaw", "size", "discs"):
            setattr(self, name, [v for v, k in zip(getattr(self, name), mask, strict=True) if k])


class Tracker:
    """Multi-object tracker over successive scans.

    One cycle (:meth:`Tracker.update`) per scan, everything in the world frame:

    1. **Points**: valid beams within ``max_range`` of the sensor, to world coordinates
       with the robot pose and the sensor offset.
    2. **Clusters**: breakpoint segmentation in scan order, the standard for 2-D LiDARs:
       two successive returns belong to one object when they are closer than
       ``max(cluster_radius, D_max)``, ``D_max = r sin(dphi) / sin(lambda - dphi) + 3 sigma_r``
       (the adaptive breakpoint detector of Borges & Aldon, J. Intell. Robot. Syst. 39,
       2004: ``dphi`` the angle between the two beams, ``lambda`` = ``breakpoint_angle``,
       sigma_r = ``range_sd``; far returns are sparse, so the allowance grows with the range);
       returns with more than ``max_beam_gap`` beams between them that saw nothing, or
       more than ``lambda`` apart in angle, never join (the rays between passed through free
       space). The first and last segment join across the scan's seam.
       Clusters with fewer than ``min_points`` points are noise; clusters longer than
       ``max_extent`` are walls or other structure, not objects (the planner still sees them
       in the scan). Why not a library clustering (scipy ``cKDTree`` + ``connected_components``,
       scikit-learn DBSCAN): on a scan the neighbours are already ordered, and the sparse-graph
       set-up took most of the cycle in our first version (nodes/tracker/README.md).
       A cluster's box: its bounding box in its principal axes (the visible part).
    3. **Association**: predicted tracks vs cluster boxes by centre distance, globally optimal
       (``scipy.optimize.linear_sum_assignment``, the Hungarian method), pairs farther than
       ``gate`` rejected.
    4. **Box model** (:mod:`nodes.tracker.box`): a matched cluster is measured in its track's
       frame, as the centre of a box of the track's size whose faces nearest the sensor lie on
       the seen points (a car seen from behind is measured at its centre once its length has
       been seen, not at its rear face). A cluster on a circle (a person, a cylinder:
       :func:`nodes.tracker.box.disc`) is measured as the circle's centre and diameter.
    5. **Filter**: a constant-velocity Kalman filter per track (state x, y, vx, vy;
       white-noise acceleration of ``accel_sd``; position measurements of ``meas_sd``),
       vectorised over all tracks with numpy. Unmatched clusters start tracks (velocity 0,
       ``init_speed_sd``); a track is published after ``confirm_hits`` hits and dropped
       after ``max_misses`` scans without one.

    Heading: the direction of the filtered velocity when its speed exceeds ``moving_speed``
    and twice the filter's own velocity standard deviation along it, else the last one (a new
    track: the cluster's principal axis) — a standing car's velocity is noise, and its
    direction would turn the box at random. Size: the largest extents seen along / across the
    heading (a rigid object only shows more of itself over time), swapped when the heading
    turns by more than 45 degrees.

    Deterministic: the output depends only on the inputs, in order.
    """

    def __init__(self, params: TrackerParams | None = None):
        self.params = params or TrackerParams()
        self.tracks = _Tracks()
        self.t_ns: int | None = None
        self._next_id = 1
        self._model: tuple | None = None     # (dt, F, F^T, Q) of the last prediction

    def warm_up(self) -> None:
        """Compile the numba kernel (a few seconds, once per machine with its cache) now
        rather than in the first cycle; the tracker's state is untouched."""
        if self.params.use_numba and kernels.HAVE_NUMBA:
            xy = np.array([[1.0, 0.0], [1.0, 0.01], [1.0, 0.02]])
            sp = ScanPoints(xy, np.ones(3), np.arange(3), 360, math.radians(1.0))
            cluster_points(sp, self.params)
            box.fit(xy, 0.0, (0.1, 0.1), (0.0, 0.0))

    def update(self, scan: Scan, odom: Odometry) -> Objects:
        """One cycle on ``scan`` taken at pose ``odom``; the confirmed tracks, scan-stamped."""
        p = self.params
        t = scan.stamp_ns
        if self.t_ns is not None and t < self.t_ns:        # time went back: a new run
            self.tracks, self._next_id = _Tracks(), 1
        dt = 0.0 if self.t_ns is None else (t - self.t_ns) / NS_PER_S
        self.t_ns = t
        sp = scan_points(scan, odom, p.max_range)
        clusters = [self._disc(c, sp.origin) for c in cluster_points(sp, p)]
        self._predict(dt)
        rows, cols = self._associate(clusters)
        self._correct(rows, [self._box(i, clusters[j], sp.origin)
                             for i, j in zip(rows, cols, strict=True)])
        self._age(rows)
        for j in sorted(set(range(len(clusters))) - set(cols)):
            self._start(clusters[j])
        return self.objects(t)

    def objects(self, stamp_ns: int) -> Objects:
        """The confirmed tracks as an ``Objects`` message."""
        tr, p = self.tracks, self.params
        out = [ObjectTrack(id=tr.ids[i], x=float(tr.x[i, 0]), y=float(tr.x[i, 1]), yaw=tr.yaw[i],
                           vx=float(tr.x[i, 2]), vy=float(tr.x[i, 3]), length=tr.size[i][0],
                           width=tr.size[i][1])
               for i in range(len(tr.ids)) if tr.hits[i] >= p.confirm_hits]
        return Objects(stamp_ns=stamp_ns, source="tracker", tracks=tuple(out))

    # -- steps ---------------------------------------------------------------
    def _predict(self, dt: float) -> None:
        """x <- F x, P <- F P F^T + Q (constant velocity, white-noise acceleration)."""
        if dt <= 0 or not len(self.tracks.ids):
            return
        if self._model is None or self._model[0] != dt:   # lockstep: the same dt every scan
            F = np.eye(4)
            F[0, 2] = F[1, 3] = dt
            q = self.params.accel_sd ** 2
            a, b, c = dt ** 4 / 4 * q, dt ** 3 / 2 * q, dt ** 2 * q
            Q = np.array([[a, 0, b, 0], [0, a, 0, b], [b, 0, c, 0], [0, b, 0, c]])
            self._model = (dt, F, F.T.copy(), Q)
        _, F, FT, Q = self._model
        self.tracks.x = self.tracks.x @ FT
        self.tracks.P = F @ self.tracks.P @ FT + Q

    def _associate(self, clusters: list[Cluster]) -> tuple[list[int], list[int]]:
        """(track rows, cluster indices) of the gated optimal assignment."""
        tr = self.tracks
        if not clusters or not tr.ids:
            return [], []
        z = np.array([(c.x, c.y) for c in clusters])
        diff = tr.x[:, None, :2] - z[None, :, :]
        cost = np.sqrt(diff[..., 0] ** 2 + diff[..., 1] ** 2)
        gated = np.where(cost <= self.params.gate, cost, GATED_COST)
        rows, cols = linear_sum_assignment(gated)
        ok = cost[rows, cols] <= self.params.gate
        return rows[ok].tolist(), cols[ok].tolist()

    def _disc(self, c: Cluster, origin: tuple[float, float]) -> Cluster:
        """Cluster ``c`` as a disc (centre, diameter) when it is an arc (:func:`box.disc`)."""
        p = self.params
        if c.points is None or c.length > 2 * p.disc_max_radius:
            return c
        fit = box.disc(c.points, origin, p.disc_max_radius, p.disc_max_rms)
        if fit is None:
            return c
        x, y, r = fit
        return Cluster(x, y, c.axis, 2 * r, 2 * r, c.points, disc=True)

    def _box(self, i: int, c: Cluster, origin: tuple[float, float]) -> Cluster:
        """Cluster ``c`` measured as track ``i``'s box (:func:`nodes.tracker.box.fit`); a
        disc as itself (its centre does not depend on the track's heading)."""
        if c.disc:
            return Cluster(c.x, c.y, self.tracks.yaw[i], c.length, c.width, disc=True)
        if self.tracks.discs[i] >= DISC_HITS and c.points is not None:   # a disc seen unclean
            x, y = box.disc_seen(c.points, origin, 0.5 * self.tracks.size[i][0])
            return Cluster(x, y, self.tracks.yaw[i], c.length, c.width)
        pts = c.points if c.points is not None else np.array([(c.x, c.y)])
        x, y, along, across = box.fit(pts, self.tracks.yaw[i], self.tracks.size[i], origin,
                                      self.params.use_numba)
        return Cluster(x, y, self.tracks.yaw[i], along, across)

    def _correct(self, rows: list[int], clusters: list[Cluster]) -> None:
        """Kalman update of the matched tracks with their box centres (H = [I 0])."""
        if not rows:
            return
        tr, p = self.tracks, self.params
        x, P = tr.x[rows], tr.P[rows]
        z = np.array([(c.x, c.y) for c in clusters])
        r2 = p.meas_sd ** 2
        a, b, d = P[:, 0, 0] + r2, P[:, 0, 1], P[:, 1, 1] + r2           # S = [[a, b], [b, d]]
        det = a * d - b * b
        s_inv = np.empty((len(rows), 2, 2))                                # closed-form 2x2
        s_inv[:, 0, 0], s_inv[:, 1, 1] = d / det, a / det
        s_inv[:, 0, 1] = s_inv[:, 1, 0] = -b / det
        K = P[:, :, :2] @ s_inv                                            # (M, 4, 2)
        tr.x[rows] = x + (K @ (z - x[:, :2])[:, :, None])[:, :, 0]
        tr.P[rows] = P - K @ P[:, :2, :]
        for i, c in zip(rows, clusters, strict=True):
            tr.hits[i] += 1
            tr.misses[i] = 0
            size = (max(tr.size[i][0], c.length), max(tr.size[i][1], c.width))
            tr.discs[i] += c.disc
            if c.disc:   # a fitted diameter is noisy, not a lower bound: its running mean
                size = tuple((1 - DISC_SIZE_GAIN) * a + DISC_SIZE_GAIN * c.length
                             for a in tr.size[i])
            vx, vy = tr.x[i, 2], tr.x[i, 3]
            speed = math.hypot(vx, vy)
            # the filter's own velocity uncertainty along the velocity: a speed within two
            # standard deviations of it does not tell the direction of travel
            sd = math.sqrt(max(0.0, (vx * vx * tr.P[i, 2, 2] + 2 * vx * vy * tr.P[i, 2, 3]
                                     + vy * vy * tr.P[i, 3, 3]) / max(speed * speed, 1e-12)))
            if speed > max(p.moving_speed, 2.0 * sd):
                yaw = math.atan2(vy, vx)
                size = box.turned(size, yaw - tr.yaw[i])
                tr.yaw[i] = yaw
            tr.size[i] = size

    def _age(self, matched: list[int]) -> None:
        tr = self.tracks
        hit = set(matched)
        for i in range(len(tr.ids)):
            if i not in hit:
                tr.misses[i] += 1
        if any(m >= self.params.max_misses for m in tr.misses):
            tr.keep(np.array([m < self.params.max_misses for m in tr.misses]))

    def _start(self, c: Cluster) -> None:
        tr, p = self.tracks, self.params
        P0 = np.diag([p.meas_sd ** 2, p.meas_sd ** 2, p.init_speed_sd ** 2, p.init_speed_sd ** 2])
        tr.ids.append(self._next_id)
        self._next_id += 1
        tr.x = np.vstack([tr.x, [c.x, c.y, 0.0, 0.0]])
        tr.P = np.concatenate([tr.P, P0[None]])
        tr.hits.append(1)
        tr.misses.append(0)
        tr.yaw.append(c.axis)
        tr.size.append((c.length, c.width))
        tr.discs.append(int(c.disc))
