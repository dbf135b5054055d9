"""Ports of the recorder (see :mod:`common.ports`): every key under ``--keys``, raw."""

PORTS = (
    ("in?", "**", "any"),                        # recorded raw, bad payloads too
)
VARIANTS: dict = {}
