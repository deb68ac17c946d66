"""``python -m services.pose``: see :mod:`services.pose.node` for parameters."""

import sys

from services.pose.node import main

if __name__ == "__main__":
    sys.exit(main())
