"""Every error the stack raises on purpose subclasses :class:`PapfError`.

Messages name the offending value and say what would be valid or what to do.
"""


class PapfError(Exception):
    """Base of all papf-stack errors."""


class SchemaError(PapfError, ValueError):
    """Bytes or values that do not form a valid message of a given type."""


class WorldError(PapfError):
    """A world file that is missing, unreadable or describes an invalid world."""


class ConfigError(PapfError):
    """An invalid command-line or TOML setting."""


class RecordingError(PapfError):
    """An MCAP recording that cannot be read, written or recovered."""
