"""``python -m papf ...``: the same as the ``papf`` command (:func:`papf.cli.main`).

After ``papf run`` — every process it started stopped and their last output lines printed
(:meth:`papf.supervisor.Supervisor.stop`), its Zenoh session closed, the result printed —
the interpreter's teardown of numpy, Zenoh and rich is skipped
(:func:`common.transport.exit_fast`: logs and streams flushed, then ``os._exit``).
"""

import sys

from papf.cli import main

code = main()
if sys.argv[1:2] == ["run"]:
    from common.transport import exit_fast  # Zenoh is loaded by the run already

    exit_fast(code)
sys.exit(code)
