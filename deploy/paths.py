"""Where the repository is: the one place deploy finds its worlds, stack files and run directories."""

from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
