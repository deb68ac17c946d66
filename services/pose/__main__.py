"""``python -m services.pose``: see :mod:`services.pose.node` for parameters."""

import sys

from shared.memory import keep_openssl_out, skip_pydantic_plugin_scan

keep_openssl_out()  # before any import of pydantic, which loads hashlib
skip_pydantic_plugin_scan()  # before the first pydantic model

from services.pose.node import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
