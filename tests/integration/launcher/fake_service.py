"""A stand-in for a zendock service, run by path (``python fake_service.py ...``) in launcher tests.

Like a real service it reads ``ZENDOCK_NAMESPACE``/``ZENDOCK_CONNECT``, declares its node liveliness token
once "ready", and exits 0 on SIGINT/SIGTERM; flags make it misbehave in the ways the launcher must handle.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import threading
import time


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    parser.add_argument("--name", default="fake")
    parser.add_argument("--token", metavar="NODE", help="declare this node's liveliness token when ready")
    parser.add_argument("--ready-after", type=float, default=0.0, help="seconds before declaring the token")
    parser.add_argument("--exit-after", type=float, help="exit by itself after this many seconds")
    parser.add_argument("--exit-code", type=int, default=0)
    parser.add_argument("--record", help="append '<name> <event> <monotonic time>' lines to this file")
    parser.add_argument("--grandchild", choices=["group", "session"], help="spawn a long-lived grandchild")
    parser.add_argument("--ignore", action="append", default=[], choices=["SIGINT", "SIGTERM"])
    parser.add_argument("--fail-unless-exists", metavar="FILE", help="exit 3 at once unless FILE exists")
    return parser.parse_args()


def record(args: argparse.Namespace, event: str) -> None:
    if args.record:
        with open(args.record, "a", encoding="utf-8") as out:
            out.write(f"{args.name} {event} {time.monotonic():.6f} {os.getpid()}\n")


def main() -> int:
    args = parse_args()
    stop = threading.Event()
    for name in ("SIGINT", "SIGTERM"):
        sig = getattr(signal, name)
        signal.signal(sig, signal.SIG_IGN if name in args.ignore else lambda *_: stop.set())
    record(args, "start")
    print(f"{args.name} up (pid {os.getpid()})", flush=True)
    if args.fail_unless_exists and not os.path.exists(args.fail_unless_exists):
        print(f"{args.name}: {args.fail_unless_exists} missing", flush=True)
        return 3
    if args.grandchild:
        child = subprocess.Popen(
            [sys.executable, "-c", "import time; time.sleep(300)"],
            start_new_session=args.grandchild == "session",
        )
        print(f"grandchild {child.pid}", flush=True)
    session = token = None
    if args.token:
        from shared.names import (
            node_token_key,  # zenoh is imported only by fakes that need it: faster restarts
        )
        from shared.session import SessionSpec, open_session

        connect = tuple(os.environ["ZENDOCK_CONNECT"].split(","))
        session = open_session(SessionSpec(mode="client", connect=connect))
        if stop.wait(args.ready_after):
            session.close()
            return 0
        token = session.liveliness().declare_token(
            node_token_key(os.environ.get("ZENDOCK_NAMESPACE", ""), args.token)
        )
        record(args, "ready")
        print(f"{args.name} ready", flush=True)
    stopped = stop.wait(args.exit_after)
    if token is not None:
        token.undeclare()
    if session is not None:
        session.close()
    record(args, "stop" if stopped else "exit")
    return 0 if stopped else args.exit_code


if __name__ == "__main__":
    sys.exit(main())
