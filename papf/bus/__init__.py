"""Tools to poke the bus, like ``ros2 topic`` / ``ros2 run teleop_twist_keyboard``.

- :mod:`papf.bus.decode` — any payload on a key -> its encoding, type and fields
  (our msgpack schemas, the bridge's ROS 2 CDR, or raw bytes);
- :mod:`papf.bus.stats` — message rates as ``ros2 topic hz`` prints them;
- :mod:`papf.bus.topics` — ``papf topic list | echo | hz`` over a Zenoh session;
- :mod:`papf.bus.goal` — ``papf goal X Y``: goal handshake, optional run start, progress;
- :mod:`papf.bus.teleop` — ``papf teleop``: keyboard -> ``cmd_vel`` through the driver's gate.
"""
