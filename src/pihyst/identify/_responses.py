"""What the record's input alone determines, computed once per fit and reused by every
later step (the identification issue's "compute once"): the fit of a record with sample
times fits the same input again with the creep estimate removed from the output, and
the responses that do not depend on the output are the same there.

:class:`Responses` keeps them by a key of the input they were computed on (a digest of
its bytes, so two equal inputs share an entry and a different one never does). Today
it holds the Bouc-Wen shape grid's z trajectories (identify/_boucwen.py), the costliest
output-independent part of a fit.
"""

import hashlib

import numpy as np


def digest(*arrays):
    """A key of the arrays' values (their bytes, shapes and dtypes)."""
    h = hashlib.blake2b(digest_size=16)
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(str((a.dtype.str, a.shape)).encode())
        h.update(a.tobytes())
    return h.hexdigest()


class Responses:
    """Output-independent results of one fit, by key; ``get(key, compute)`` computes
    an entry once."""

    def __init__(self):
        self._entries = {}

    def get(self, key, compute):
        if key not in self._entries:
            self._entries[key] = compute()
        return self._entries[key]

    def __len__(self):
        return len(self._entries)
