import sys

from services.ros2_dds.node import main

sys.exit(main())
