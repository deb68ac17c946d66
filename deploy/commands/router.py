"""``zendock router``: an embedded Zenoh router, so a stack needs nothing installed beyond PyPI.

It listens on loopback by default, never scouts by multicast, prints one line once it is listening and
exits 0 on SIGINT or SIGTERM after closing its session (the launcher stops services that way).
"""

from __future__ import annotations

import argparse
import re
import signal
import sys
import threading
from collections.abc import Sequence

from shared.bus_env import listen_from_env
from shared.config_errors import ConfigError
from shared.session import DEFAULT_ROUTER_ENDPOINT, SessionSpec, open_session
from shared.waiting import wait_interruptibly

#: A link whose send queue stays blocked this long (µs) is closed, instead of Zenoh's default 5 s: a cut
#: link to another host must not hold up this router's forwarding to its local services.
BLOCKED_LINK_CLOSE_US = 500_000


def router_spec(listen: Sequence[str], config_file: str | None) -> SessionSpec:
    """Listen endpoints win over the config file's; with neither, listen on the default loopback endpoint."""
    if not listen and not config_file:
        listen = (DEFAULT_ROUTER_ENDPOINT,)
    overrides = (
        ()
        if config_file
        else (
            (
                "transport/link/tx/queue/congestion_control/block/wait_before_close",
                str(BLOCKED_LINK_CLOSE_US),
            ),
        )
    )
    return SessionSpec(
        mode="router", connect=(), listen=tuple(listen), config_file=config_file, overrides=overrides
    )


def plain_error(text: str) -> str:
    """Zenoh's error without the Rust source locations it carries (``at .../tcp.rs:61``): the first line,
    cut where the first location begins."""
    first = text.strip().splitlines()[0] if text.strip() else text
    cut = re.search(r"\s+at\s+\S+\.rs:\d+", first)
    return (first[: cut.start()] if cut else first).strip()


def run_router(spec: SessionSpec, stop: threading.Event) -> int:
    """Serve until ``stop`` is set; the session is closed on the way out."""
    try:
        session = open_session(spec)
    except ValueError as exc:  # a missing config file or a bad mode
        raise ConfigError(str(exc)) from exc
    except Exception as exc:  # zenoh.ZError: the endpoint is taken or malformed
        text = plain_error(str(exc))
        if "address already in use" in text.lower() or "os error 98" in text:
            where = ", ".join(spec.listen) or "its endpoint"
            # The same port stays taken: a configuration error (exit 2), not worth a restart.
            raise ConfigError(
                f"{where} is in use: set ZENOH_LISTEN and ZENOH_CONNECT to a free port "
                "(e.g. tcp/127.0.0.1:7448), or stop what listens there"
            ) from None
        print(f"zendock router: cannot start: {text}", file=sys.stderr, flush=True)
        return 1
    with session:
        where = ", ".join(spec.listen) if spec.listen else f"the endpoints of {spec.config_file}"
        print(f"zendock router: listening on {where} (zid {session.info.zid()})", flush=True)
        wait_interruptibly(stop)
    return 0


def main(args: argparse.Namespace) -> int:
    stop = threading.Event()

    def request_stop(_signum: int, _frame: object) -> None:
        stop.set()

    signal.signal(signal.SIGINT, request_stop)
    signal.signal(signal.SIGTERM, request_stop)
    # --listen, else (without a config file of its own) ZENOH_LISTEN, as every zendock process reads it.
    listen = args.listen or (() if args.config else listen_from_env())
    return run_router(router_spec(listen, args.config), stop)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "router",
        help="run an embedded Zenoh router",
        description="Run an embedded Zenoh router (multicast scouting off). Exits 0 on SIGINT/SIGTERM.",
    )
    parser.add_argument(
        "--listen",
        action="append",
        metavar="ENDPOINT",
        help=f"endpoint to listen on, repeatable (env ZENOH_LISTEN; default {DEFAULT_ROUTER_ENDPOINT}, or the "
        "config file's)",
    )
    parser.add_argument(
        "--config", metavar="FILE", help="a Zenoh json5 config file (e.g. deploy/zenoh/router.json5)"
    )
    parser.set_defaults(func=main)
