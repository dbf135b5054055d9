"""``python -m papf ...``: the same as the ``papf`` command (:func:`papf.cli.entry`)."""

import signal

# First, before the imports below (0.1-0.5 s): a script's `papf launch robot &` starts it with
# SIGINT ignored (the shell's rule for background commands), and a `kill -INT` that comes
# while it is still ignored is discarded by the kernel — the launch then runs on, deaf to it
# (issue 31, bench/ctrlc_loop.py). papf.cli.main installs the handlers it keeps.
signal.signal(signal.SIGINT, signal.default_int_handler)

from papf.cli import entry  # noqa: E402  (after the handler: see above)

entry()
