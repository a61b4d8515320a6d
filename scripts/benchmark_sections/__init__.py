"""The sections of ``scripts/benchmark.py``, one module each; ``cases`` is the only one the others import."""
