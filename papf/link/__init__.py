"""A link you can rehearse: ``papf link``, a userspace emulator of the robot/laptop network.

:mod:`papf.link.spec` (what a link does: profiles, ``PROFILE|SPEC`` text), :mod:`papf.link.schedule`
(the pure core: when each chunk leaves), :mod:`papf.link.proxy` (the asyncio TCP forwarder)
and :mod:`papf.link.stats` (what it did). docs/link.md.
"""
