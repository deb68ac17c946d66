"""Restart policies and the exponential backoff between restarts (the rules ``ps`` shows the effect of)."""

from __future__ import annotations

import re
from dataclasses import dataclass

from shared.config_errors import CONFIG_ERROR_EXIT

#: Exits a restart would only repeat, and what each means: the same files, flags and programs give the same
#: answer, so the service is left down and the run told at once instead of a crash loop.
FINAL_EXITS = {
    CONFIG_ERROR_EXIT: "a configuration error",
    78: "a configuration error",  # EX_CONFIG
    126: "a command that cannot run",
    127: "a command not found",
}
_POLICY_RE = re.compile(r"^(no|always|unless-stopped|on-failure)(?::(\d+))?$")


@dataclass(frozen=True)
class RestartPolicy:
    """When a service that exited by itself is started again.

    ``always`` and ``unless-stopped`` restart after any exit; ``on-failure`` after a non-zero exit (a
    signal counts as a failure), at most ``max_retries`` times in a row when given. A service stopped by the
    user (``stop``, ``down``) is never restarted, whatever the policy, nor is one that exited with
    :data:`~shared.config_errors.CONFIG_ERROR_EXIT` (2) or another of :data:`FINAL_EXITS` (a configuration
    error, a command not found), which the same files and flags would only repeat, as a crash loop.
    """

    mode: str = "no"
    max_retries: int | None = None

    def should_restart(self, exit_code: int, consecutive_restarts: int) -> bool:
        if exit_code in FINAL_EXITS:
            return False
        if self.mode in ("always", "unless-stopped"):
            return True
        if self.mode == "on-failure" and exit_code != 0:
            return self.max_retries is None or consecutive_restarts < self.max_retries
        return False

    def __str__(self) -> str:
        return f"{self.mode}:{self.max_retries}" if self.max_retries is not None else self.mode


def parse_restart_policy(value: object) -> RestartPolicy:
    """``no`` | ``always`` | ``on-failure[:max]`` | ``unless-stopped``; YAML's bare ``no`` (False) is ``no``."""
    if value is False:
        return RestartPolicy("no")
    if isinstance(value, RestartPolicy):
        return value
    match = _POLICY_RE.match(value) if isinstance(value, str) else None
    if match is None:
        raise ValueError(f"expected one of no, always, on-failure[:max], unless-stopped; got {value!r}")
    mode, retries = match.group(1), match.group(2)
    if retries is not None and mode != "on-failure":
        raise ValueError(f"only on-failure takes a maximum, got {value!r}")
    return RestartPolicy(mode, int(retries) if retries is not None else None)


@dataclass(frozen=True)
class Backoff:
    """Exponential delay before restart n (0-based) of a streak: ``initial_s * 2**n``, capped at ``max_s``.

    A run that lasted ``reset_after_s`` or longer, or passed its healthcheck, ends the streak, so a service
    killed now and then restarts quickly while one that crashes at start-up settles at one attempt every
    ``max_s``. The first delay is 0.1 s, as Docker's restart policy starts: a longer first wait would be
    most of a recovery (how long a start takes: measurement 107).

    A service that was healthy and then died (killed, or a fault long after start) is restarted at once
    the first time within ``reset_after_s``: the wait guards against crash loops, and one death after a
    healthy run is not a loop. A second death within ``reset_after_s`` waits as any restart does.
    """

    initial_s: float = 0.1
    max_s: float = 10.0
    reset_after_s: float = 10.0

    def delay_s(self, consecutive_restarts: int) -> float:
        return min(self.max_s, self.initial_s * 2.0 ** min(consecutive_restarts, 32))

    def restart_delay_s(
        self, consecutive_restarts: int, *, run_was_healthy: bool, since_last_restart_s: float | None
    ) -> float:
        """The wait before this restart: none after a healthy run when no restart came in the last
        ``reset_after_s`` (``since_last_restart_s`` None: never restarted), else :meth:`delay_s`."""
        quiet = since_last_restart_s is None or since_last_restart_s >= self.reset_after_s
        if run_was_healthy and quiet:
            return 0.0
        return self.delay_s(consecutive_restarts)
