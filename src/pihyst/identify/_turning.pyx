# cython: boundscheck=False, wraparound=False, language_level=3
"""Turning points of a signal in one pass over its samples, in C: the loop of
``pihyst._reference.turning_points_loop`` (its plain twin; the tests compare them)
with typed variables. On a 10^6-sample record of 3,400 reversals it takes a few
milliseconds, where a vectorized NumPy search took a Python step per reversal.

A phase rising from its start ends at the first sample t where the running maximum
exceeds v[t] by more than the tolerance; the maximum (the first sample reaching it) is a
turning point, and a falling phase starts at t (and the other way round). Before the
first reversal both running extremes are watched from sample 0 (a maximum first if both
trip at once); a turning point at sample 0 is not reported.
"""

import numpy as np


def turning_points(const double[::1] v, double tolerance):
    """[(index, +1 for a maximum / -1 for a minimum), ...] of ``v`` in time order."""
    cdef Py_ssize_t n = v.shape[0], t, hi_i = 0, lo_i = 0, count = 0
    cdef int direction = 0       # +1 rising (looking for a maximum), -1 falling, 0 unknown
    cdef double x
    index = np.empty(max(n, 1), dtype=np.intp)
    kind = np.empty(max(n, 1), dtype=np.int8)
    cdef Py_ssize_t[::1] index_v = index
    cdef signed char[::1] kind_v = kind
    with nogil:
        for t in range(1, n):
            x = v[t]
            if x > v[hi_i]:
                hi_i = t
            if x < v[lo_i]:
                lo_i = t
            if direction >= 0 and v[hi_i] - x > tolerance:
                if hi_i > 0:
                    index_v[count] = hi_i
                    kind_v[count] = 1
                    count += 1
                direction = -1
                lo_i = t
            elif direction <= 0 and x - v[lo_i] > tolerance:
                if lo_i > 0:
                    index_v[count] = lo_i
                    kind_v[count] = -1
                    count += 1
                direction = 1
                hi_i = t
    return list(zip(index[:count].tolist(), kind[:count].tolist()))
