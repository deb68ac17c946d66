"""Where the repository is: the one place deploy finds its worlds, stack files and run directories."""

import time
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
#: Where runs write their reports and logs unless told otherwise (``--runs-dir``).
RUNS_DIR = REPO_ROOT / "runs"


def new_run_dir(runs_dir: Path, prefix: str = "", suffix: str = "") -> Path:
    """A new directory ``runs_dir/<prefix><time><suffix>``, made now and never shared with another run.

    Two runs started in the same second (parallel campaigns, a script's loop) would otherwise write into
    one directory, and the second found the first's stack there ("already up"): the later one gets
    ``-2``, ``-3``, ... after its name.
    """
    name = f"{prefix}{time.strftime('%Y%m%d-%H%M%S')}{suffix}"
    runs_dir.mkdir(parents=True, exist_ok=True)
    attempt = 1
    while True:
        candidate = runs_dir / (name if attempt == 1 else f"{name}-{attempt}")
        try:
            candidate.mkdir()
        except FileExistsError:
            attempt += 1
            continue
        return candidate
