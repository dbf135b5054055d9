"""``python -m papf ...``: the same as the ``papf`` command (:func:`papf.cli.entry`)."""

from papf.cli import entry

entry()
