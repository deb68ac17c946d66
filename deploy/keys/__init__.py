"""``zendock keys``: inspect and drive the keys services use, as ``ros2 topic`` does for topics.

One module per verb (:mod:`listing`, :mod:`echo`, :mod:`hz`, :mod:`bw`, :mod:`delay`, :mod:`info`,
:mod:`pub`) over a few shared pieces: :mod:`connection` (endpoints, namespace, a session that fails fast),
:mod:`graph` (who publishes what, from liveliness tokens and the router's admin space), :mod:`decoding`
(payload to a printable tree, never raising), :mod:`render` (YAML-like, CSV and hex output),
:mod:`stats` (rate, bandwidth and delay windows), :mod:`sampling` (subscriptions feeding the windows) and
:mod:`values` (YAML merged over a type's defaults and validated). The argparse layer lives in
:mod:`deploy.commands.keys`; every verb takes an output stream so tests read what a user would see.
"""
