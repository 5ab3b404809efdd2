"""The Galton-board benchmark driven through the bridge: build, release, settle, score."""
