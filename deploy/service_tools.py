"""Run a service's own tool (map rasteriser, benchmarks, lower bound) as a process.

The launcher floor never imports a service's code: it starts it, as it starts the services
themselves, and reads what the tool prints.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass
class ToolResult:
    returncode: int
    stdout: str
    stderr: str

    def echo(self) -> int:
        """Pass the tool's output on as this command's own; returns its exit code."""
        if self.stdout:
            print(self.stdout, end="" if self.stdout.endswith("\n") else "\n")
        if self.stderr:
            print(self.stderr, end="" if self.stderr.endswith("\n") else "\n", file=sys.stderr)
        return self.returncode

    def last_json(self) -> Any:
        """The last line of output, parsed as JSON (``RuntimeError`` with the tool's error otherwise)."""
        if self.returncode != 0:
            raise RuntimeError(
                self.stderr.strip().splitlines()[-1] if self.stderr.strip() else f"exit {self.returncode}"
            )
        lines = [line for line in self.stdout.splitlines() if line.strip()]
        if not lines:
            raise RuntimeError("the tool printed nothing")
        return json.loads(lines[-1])


def run_tool(
    module: str, argv: Sequence[str], input_text: str | None = None, timeout_s: float = 600.0
) -> ToolResult:
    """``python -m <module> <argv...>`` with this interpreter; output captured."""
    done = subprocess.run(
        [sys.executable, "-m", module, *argv],
        input=input_text,
        capture_output=True,
        text=True,
        timeout=timeout_s,
        cwd=Path.cwd(),
    )
    return ToolResult(done.returncode, done.stdout, done.stderr)
