"""``galton-client view``: a live 3-D view of a daemon's world in the browser (viser), with
side worlds as translucent ghosts, and bench trials replayed in the same page.

Installed by the ``[view]`` extra (viser), so that a robot's daemon does not carry it. The
page is fed by a state stream (docs/protocol.md, "stream_states"): opening it reads the
world and never changes it.
"""
