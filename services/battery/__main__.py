"""``python -m services.battery``: see :mod:`services.battery.node` for parameters."""

import sys

from services.battery.node import main

if __name__ == "__main__":
    sys.exit(main())
