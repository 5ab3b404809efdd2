"""The Python SDK: ``Client`` (``client.py``) with its operation families mixed in
(control, joints, perception, streams, worlds), the values its methods return, telemetry
streams and a loopback daemon for programs and tests (``embedded.py``).

Programs import the public names from ``galton.client``; this package imports nothing, so
that a module needing one of its parts does not load the rest.
"""
