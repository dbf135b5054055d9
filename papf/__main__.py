import sys

from papf.cli import main

sys.exit(main())
