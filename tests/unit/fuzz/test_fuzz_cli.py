"""``zendock fuzz`` on the command line: bad arguments are usage errors, remote endpoints refused."""

from __future__ import annotations

import pytest

from deploy.cli import main


def test_a_remote_endpoint_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["fuzz", "--connect", "tcp/10.1.2.3:7447", "--messages", "10"]) == 2
    assert "not a loopback endpoint" in capsys.readouterr().err


def test_bad_counts_are_usage_errors(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["fuzz", "--connect", "tcp/127.0.0.1:7447", "--messages", "-1"]) == 2
    assert "--messages" in capsys.readouterr().err
