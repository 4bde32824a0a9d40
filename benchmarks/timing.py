"""Timing helper shared by the benchmark scripts (run as `python benchmarks/bench_*.py`)."""

import time


def best_time(fn, repeats):
    """Best wall time of ``repeats`` calls of ``fn``, in seconds: the least disturbed run
    on a shared machine."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best
