"""A warm standby for one of zendock's services: ``python -m deploy.standby services.<name> FLAGS``.

A restarted service spends most of its recovery importing (numpy, Zenoh, its own modules; far longer
on a loaded machine), then much less opening its session (measurements 28 and 107). A standby pays the imports
once, ahead of time, and then forks the service on demand, as a zygote does: each ``go`` line on its standard
input forks a child that becomes the service, with the standby's flags and environment, in a session of its
own, while the standby stays ready for the next one. The child opens its Zenoh session after the fork; the
standby never opens one.

The standby is the children's parent, so it reports on the file descriptor named by
``ZENDOCK_STANDBY_STATUS_FD``, one line each: ``started PID`` after a fork, ``exited PID CODE`` once a child
has exited (CODE negative: killed by that signal), and ``ready`` once, when its imports are done. At the end of its input it exits: the supervisor has
stopped it, or has gone. The children share the standby's standard output and error.

It imports the service's ``__main__`` module, which holds nothing but the service's start-up imports (and
``keep_openssl_out``, which must come before them), then does once what each child would otherwise redo
(:func:`_prepare_for_forks`). This module is deliberately bare: it is the first thing a standby imports.
"""

from __future__ import annotations

import gc
import importlib
import os
import runpy
import select
import signal
import sys

#: The line that forks a service.
GO = b"go\n"
#: The environment variable naming the descriptor the standby reports on.
STATUS_FD_ENV = "ZENDOCK_STANDBY_STATUS_FD"
USAGE = f"usage: {STATUS_FD_ENV}=FD python -m deploy.standby services.<name> [FLAGS...]"


def _report(status_fd: int, text: str) -> None:
    os.write(status_fd, f"{text}\n".encode())


def _reap(status_fd: int) -> None:
    """Report every child that has exited."""
    while True:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        _report(status_fd, f"exited {pid} {os.waitstatus_to_exitcode(status)}")


def _become(module: str, flags: list[str], inherited: tuple[int, ...]) -> None:
    """In the forked child: leave the standby's session, signals and descriptors, and run the service as
    ``python -m`` would. Never returns: the service's exit ends the process."""
    os.setsid()
    signal.set_wakeup_fd(-1)
    signal.signal(signal.SIGCHLD, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    for fd in inherited:
        os.close(fd)
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)  # a service started directly reads /dev/null
    os.close(devnull)
    del sys.modules[f"{module}.__main__"]  # run afresh as ``__main__`` (its imports are done and stay)
    sys.argv = [module, *flags]
    runpy.run_module(module, run_name="__main__", alter_sys=True)
    raise SystemExit(0)


def serve(module: str, flags: list[str], status_fd: int) -> int:
    """Fork the service at each ``go``, report children's exits, until the end of the input."""
    wake_r, wake_w = os.pipe()
    os.set_blocking(wake_r, False)
    os.set_blocking(wake_w, False)
    signal.set_wakeup_fd(wake_w, warn_on_full_buffer=False)
    signal.signal(signal.SIGCHLD, lambda *_: None)  # wakes the select through wake_w
    pending = b""
    while True:
        try:
            ready, _, _ = select.select([0, wake_r], [], [])
        except InterruptedError:
            continue
        if wake_r in ready:
            while True:
                try:
                    if not os.read(wake_r, 512):
                        break
                except BlockingIOError:
                    break
            _reap(status_fd)
        if 0 in ready:
            chunk = os.read(0, 4096)
            if not chunk:
                return 0
            pending += chunk
            while b"\n" in pending:
                line, pending = pending.split(b"\n", 1)
                if line + b"\n" != GO:
                    print(f"warm standby: ignored {line[:80]!r}", file=sys.stderr, flush=True)
                    continue
                pid = os.fork()
                if pid == 0:
                    _become(module, flags, (wake_r, wake_w, status_fd))
                _report(status_fd, f"started {pid}")


def _prepare_for_forks() -> None:
    """Finish, once and before any fork, the work each child would otherwise redo on its way to ready.

    Every message class the service's imports defined becomes a dataclass with its codec compiled (a service
    started directly does that for each class on first use). Then what the imports made is frozen out of
    the garbage collector: a child's collections would otherwise walk it and copy every page they touch."""
    schema = sys.modules.get("shared.schema")
    if schema is not None:
        schema.compile_all()
    gc.collect()
    gc.freeze()


def main(argv: list[str]) -> int:
    status = os.environ.pop(STATUS_FD_ENV, "")
    if not argv or not argv[0].startswith("services.") or not status.isdigit():
        print(USAGE, file=sys.stderr)
        return 2
    module, flags = argv[0], argv[1:]
    # Stopped before it is needed, a standby goes quietly: it has nothing to close.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    try:
        importlib.import_module(f"{module}.__main__")  # its ``__name__`` guard keeps the service's main out
        _prepare_for_forks()
    except Exception as exc:
        print(f"warm standby: cannot import {module}: {exc!r}", file=sys.stderr)
        return 1
    sys.stdout.flush()
    sys.stderr.flush()
    try:
        _report(int(status), "ready")
        return serve(module, flags, int(status))
    except BrokenPipeError:  # nobody reads the reports: the supervisor has gone
        return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
