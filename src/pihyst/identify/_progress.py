"""Progress of a fit: each step's end and its time, for the command line to print on a
terminal (``fit(..., progress=print)``)."""

import time


class Steps:
    """Reports each step's end, with the seconds since the last one, to ``progress``
    (a callable taking one line of text; None: nothing)."""

    def __init__(self, progress):
        self.progress, self.t0 = progress, time.perf_counter()

    def done(self, what):
        if self.progress is not None:
            now = time.perf_counter()
            self.progress(f"{what} ({now - self.t0:.2f} s)")
            self.t0 = now
