"""What the daemon does for each operation: the handler table (handlers.py) and the
handlers by family."""
