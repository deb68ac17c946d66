"""Where the repository is: the one place deploy finds its worlds, stack files and run directories."""

from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
#: Where runs write their reports and logs unless told otherwise (``--runs-dir``).
RUNS_DIR = REPO_ROOT / "runs"
