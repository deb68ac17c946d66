"""Every message type the shared kit defines, registered before a tool decodes or builds messages.

Types register when their module is imported: the plain messages (:mod:`shared.messages`), the action
plumbing (:mod:`shared.action`) and each service's interfaces (every module of :mod:`shared.interfaces`).
"""

from __future__ import annotations

import importlib
import pkgutil
from functools import cache

from shared.schema import Message, registered_types

MESSAGE_MODULES = ("shared.messages", "shared.action")
INTERFACE_PACKAGE = "shared.interfaces"


@cache
def load_message_types() -> None:
    for name in MESSAGE_MODULES:
        importlib.import_module(name)
    package = importlib.import_module(INTERFACE_PACKAGE)
    for info in pkgutil.iter_modules(package.__path__):
        importlib.import_module(f"{INTERFACE_PACKAGE}.{info.name}")


def known_types() -> dict[str, type[Message]]:
    """Type name -> message class, for every type zendock defines."""
    load_message_types()
    return registered_types()
