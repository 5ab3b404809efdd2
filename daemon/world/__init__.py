"""The scene graph over one engine, its joints, wrenches, cameras, snapshot codec, slots
and checkpoints."""
