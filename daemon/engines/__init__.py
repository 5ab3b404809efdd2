"""galton package."""
