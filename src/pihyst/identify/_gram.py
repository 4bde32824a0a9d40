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


# Bank.gram_segments' codes of the roles of a segment
ROLE_CODES = {"settle": 0, "fit": 1, "held_back": 2}


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
    cuts = set(int(i) for i in rows_at)
    bank = model._new_bank(np.asarray(initial_state, dtype=float))
    # chunks: the segments, cut after every index whose row is wanted (the state after
    # sample t is row t); the C core sums a run of chunks in one call (a record of
    # thousands of cycles spent 20 us of Python on each), the bank's state advancing
    chunks = [(a, z, ROLE_CODES[role]) for start, stop, role in segments
              for a, z in _pieces(start, stop, cuts)]
    totals, rows, run = None, {}, []
    for chunk in chunks:
        run.append(chunk)
        if chunk[1] - 1 in cuts or chunk is chunks[-1]:
            sums = bank.gram_segments(u, d, *zip(*run))
            totals = sums if totals is None else tuple(
                tuple(x + y for x, y in zip(mine, theirs)) for mine, theirs in zip(totals, sums))
            run = []
            if chunk[1] - 1 in cuts:
                state = bank.state
                rows[chunk[1] - 1] = np.r_[state, 1.0] if offset else state
    if totals is None:
        k = model.n_operators
        totals = ((np.zeros((k, k)), np.zeros(k), np.zeros(k), 0.0, 0.0, 0),) * 2
    return {"fit": _gram_of(totals[0], offset), "held_back": _gram_of(totals[1], offset)}, rows


def _pieces(start, stop, cuts):
    """[start, stop) cut after every index of ``cuts`` inside it."""
    bounds = [start] + sorted(c + 1 for c in cuts if start <= c < stop - 1) + [stop]
    return list(zip(bounds[:-1], bounds[1:]))


def _gram_of(acc, offset):
    """The Gram of one role's sums, with the constant column when ``offset``."""
    G, b, s, d_sum, dd, n = acc
    if offset:
        G = np.block([[G, s[:, None]], [s[None, :], np.array([[float(n)]])]])
        b = np.r_[b, d_sum]
    return Gram(G, b, dd, n)
