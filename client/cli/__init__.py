"""The ``galton-client`` command: ``console.py`` is its entry, ``common.py`` the helpers
every command shares, and one module per command group.

Imports nothing itself, so that ``galton-client --version`` stays fast.
"""
