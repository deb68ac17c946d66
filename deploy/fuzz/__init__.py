"""``zendock fuzz``: malformed input to every key and request endpoint of a running stack.

Discovers the stack's keys from its liveliness graph (and :mod:`shared.topics`), sends each its share of
payloads generated from the key's message schema and broken on purpose (:mod:`deploy.fuzz.payloads`), and
counts what it sent per key and kind, and what the request endpoints answered. Bounded in count, time and
rate, and only ever aimed at a loopback endpoint::

    from deploy.fuzz import FuzzOptions, run_fuzz

    report = run_fuzz(FuzzOptions(connect=("tcp/127.0.0.1:7447",), namespace="robot1", messages=5000, seed=1))
    report.sent, report.as_dict()["keys"]["robot1/cmd_vel"]["kinds"]
"""

from deploy.fuzz.campaign import FuzzOptions, FuzzReport, KeyReport, check_loopback, fuzz_session, run_fuzz
from deploy.fuzz.payloads import Malformed, PayloadFactory
from deploy.fuzz.targets import Target

__all__ = [
    "FuzzOptions",
    "FuzzReport",
    "KeyReport",
    "Malformed",
    "PayloadFactory",
    "Target",
    "check_loopback",
    "fuzz_session",
    "run_fuzz",
]
