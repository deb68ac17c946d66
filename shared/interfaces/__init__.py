"""Request/response and action interfaces of zendock's services, one module per service.

Each module holds the message pairs (``<Name>_Request`` / ``<Name>_Response`` as in ROS 2's generated
types) and the :class:`~shared.node.ServiceType` (or action type) constants servers and clients share:
:mod:`~shared.interfaces.battery`, :mod:`~shared.interfaces.docking`, :mod:`~shared.interfaces.navigation`,
:mod:`~shared.interfaces.simulator`, and :mod:`~shared.interfaces.parameters`, which every node answers.
Import from the module itself.
"""
