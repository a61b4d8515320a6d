"""One module per paper; each provides ``fill(ctx, **params) -> Patch``, ``PARAMS`` and ``RINGS``."""
