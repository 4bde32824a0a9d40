"""Normal equations of a record, accumulated once over all candidate operators.

For a bank of K operators (columns f_k) plus an optional constant column (the fitted
offset), and one part of the record (fitted or held-back samples),

    G = A^T A,  b = A^T d,  dd = d^T d,  n = len(d),     A = [f_0 ... f_{K-1} (1)]

and the squared error of any weights x on that part is, without touching A again,

    SSE(x) = ||A x - d||^2 = dd - 2 b^T x + x^T G x.                        (1)

A subset of operators uses the submatrix of its columns, so every subset of a candidate
grid is judged from one pass over the data. The operator outputs come from the C core
(``Bank.gram``), chunk by chunk, so memory does not grow with the record.
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Gram:
    """Normal equations of one part of a record (see module docstring)."""

    G: np.ndarray
    b: np.ndarray
    dd: float
    n: int

    def sse(self, cols, x):
        """Squared error of weights ``x`` on columns ``cols``, by (1)."""
        G = self.G[np.ix_(cols, cols)]
        return max(0.0, float(self.dd - 2.0 * self.b[cols] @ x + x @ G @ x))

    def rms(self, cols, x):
        return float(np.sqrt(self.sse(cols, x) / self.n))

    def __add__(self, other):
        return Gram(self.G + other.G, self.b + other.b, self.dd + other.dd,
                    self.n + other.n)


def _empty(k):
    return Gram(np.zeros((k, k)), np.zeros(k), 0.0, 0)


def accumulate(model, u, d, segments, initial_state, *, offset=True, rows_at=()):
    """Normal equations of ``model``'s operators over the parts of a record.

    Parameters
    ----------
    model : PIModel
        Its operators (weights ignored) give the columns.
    u, d : ndarray
        Input and measured output of the whole record.
    segments : list of (start, stop, role)
        Consecutive slices covering the record in order; ``role`` is ``"settle"``
        (operators run, samples not used), ``"fit"`` or ``"held_back"``.
    initial_state : ndarray
        Operator state before the first sample.
    offset : bool
        Append a constant column (a fitted offset).
    rows_at : iterable of int
        Sample indices whose row of A (operator outputs, and 1) is wanted, e.g. for an
        equality constraint through a measured point.

    Returns
    -------
    parts : dict role -> Gram
        For ``"fit"`` and ``"held_back"`` (empty if no segment has that role).
    rows : dict index -> ndarray
    """
    k = model.n_operators
    # the sums of each role, kept apart until the end: a record of many short cycles
    # (10^4 segments) would otherwise spend its time building a block matrix per segment
    sums = {role: [np.zeros((k, k)), np.zeros(k), np.zeros(k), 0.0, 0.0, 0]
            for role in ("fit", "held_back")}
    rows = {}
    cuts = sorted(set(int(i) for i in rows_at))
    # The bank's state advances over each chunk in turn; chunks are the segments, cut
    # after every index whose row is wanted (the state after sample t is row t).
    bank = model._new_bank(np.asarray(initial_state, dtype=float))
    for start, stop, role in segments:
        bounds = [start] + [c + 1 for c in cuts if start <= c < stop - 1] + [stop]
        for a, z in zip(bounds[:-1], bounds[1:]):
            ua, da = u[a:z], d[a:z]
            if role == "settle":
                bank.run(ua)
            else:
                G, b, s = bank.gram(ua, da)
                acc = sums[role]
                acc[0] = acc[0] + G
                acc[1] = acc[1] + b
                acc[2] = acc[2] + s
                acc[3] = acc[3] + da.sum()
                acc[4] = acc[4] + float(da @ da)
                acc[5] += z - a
            if z - 1 in cuts:
                state = bank.state
                rows[z - 1] = np.r_[state, 1.0] if offset else state
    return {role: _gram_of(acc, offset) for role, acc in sums.items()}, rows


def _gram_of(acc, offset):
    """The Gram of one role's sums, with the constant column when ``offset``."""
    G, b, s, d_sum, dd, n = acc
    if offset:
        G = np.block([[G, s[:, None]], [s[None, :], np.array([[float(n)]])]])
        b = np.r_[b, d_sum]
    return Gram(G, b, dd, n)
