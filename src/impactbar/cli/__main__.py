"""``python -m impactbar.cli``: the command line, as ``impactbar``."""

import sys

from . import main

sys.exit(main())
