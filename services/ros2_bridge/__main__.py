import sys

from shared.memory import keep_openssl_out

keep_openssl_out()  # before any import of pydantic, which loads hashlib

from services.ros2_bridge.node import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
