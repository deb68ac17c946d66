import sys

from services.docking.node import main

sys.exit(main())
