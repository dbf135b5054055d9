"""A :class:`worlds.World` as static pybullet bodies (docs/worlds.md).

Shared by the simulated base driver (collisions) and the simulated LiDAR (ray
casting), so both see exactly the same geometry. Every obstacle is a static body
(mass 0) whose shape and pose its kind gives (:meth:`worlds.kinds.base.Kind.body`,
:meth:`~worlds.kinds.base.Kind.pose`): boxes and walls, cylinders standing on the ground
plane ``z = 0``, spheres at their (x, y, z).

Moving obstacles (``[obstacles.motion]``) are kinematic: static bodies that
:class:`MovingBodies` teleports to their track pose (``resetBasePositionAndOrientation``)
at each sim time the caller asks for — the driver before every physics step, the LiDAR
before every scan — so both see the same obstacle at the same sim time, and contact
with one is found like contact with any other body, also when it drives into the robot.

Only pybullet is imported here; the caller owns the client (``p.connect(p.DIRECT)``).
"""

from __future__ import annotations

import math

import numpy as np

from common.quiet import import_quietly
from worlds import Obstacle, World

p = import_quietly("pybullet")   # no build banner on stderr (common/quiet.py)

GROUND_FRICTION = 1.0  # [-] lateral friction of the floor; the product with the wheel's is used


def _pose(ob: Obstacle) -> tuple[list[float], list[float]]:
    """Base position (shape centre) and orientation quaternion of an obstacle."""
    return ob.model.pose(p, ob)


def build_world(client_id: int, world: World, owners: dict[int, int] | None = None) -> list[int]:
    """Create the static bodies of every obstacle of ``world``; return each obstacle's first
    body id, in file order. ``owners`` (if given) gets body id -> obstacle index for every
    body (a map is several; :data:`MERGED` for a mesh of many obstacles)."""
    merged = _mergeable(world)
    ids = [-1] * len(world.obstacles)
    for tile in _by_tile(world, sorted(merged)):
        for body, members in _meshes(client_id, merged, tile):
            for i in members:
                ids[i] = body
            if owners is not None:
                owners[body] = MERGED
    for i, ob in enumerate(world.obstacles):
        if i in merged:
            continue
        pos, quat = _pose(ob)
        bodies = [p.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=shape,
                                    basePosition=pos, baseOrientation=quat,
                                    physicsClientId=client_id)
                  for shape in ob.model.bodies(p, client_id, ob)]
        ids[i] = bodies[0] if bodies else -1
        if owners is not None:
            owners.update(dict.fromkeys(bodies, i))
    return ids


MERGE_MIN = 64        # [-] static obstacles from which they are merged into meshes
MESH_VERTICES = 32768  # [-] vertices per merged mesh
MERGED = -1           # owners' value for a mesh of many obstacles
TILE_M = 10.0         # [m] side of the square places whose obstacles share meshes


def _mergeable(world: World) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """The static obstacles merged into meshes, index -> their triangles (vertices, faces):
    all that have triangles, when there are more than :data:`MERGE_MIN` (a body each costs
    start-up time and every physics step; a mesh's BVH costs neither)."""
    tris = {}
    for i, ob in enumerate(world.obstacles):
        if ob.motion is None:
            t = ob.model.triangles(ob)
            if t is not None:
                tris[i] = t
    return tris if len(tris) > MERGE_MIN else {}


def _by_tile(world: World, indices: list[int]) -> list[list[int]]:
    """Obstacle ``indices`` grouped by the :data:`TILE_M` square their bounding box's centre
    lies in (file order within a tile), so that each mesh covers one compact place: a ray or
    the robot then meets only the meshes of the tiles it crosses, not every mesh."""
    tiles: dict[tuple[int, int], list[int]] = {}
    for i in indices:
        ob = world.obstacles[i]
        x0, y0, x1, y1 = ob.model.bounds(ob)
        key = (math.floor((x0 + x1) / 2 / TILE_M), math.floor((y0 + y1) / 2 / TILE_M))
        tiles.setdefault(key, []).append(i)
    return [tiles[k] for k in sorted(tiles)]


def _meshes(client_id: int, tris: dict[int, tuple[np.ndarray, np.ndarray]],
            indices: list[int]) -> list[tuple[int, list[int]]]:
    """Static triangle-mesh bodies holding the solids (``tris``) of obstacles ``indices``,
    about :data:`MESH_VERTICES` each: (body id, the obstacle indices it holds) per mesh."""
    out, verts, faces, members, count = [], [], [], [], 0
    for k, i in enumerate(indices):
        v, f = tris[i]
        verts.append(v)
        faces.append(f + count)
        members.append(i)
        count += len(v)
        if count >= MESH_VERTICES or k == len(indices) - 1:
            shape = p.createCollisionShape(p.GEOM_MESH, vertices=np.vstack(verts).tolist(),
                                           indices=np.vstack(faces).ravel().tolist(),
                                           physicsClientId=client_id)
            out.append((p.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=shape,
                                          physicsClientId=client_id), members))
            verts, faces, members, count = [], [], [], 0
    return out


class MovingBodies:
    """The moving obstacles of a built world, placed on demand at a sim time."""

    def __init__(self, client_id: int, world: World, bodies: list[int]):
        self.client_id = client_id
        self._moving = [(body, ob) for body, ob in zip(bodies, world.obstacles, strict=True)
                        if ob.moving]
        self.t_ns: int | None = None

    def __bool__(self) -> bool:
        return bool(self._moving)

    def place(self, t_ns: int) -> None:
        """Put every moving obstacle where its track is at sim time ``t_ns`` [ns]."""
        if t_ns == self.t_ns:
            return
        self.t_ns = t_ns
        t = t_ns * 1e-9
        for body, ob in self._moving:
            pos, quat = _pose(ob.at(t))
            p.resetBasePositionAndOrientation(body, pos, quat, physicsClientId=self.client_id)


def add_ground(client_id: int, friction: float = GROUND_FRICTION) -> int:
    """An infinite static ground plane at ``z = 0``; returns its body id."""
    shape = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=client_id)
    body = p.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=shape,
                             physicsClientId=client_id)
    p.changeDynamics(body, -1, lateralFriction=friction, physicsClientId=client_id)
    return body
