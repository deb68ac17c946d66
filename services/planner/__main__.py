"""``python -m services.planner``: see :mod:`services.planner.node` for parameters."""

import sys

from services.planner.node import main

if __name__ == "__main__":
    sys.exit(main())
