"""``python -m services.battery``: see :mod:`services.battery.node` for parameters."""

import sys

from shared.memory import keep_blas_single_threaded, keep_openssl_out

keep_openssl_out()  # before anything that imports hashlib (the glass memory's digest, foxglove)
keep_blas_single_threaded()  # before numpy: no OpenBLAS threads spinning at start

from services.battery.node import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
