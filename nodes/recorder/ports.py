"""Ports of the recorder (see :mod:`common.ports`): every key under ``--keys``, raw."""

PORTS = (
    ("in?", "**", "any"),                        # recorded raw, bad payloads too
    ("in?", "events", "Event"),                  # run_ended closes the file (--close-on-run-ended)
    ("out", "events", "Event"),                  # recording_closed: the file is complete
)
VARIANTS: dict = {}
