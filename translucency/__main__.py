"""``python -m translucency``: the command line (see :mod:`translucency.app.cli`)."""

import sys

from translucency.app.cli import main

sys.exit(main())
