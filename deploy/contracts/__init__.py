"""Contracts as documents (``zendock contract``, ``docs/contracts/``) and the conformance kit (``zendock conform``)."""
