"""MIMO state-space models from periodic multisine records: the BLA
(:mod:`._bla`), frequency-domain subspace identification (:mod:`._statespace`), the order
chosen by validation on held-back records (docs/theory/hammerstein.md).

Order selection: the records are split into a fitting part (all but the held-back ones,
at least m of them) and a validation part. For each candidate order n the model fitted
on the fitting part's BLA is simulated from rest on each validation record, and its
error is measured over the periods after the first ``discard`` (steady state):

    e(n) = sqrt( mean_{validation records, t >= discard N, j} (y_j[t] - yhat_j[t])^2 ).

The smallest order whose e(n) is within ``tolerance`` (relative) of the smallest one is
refitted on all the records (parsimony: orders above the true one fit as well without
noise, and only noise with it), then, with ``refine``, refined by nonlinear least squares
on the BLA of all the records (:mod:`._refine`).
"""

from dataclasses import dataclass

import numpy as np

from pihyst.dynamics._bla import estimate_bla, periodic_records
from pihyst.dynamics._refine import refine as refined
from pihyst.dynamics._statespace import fsid, observability_bases
from pihyst.exceptions import InvalidArgumentError

DEFAULT_ORDERS = tuple(range(4, 65, 4))


@dataclass(frozen=True)
class OrderSelection:
    """Validation errors per candidate order and the chosen one."""

    orders: tuple
    errors: tuple
    chosen: int
    validation: tuple


def bla_weights(frf, weighted):
    """1 / standard deviation of each BLA element (L, p, m), or None (unweighted, or
    no variance estimate with only m records)."""
    if not weighted or frf.variance is None:
        return None
    sd = np.sqrt(frf.variance)
    # a line with a (near-)zero variance estimate must not dominate: floor at 1e-3 of
    # the median standard deviation of its channel
    floor = 1e-3 * np.median(sd, axis=0, keepdims=True) + 1e-300
    return 1.0 / np.maximum(sd, floor)


def steady_state_rms(model, records, period, discard):
    """RMS simulation error over all outputs and the periods after ``discard``."""
    sq, count = 0.0, 0
    for u, y in records:
        start = min(discard, u.shape[0] // period - 1) * period
        e = model.predict(u)[start:] - y[start:]
        sq += float(np.sum(e * e))
        count += e.size
    return np.sqrt(sq / count)


def fit_state_space(records, period, order=None, *, orders=DEFAULT_ORDERS, validation=None,
                    discard=1, weighted=False, q=None, tolerance=0.01, refine=True,
                    max_nfev=30, return_selection=False):
    """A stable MIMO :class:`~pihyst.dynamics.StateSpace` fitted to periodic multisine
    records (list of (u (N, m), y (N, p)), N a multiple of ``period``; the first
    ``discard`` periods of each are the transient).

    ``order``: the state dimension; None chooses it from ``orders`` by validation on
    the records with indices ``validation`` (default: the last third, leaving at least
    m to fit), the smallest within ``tolerance`` of the best. ``weighted``: weight
    the B, D fit by the BLA's inverse standard deviation (off by default: with few
    records the variance estimate is too noisy to help). ``q``: FSID block rows
    (default order + 1). ``refine``: finish with the nonlinear least-squares fit of
    :mod:`pihyst.dynamics._refine` (at most ``max_nfev`` evaluations; kept only if it
    lowers the error on the BLA). With ``return_selection`` returns (model,
    :class:`OrderSelection` or None)."""
    recs = periodic_records(records, period)
    R, m = len(recs), recs[0][0].shape[1]
    selection = None
    if order is None:
        orders = tuple(int(n) for n in orders)
        if not orders or min(orders) < 1:
            raise InvalidArgumentError(f"orders must be positive integers, not {orders!r}")
        if validation is None:
            held = max(1, R // 3)
            if R - held < m:
                raise InvalidArgumentError(f"choosing the order needs more than {m} records "
                                           f"({R} given): give order=")
            validation = tuple(range(R - held, R))
        validation = tuple(int(v) for v in validation)
        if not validation or min(validation) < 0 or max(validation) >= R:
            raise InvalidArgumentError(f"validation indices {validation} are not records "
                                       f"0..{R - 1}")
        fitting = [recs[i] for i in range(R) if i not in validation]
        if len(fitting) < m:
            raise InvalidArgumentError(f"{len(fitting)} records left to fit; {m} inputs "
                                       f"need at least {m}")
        held_out = [recs[i] for i in validation]
        frf = estimate_bla(fitting, period, discard=discard)
        w = bla_weights(frf, weighted)
        rows = {n: n + 1 if q is None else int(q) for n in orders}
        bases = observability_bases(frf.omega, frf.G, sorted(set(rows.values())))
        errors = []
        for n in orders:
            model = fsid(frf.omega, frf.G, n, q=rows[n], weight=w, basis=bases[rows[n]])
            errors.append(steady_state_rms(model, held_out, period, discard))
        # an absolute floor for noiseless data, whose errors are at rounding level
        floor = 1e-9 * np.sqrt(np.mean(np.vstack([y for _, y in held_out]) ** 2))
        good = np.flatnonzero(np.array(errors) <= (1 + tolerance) * min(errors) + floor)
        order = min(orders[i] for i in good)
        selection = OrderSelection(orders=orders, errors=tuple(errors), chosen=order,
                                   validation=validation)
    frf = estimate_bla(recs, period, discard=discard)
    w = bla_weights(frf, weighted)
    model = fsid(frf.omega, frf.G, order, q=q, weight=w)
    if refine:
        model = refined(model, frf.omega, frf.G, w, max_nfev=max_nfev)
    return (model, selection) if return_selection else model
