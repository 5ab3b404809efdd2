"""No state kept in memory on PyBullet: ``save_state`` stays the base Engine's (None), so
every snapshot to a slot takes the portable path. PyBullet's own ``saveState`` and
``restoreState`` go on bit for bit from a state with contacts, but a ``restoreState`` keeps
the contact manifolds the world holds at the restore that the saved state lacks: a slot
restored twice gave two different runs (docs/PERFORMANCE.md, "Known limits"; issue 51). A
kept state would live here."""

KEPT_IN_MEMORY = False  # the engine keeps no state of its own: snapshots are its portable blob
