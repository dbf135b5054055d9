"""A URDF of the ROSbot 2.0 PRO from the facts in :mod:`common.robot`, for ``/robot_description``.

Links: ``base_link`` (the footprint centre on the floor, x forward, z up, REP 103) carrying the
chassis box, four wheel links on continuous joints about their axles (y), and ``laser`` on a
fixed joint at the LiDAR's mount (``robot.LIDAR_X_M``, ``LIDAR_Y_M``, ``LIDAR_HEIGHT_M``) —
the same ``base_link -> laser`` transform ``/tf_static`` carries. Geometry only as far as the
facts go: the chassis is a box, a wheel a cylinder. ASSUMPTION: the chassis box spans from
half a wheel radius above the floor to the scan plane (the LiDAR sits on its top).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from functools import lru_cache

from common import robot

ROBOT_NAME = "rosbot_2_pro"
BASE_LINK = "base_link"
LASER = "laser"
WHEELS = ("front_left", "front_right", "rear_left", "rear_right")
CLEARANCE_M = 0.5 * robot.WHEEL_RADIUS_M        # [m] chassis bottom above the floor (assumption)
CHASSIS_HEIGHT_M = robot.LIDAR_HEIGHT_M - CLEARANCE_M   # [m] box height up to the LiDAR's base
LASER_RADIUS_M, LASER_HEIGHT_M = 0.038, 0.041   # [m] RPLIDAR A3 housing (datasheet: 76 x 41 mm)


def _f(x: float) -> str:
    return f"{x:.6g}"


def _xyz(*v: float) -> str:
    return " ".join(_f(x) for x in v)


def _origin(parent: ET.Element, xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0)) -> None:
    ET.SubElement(parent, "origin", xyz=_xyz(*xyz), rpy=_xyz(*rpy))


def _inertial(link: ET.Element, mass: float, ixx: float, iyy: float, izz: float,
              centre=(0.0, 0.0, 0.0)) -> None:
    """``<inertial>`` of ``mass`` [kg], principal moments [kg m²] about ``centre`` [m]."""
    el = ET.SubElement(link, "inertial")
    _origin(el, centre)
    ET.SubElement(el, "mass", value=_f(mass))
    ET.SubElement(el, "inertia", ixx=_f(ixx), ixy="0", ixz="0", iyy=_f(iyy), iyz="0",
                  izz=_f(izz))


def _shape(link: ET.Element, geometry: tuple[str, dict], xyz=(0.0, 0.0, 0.0),
           rpy=(0.0, 0.0, 0.0)) -> None:
    """The same ``<visual>`` and ``<collision>`` geometry on ``link``."""
    for tag in ("visual", "collision"):
        el = ET.SubElement(link, tag)
        _origin(el, xyz, rpy)
        ET.SubElement(ET.SubElement(el, "geometry"), geometry[0], **geometry[1])


def _chassis(root: ET.Element) -> None:
    link = ET.SubElement(root, "link", name=BASE_LINK)
    size = (robot.BODY_LENGTH_M, robot.BODY_WIDTH_M, CHASSIS_HEIGHT_M)
    centre = (0.0, 0.0, CLEARANCE_M + size[2] / 2)
    _shape(link, ("box", {"size": _xyz(*size)}), xyz=centre)
    m = robot.MASS_KG - 4 * robot.WHEEL_MASS_KG
    lx, ly, lz = size
    _inertial(link, m, m * (ly**2 + lz**2) / 12, m * (lx**2 + lz**2) / 12,
              m * (lx**2 + ly**2) / 12, centre)


def wheel_origin(name: str) -> tuple[float, float, float]:
    """Where the wheel ``name``'s joint sits on ``base_link`` [m]: its axle's centre."""
    x = (0.5 if name.startswith("front") else -0.5) * robot.WHEELBASE_M
    y = (0.5 if name.endswith("left") else -0.5) * robot.TRACK_M
    return x, y, robot.WHEEL_RADIUS_M


def _wheel(root: ET.Element, name: str) -> None:
    link = ET.SubElement(root, "link", name=f"{name}_wheel_link")
    r, w, m = robot.WHEEL_RADIUS_M, robot.WHEEL_WIDTH_M, robot.WHEEL_MASS_KG
    # a cylinder's axis is z: roll it by -90 deg onto the axle (y)
    _shape(link, ("cylinder", {"radius": _f(r), "length": _f(w)}), rpy=(-math.pi / 2, 0, 0))
    i_rim = m * (3 * r**2 + w**2) / 12
    _inertial(link, m, i_rim, m * r**2 / 2, i_rim)
    joint = ET.SubElement(root, "joint", name=f"{name}_wheel_joint", type="continuous")
    ET.SubElement(joint, "parent", link=BASE_LINK)
    ET.SubElement(joint, "child", link=f"{name}_wheel_link")
    _origin(joint, wheel_origin(name))
    ET.SubElement(joint, "axis", xyz="0 1 0")


def _laser(root: ET.Element) -> None:
    link = ET.SubElement(root, "link", name=LASER)
    # the housing around the scan plane (the link origin), which is 2 cm below its top
    _shape(link, ("cylinder", {"radius": _f(LASER_RADIUS_M), "length": _f(LASER_HEIGHT_M)}),
           xyz=(0.0, 0.0, -LASER_HEIGHT_M / 2 + 0.02))
    joint = ET.SubElement(root, "joint", name="laser_joint", type="fixed")
    ET.SubElement(joint, "parent", link=BASE_LINK)
    ET.SubElement(joint, "child", link=LASER)
    _origin(joint, (robot.LIDAR_X_M, robot.LIDAR_Y_M, robot.LIDAR_HEIGHT_M),
            (0.0, 0.0, robot.LIDAR_YAW_RAD))


@lru_cache(maxsize=1)
def rosbot_urdf() -> str:
    """The URDF (XML text) of the ROSbot 2.0 PRO: chassis, four wheels, the LiDAR."""
    root = ET.Element("robot", name=ROBOT_NAME)
    _chassis(root)
    for name in WHEELS:
        _wheel(root, name)
    _laser(root)
    ET.indent(root)
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
