"""``python -m papf ...``: the same as the ``papf`` command (:func:`papf.cli.main`)."""

import sys

from papf.cli import main

sys.exit(main())
