"""``galton-client check RESULTS``: does a bench run meet the fidelity targets?"""

from __future__ import annotations
