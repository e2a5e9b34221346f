"""Random inputs for a C twin of ego._native against its Python reference (the learning
controllers' steps): the same values for both, with a non-finite one now and then and a
moment to replace a weight array between steps."""

import numpy as np


def twin_inputs(rng, width: int, steps: int, scale: float, trial: int, inject_at: int, replace_at: int):
    """``steps`` vectors of ``width`` normal values times ``scale``, yielded as (values,
    replace): on every 4th trial one value is NaN or infinite at step ``inject_at``; replace
    is True at step ``replace_at`` of trial 1 (the test swaps a weight array then)."""
    for k in range(steps):
        v = rng.standard_normal(width) * scale
        if trial % 4 == 0 and k == inject_at:
            v[rng.integers(width)] = rng.choice([np.nan, np.inf, -np.inf])
        yield v, trial == 1 and k == replace_at
