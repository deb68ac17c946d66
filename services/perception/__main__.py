import sys

from services.perception.node import main

sys.exit(main())
