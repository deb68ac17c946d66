import sys

from services.simulator.node import main

sys.exit(main())
