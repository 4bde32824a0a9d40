"""Discrete linear dynamics: MISO output-error models fitted by least squares.

For one output y and input columns v_c (c = 1..C) the model is

    A(q) y[t] = sum_c B_c(q) v_c[t],
    A(q) = 1 + a_1 q^-1 + ... + a_na q^-na,  B_c(q) = b_c0 + b_c1 q^-1 + ... + b_c,nb-1 q^-(nb-1)

(q^-1 the delay). The ARX estimate minimizes the equation error A y - sum B_c v_c by
linear least squares; the Steiglitz-McBride iterations then refit the same problem on
y and v prefiltered by 1 / A of the previous estimate, which moves the estimate towards
the output-error (simulation-error) optimum. Poles outside the unit circle are reflected
inside (|p| -> 1/|p|, the same amplitude response up to a gain) so the model is stable.
Several experiments (records) are fitted together; the first max(na, nb) samples of
each only start the regressors.
"""

import numpy as np


def _signal():
    # lazy: importing scipy.signal takes about 0.4 s
    import scipy.signal
    return scipy.signal


def lagged(x, n, start=0):
    """[x[t - start], x[t - start - 1], ..., x[t - start - n + 1]] for every t (zeros
    before the record)."""
    out = np.zeros((x.size, n))
    for k in range(n):
        s = start + k
        out[s:, k] = x[:x.size - s] if s else x
    return out


def stabilized(a):
    """A(q) with its roots outside the unit circle reflected inside."""
    roots = np.roots(a)
    big = np.abs(roots) >= 1.0
    if not np.any(big):
        return np.asarray(a, dtype=float)
    roots[big] = 1.0 / np.conj(roots[big])
    return np.real(np.poly(roots))


def _design(records, na, nb, a_filter):
    sig = _signal()
    rows, target = [], []
    skip = max(na, nb)
    for v, y in records:
        if a_filter is not None:
            y = sig.lfilter([1.0], a_filter, y)
            v = sig.lfilter([1.0], a_filter, v, axis=0)
        cols = [-lagged(y, na, 1)] + [lagged(v[:, c], nb) for c in range(v.shape[1])]
        rows.append(np.hstack(cols)[skip:])
        target.append(y[skip:])
    return np.vstack(rows), np.concatenate(target)


def fit_oe(records, na, nb, iterations=5, ridge=1e-9):
    """(A, B) of the model of the module notes; B has one row per input column.

    ``records``: list of (v, y) with v of shape (N, C) and y of length N.
    """
    a_prev = None
    C = records[0][0].shape[1]
    for _ in range(iterations + 1):
        X, t = _design(records, na, nb, a_prev)
        scale = np.sqrt(np.mean(X * X, axis=0)) + 1e-300
        G = (X / scale).T @ (X / scale)
        G[np.diag_indices_from(G)] += ridge * np.trace(G) / G.shape[0]
        theta = np.linalg.solve(G, (X / scale).T @ t) / scale
        a = stabilized(np.r_[1.0, theta[:na]])
        b = theta[na:].reshape(C, nb)
        a_prev = a
    return a, b


def simulate(a, b, v):
    """y = sum_c B_c / A v_c from rest."""
    sig = _signal()
    return sum(sig.lfilter(b[c], a, v[:, c]) for c in range(v.shape[1]))
