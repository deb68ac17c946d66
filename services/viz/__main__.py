"""``python -m services.viz``: see :mod:`services.viz.node` for parameters."""

import sys

from services.viz.node import main

if __name__ == "__main__":
    sys.exit(main())
