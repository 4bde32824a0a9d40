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

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pihyst.dynamics._bla import estimate_bla, periodic_records
from pihyst.dynamics._refine import refine as refined
from pihyst.dynamics._statespace import fsid, observability_bases
from pihyst.exceptions import InvalidArgumentError

DEFAULT_ORDERS = tuple(range(4, 65, 4))


@dataclass(frozen=True)
class OrderSelection:
    """Validation errors per candidate order and the chosen one, as
    :func:`fit_state_space` returns them with ``return_selection``.

    Parameters
    ----------
    orders : tuple of int
        The candidate orders.
    errors : tuple of float
        Each one's steady-state RMS simulation error on the validation records.
    chosen : int
        The order chosen.
    validation : tuple of int
        The indices of the records held back for validation.

    Examples
    --------
    >>> from pihyst.dynamics import OrderSelection
    >>> OrderSelection(orders=(1, 2), errors=(0.1, 0.1), chosen=1, validation=(2,)).chosen
    1
    """

    orders: tuple[int, ...]
    errors: tuple[float, ...]
    chosen: int
    validation: tuple[int, ...]


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


def fit_state_space(records: Iterable[tuple[Any, Any]], period: int, order: int | None = None,
                    *, orders: Sequence[int] = DEFAULT_ORDERS,
                    validation: Sequence[int] | None = None, discard: int = 1,
                    weighted: bool = False, q: int | None = None, tolerance: float = 0.01,
                    refine: bool = True, max_nfev: int = 30,
                    return_selection: bool = False) -> Any:
    """A stable MIMO :class:`~pihyst.dynamics.StateSpace` fitted to periodic multisine
    records (module notes).

    Parameters
    ----------
    records : iterable of (array_like, array_like)
        ``(u, y)`` pairs, u (N, m) and y (N, p) (or 1-D for one), N a multiple of
        ``period``.
    period : int
        Samples per period.
    order : int, optional
        The state dimension; None chooses it from ``orders`` by validation.
    orders : sequence of int
        The candidate orders.
    validation : sequence of int, optional
        Indices of the records held back to choose the order (default: the last
        third, leaving at least m to fit).
    discard : int
        Leading periods of each record that are the transient.
    weighted : bool
        Weight the B, D fit by the BLA's inverse standard deviation (off by default:
        with few records the variance estimate is too noisy to help).
    q : int, optional
        FSID block rows (default order + 1).
    tolerance : float
        The smallest order whose validation error is within this (relative) of the
        best is chosen.
    refine : bool
        Finish with a nonlinear least-squares fit on the BLA (kept only if it lowers
        the error there).
    max_nfev : int
        At most this many evaluations of that fit.
    return_selection : bool
        Return the order selection too.

    Returns
    -------
    StateSpace or (StateSpace, OrderSelection or None)
        The model; with ``return_selection``, also how its order was chosen (None
        when ``order`` was given).

    Raises
    ------
    InvalidArgumentError
        Records that are not whole periods, too few records to fit or choose the
        order, orders or validation indices that are not valid.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import StateSpace
    >>> plant = StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]])
    >>> def multisine(seed, t=np.arange(64), k=np.arange(1, 8)):
    ...     phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, k.size)
    ...     return 10 + np.cos(2 * np.pi * np.outer(t, k) / 32 + phase).sum(axis=1)
    >>> records = [(u, plant.predict(u)) for u in map(multisine, range(3))]
    >>> from pihyst.dynamics import fit_state_space
    >>> model, selection = fit_state_space(records, 32, orders=(1, 2), return_selection=True)
    >>> selection.chosen, np.round(model.dc_gain(), 6)
    (1, array([[2.]]))
    """
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
