"""``python -m impactbar``: the command line, as ``impactbar``."""

import sys

from .cli import main

sys.exit(main())
