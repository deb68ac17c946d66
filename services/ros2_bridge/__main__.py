import sys

from services.ros2_bridge.node import main

sys.exit(main())
