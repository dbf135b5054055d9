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
    for body in _merged_bodies(client_id, [world.obstacles[i] for i in merged]):
        for i in merged:
            ids[i] = body if ids[i] < 0 else ids[i]
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


def _mergeable(world: World) -> set[int]:
    """Indices of the static obstacles merged into meshes: all that have triangles, when
    there are more than :data:`MERGE_MIN` (a body each costs start-up time and every physics
    step; a mesh's BVH costs neither)."""
    idx = {i for i, ob in enumerate(world.obstacles)
           if ob.motion is None and ob.model.triangles(ob) is not None}
    return idx if len(idx) > MERGE_MIN else set()


def _merged_bodies(client_id: int, obstacles) -> list[int]:
    """Static triangle-mesh bodies holding ``obstacles``' solids, :data:`MESH_VERTICES` each."""
    bodies, verts, faces, count = [], [], [], 0
    for k, ob in enumerate(obstacles):
        v, f = ob.model.triangles(ob)
        verts.append(v)
        faces.append(f + count)
        count += len(v)
        if count >= MESH_VERTICES or k == len(obstacles) - 1:
            shape = p.createCollisionShape(p.GEOM_MESH, vertices=np.vstack(verts).tolist(),
                                           indices=np.vstack(faces).ravel().tolist(),
                                           physicsClientId=client_id)
            bodies.append(p.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=shape,
                                            physicsClientId=client_id))
            verts, faces, count = [], [], 0
    return bodies


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
