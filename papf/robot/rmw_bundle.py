"""The secure split on rmw_zenoh: ``rmw_zenohd`` is the robot's secure router (docs/robot.md).

With ``papf make-certs DIR --robot-host H --ros rmw_zenoh [--ros-domain N]`` the bundle's
Zenoh configs take the form rmw_zenoh reads: whole Zenoh configs named by
``ZENOH_ROUTER_CONFIG_URI`` (for ``rmw_zenohd``) and ``ZENOH_SESSION_CONFIG_URI`` (for every
ROS 2 process on the robot), written from the fields of rmw_zenoh's
``DEFAULT_RMW_ZENOH_ROUTER_CONFIG.json5`` / ``DEFAULT_RMW_ZENOH_SESSION_CONFIG.json5``
(router: listen ``tcp/[::]:7447``; session: peer, connect ``tcp/localhost:7447``, listen
``tcp/localhost:0``; both: no multicast, gossip scouting, timestamps) with what the
secure split changes:

- ``rmw_zenohd.json5``: listens on the loopback only (``tcp/127.0.0.1:7447``: the robot's
  ROS 2 nodes and our router) and on TLS (``tls/0.0.0.0:7448``: the laptop), mutual TLS,
  the password dictionary, and the access control of :func:`papf.robot.certs.access_control`
  with the robot's ROS 2 domain: only ``robot`` (its password over the loopback) may put
  on the domain's keys (``<domain>/**``, the ``cmd_vel`` that moves the wheels among them),
  only ``planner`` (its password with the laptop's certificate) on ``<ns>/cmd_vel``,
  ``observer`` on nothing;
- ``ros_session.json5``: the ROS 2 nodes' session, the robot's password over the loopback;
- ``router.json5``: our router, loopback only (``tcp/127.0.0.1:7449``), joined to
  ``rmw_zenohd`` as ``robot``; ``robot.json5``: our robot nodes, clients of it.

The laptop's ``laptop.json5`` and ``observer.json5`` are the bridge bundle's: TLS to port
7448, now ``rmw_zenohd``'s. ``rmw_zenohd`` reads file paths from its working directory:
start it in the bundle's directory (the relative names then resolve).
"""

from __future__ import annotations

PAPF_PORT = 7449            # [-] our router on the robot's loopback (rmw_zenohd holds 7447)
# rmw_zenoh's defaults kept in both files (DEFAULT_RMW_ZENOH_*_CONFIG.json5)
SCOUTING = {"multicast": {"enabled": False},
            "gossip": {"enabled": True, "multihop": False,
                       "autoconnect": {"router": [], "peer": ["router", "peer"]}}}
TIMESTAMPING = {"enabled": {"router": True, "peer": True, "client": False},
                "drop_future_timestamp": False}


def rmw_configs(passwords: dict[str, str], tls: dict, acl: dict, local_port: int, tls_port: int,
                papf_port: int = PAPF_PORT) -> dict[str, dict]:
    """``rmw_zenohd``, ``ros_session``, ``router`` and ``robot`` configs (module doc)."""
    rmw = f"tcp/127.0.0.1:{local_port}"
    ours = f"tcp/127.0.0.1:{papf_port}"
    robot_auth = {"usrpwd": {"user": "robot", "password": passwords["robot"]}}
    return {
        "rmw_zenohd": {"mode": "router",
                       "listen": {"endpoints": [rmw, f"tls/0.0.0.0:{tls_port}"]},
                       "scouting": SCOUTING, "timestamping": TIMESTAMPING,
                       "transport": {"link": {"tls": tls},
                                     "auth": {"usrpwd": {"dictionary_file": "credentials.txt"}}},
                       "access_control": acl},
        "ros_session": {"mode": "peer", "connect": {"endpoints": [rmw]},
                        "listen": {"endpoints": ["tcp/127.0.0.1:0"]},
                        "scouting": SCOUTING, "timestamping": TIMESTAMPING,
                        "transport": {"auth": robot_auth}},
        "router": {"mode": "router", "connect": {"endpoints": [rmw]},
                   "listen": {"endpoints": [ours]}, "scouting": {"multicast": {"enabled": False}},
                   "transport": {"auth": {"usrpwd": {**robot_auth["usrpwd"],
                                                     "dictionary_file": "credentials.txt"}}}},
        "robot": {"mode": "client", "connect": {"endpoints": [ours]},
                  "scouting": {"multicast": {"enabled": False}}, "transport": {"auth": robot_auth}},
    }
