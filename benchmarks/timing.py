"""Timing helpers shared by the benchmark scripts (run as `python benchmarks/bench_*.py`)."""

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


def best_cpu_time(fn, repeats):
    """Best CPU time of this thread over ``repeats`` calls of ``fn``, in seconds: on a
    machine shared with other jobs the wall time counts their share of the cores too
    (the C loops run in this thread with the GIL released; BLAS single-threaded)."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.thread_time()
        fn()
        best = min(best, time.thread_time() - t0)
    return best
