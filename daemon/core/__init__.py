"""The physics thread: the loop, its calls and jobs, pacing, limits, parameters, status."""
