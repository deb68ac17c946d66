"""``python -m services.fleet``: see :mod:`services.fleet.node` for parameters."""

import sys

from services.fleet.node import main

if __name__ == "__main__":
    sys.exit(main())
