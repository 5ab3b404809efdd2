"""How a client reaches daemons: the ``Transport`` interface and its Zenoh side
(``base.py``, ``session.py``, ``discovery.py``), ZeroMQ (``zmq.py``), and who the client
is to a secured daemon (``credentials.py``, ``zmq_keys.py``, ``access.py``).

Imports nothing itself: Zenoh and ZeroMQ load with the module that needs them.
"""
