"""Hammerstein models: pihyst's static hysteresis followed by discrete linear dynamics
(docs/theory/hammerstein.md).

For inputs u_i (i = 1..m) and outputs y_j (j = 1..p),

    h_i = H_i(u_i) = sum_k w_ik f_ik(u_i)        (a classical PI model per input)
    A_j(q) y_j[t] = sum_i B_ji(q) h_i[t]          (one common denominator per output)

Identification (:func:`fit_hammerstein`), for fixed play thresholds r_ik:

1. start from the linear model: w_i = (1, 0, ..., 0), the threshold-0 operator being
   u_i itself, and A_j, B_ji fitted on h_i = u_i by least squares (ARX, then
   Steiglitz-McBride iterations towards the output-error fit, :mod:`._linear`);
2. alternate: with A and B fixed, the simulated output y_j = sum_ik w_ik (B_ji / A_j)
   f_ik is linear in w, fitted by bounded least squares (w >= 0, so each H_i is
   monotone and has pihyst's exact inverse; sum_k w_ik = 1, the gain sits in B); with w
   fixed, A_j and B_ji are refitted on the new hysteresis outputs h_i. A step is kept
   only while the simulation error on the records decreases, so the Hammerstein model
   never fits the records worse than the linear model it starts from.

The linear-only reference (:func:`fit_linear`) is the same linear fit on u itself.
"""

import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst.dynamics._linear import fit_oe, fit_oe_periodic, response, simulate
from pihyst.exceptions import InvalidArgumentError, InvalidModelError
from pihyst.model import ClassicalPI

FAMILY = "hammerstein"


def _lfilter():
    from scipy.signal import lfilter
    return lfilter


def _operators(model, u):
    # operator outputs from the zero state (a record's first period settles them)
    return model.operators(u, initial_state=np.zeros(model.n_operators))


@dataclass(frozen=True)
class HammersteinModel:
    """Static hysteresis per input followed by linear dynamics per output (module notes).

    Parameters
    ----------
    hysteresis : tuple of PIModel
        One model per input, with an exact inverse (ClassicalPI from
        :func:`fit_hammerstein`, any family from :func:`fit_dynamics`).
    a : tuple of array_like
        Per output j, A_j(q^-1) = [1, a_1, ...].
    b : tuple of array_like
        Per output j, B_ji(q^-1) as one row per input (m, nb).
    trusted_from : float
        The lowest frequency (cycles per sample) at which the dynamics were measured
        (:func:`fit_dynamics`: the slowest fast record's fundamental); 0: trusted at
        every frequency. The compensators apply none of the dynamics' correction below
        it and fade it in over the two octaves above (:func:`trust_weight`); it needs
        unit static gain.
    order_trusted_from : tuple of float
        Per harmonic order k = 1, 2, ... of a periodic trajectory, the frequency
        (cycles per sample) from which the correction applies on the period's k-th
        harmonic (:func:`fit_dynamics`: where the identification's records, each held
        back, showed it to bring the output closer than the static model alone; 0.5:
        never), faded in over the two octaves above as ``trusted_from``; orders past
        its end get no correction. Empty (the default): ``trusted_from`` alone, on
        every harmonic. Used by the periodic compensation only.
    static_offset : float or None
        The static model's mean error (output units) on the identification's slow
        record, measured minus modelled (:func:`fit_dynamics`). With it the periodic
        compensation moves the voltage's mean only as far as that error proves safe
        (:func:`pihyst.dynamics.held_mean`); None (the default): the voltage's mean
        as the hysteresis inverse gives it.

    Examples
    --------
    >>> from pihyst import ClassicalPI
    >>> from pihyst.dynamics import HammersteinModel
    >>> model = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
    ...                          a=([1.0, -0.5],), b=([[0.5]],))
    >>> model.n_inputs, model.n_outputs
    (1, 1)
    """

    hysteresis: tuple[Any, ...]
    a: tuple[Any, ...]
    b: tuple[Any, ...]
    trusted_from: float = 0.0
    order_trusted_from: tuple[float, ...] = ()
    static_offset: float | None = None

    family = FAMILY

    @property
    def n_inputs(self):
        return len(self.hysteresis)

    @property
    def n_outputs(self):
        return len(self.a)

    def hysteresis_output(self, u: ArrayLike) -> NDArray[np.float64]:
        """h_i = H_i(u_i) from each hysteresis model's initial state.

        Parameters
        ----------
        u : array_like
            (N, m) inputs, or (N,) for one input.

        Returns
        -------
        ndarray
            (N, m) the hysteresis outputs.

        Examples
        --------
        >>> from pihyst import ClassicalPI
        >>> from pihyst.dynamics import HammersteinModel
        >>> model = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                          a=([1.0, -0.5],), b=([[0.5]],))
        >>> model.hysteresis_output([0.0, 4.0, 0.0]).ravel().tolist()
        [0.0, 5.0, 1.0]
        """
        inputs = np.atleast_2d(np.asarray(u, dtype=float).T).T
        return np.column_stack([H.predict(inputs[:, i])
                                for i, H in enumerate(self.hysteresis)])

    def predict(self, u: ArrayLike) -> NDArray[np.float64]:
        """The outputs for inputs ``u``, the dynamics simulated from rest.

        Parameters
        ----------
        u : array_like
            (N, m) inputs, or (N,) for one input.

        Returns
        -------
        ndarray
            (N, p) outputs.

        Examples
        --------
        >>> from pihyst import ClassicalPI
        >>> from pihyst.dynamics import HammersteinModel
        >>> model = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                          a=([1.0, -0.5],), b=([[0.5]],))
        >>> model.predict([1.0, 1.0, 1.0]).ravel().tolist()
        [0.5, 0.75, 0.875]
        """
        h = self.hysteresis_output(u)
        return np.column_stack([simulate(self.a[j], np.asarray(self.b[j]), h)
                                for j in range(self.n_outputs)])

    def static_gain(self) -> NDArray[np.float64]:
        """B_ji(1) / A_j(1), the dynamics' gain per output and input.

        Returns
        -------
        ndarray
            (p, m) the gains.

        Examples
        --------
        >>> from pihyst import ClassicalPI
        >>> from pihyst.dynamics import HammersteinModel
        >>> model = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                          a=([1.0, -0.5],), b=([[0.5]],))
        >>> model.static_gain()
        array([[1.]])
        """
        return np.array([np.sum(np.atleast_2d(b), axis=1) / np.sum(a)
                         for a, b in zip(self.a, self.b)])

    def to_dict(self) -> dict[str, Any]:
        """The model as JSON values (its file's schema, :func:`load_hammerstein`).

        Returns
        -------
        dict
            ``family``, ``hysteresis`` (each model's dict), ``a`` and ``b``; and
            ``trusted_from`` when it is not 0, ``order_trusted_from`` when it is
            not empty, ``static_offset`` when it is not None.

        Examples
        --------
        >>> from pihyst import ClassicalPI
        >>> from pihyst.dynamics import HammersteinModel
        >>> model = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                          a=([1.0, -0.5],), b=([[0.5]],))
        >>> d = model.to_dict()
        >>> d["a"], d["b"]
        ([[1.0, -0.5]], [[[0.5]]])
        """
        d: dict[str, Any] = {"family": FAMILY,
                             "hysteresis": [H.to_dict() for H in self.hysteresis],
                             "a": [np.asarray(a).tolist() for a in self.a],
                             "b": [np.atleast_2d(b).tolist() for b in self.b]}
        if self.trusted_from:
            d["trusted_from"] = float(self.trusted_from)
        if self.order_trusted_from:
            d["order_trusted_from"] = [float(t) for t in self.order_trusted_from]
        if self.static_offset is not None:
            d["static_offset"] = float(self.static_offset)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any], source: str = "model") -> "HammersteinModel":
        """The model of a dict of :meth:`to_dict`'s keys.

        Parameters
        ----------
        d : dict
            ``family`` ("hammerstein"), ``hysteresis``, ``a`` and ``b``; optionally
            ``trusted_from`` (cycles per sample, 0 <= it < 0.5) and
            ``order_trusted_from`` (a list of them, each in [0, 0.5]) and
            ``static_offset`` (a finite number).
        source : str
            What the dict came from, for the messages.

        Returns
        -------
        HammersteinModel
            The model.

        Raises
        ------
        InvalidModelError
            A broken dict, named by ``source`` and the key (unstable dynamics among
            them).

        Examples
        --------
        >>> from pihyst import ClassicalPI
        >>> from pihyst.dynamics import HammersteinModel
        >>> model = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                          a=([1.0, -0.5],), b=([[0.5]],))
        >>> HammersteinModel.from_dict(model.to_dict()).static_gain()
        array([[1.]])
        """
        from pihyst.model import PIModel
        if not isinstance(d, dict) or d.get("family") != FAMILY:
            family = d.get("family") if isinstance(d, dict) else None
            raise InvalidModelError(f"{source}: key 'family' must be {FAMILY!r}; got "
                                    f"{family!r:.40}")
        for key in ("hysteresis", "a", "b"):
            if not isinstance(d.get(key), list) or not d[key]:
                raise InvalidModelError(f"{source}: key {key!r} must be a non-empty list")
        hysteresis = tuple(PIModel.from_dict(h, f"{source}: hysteresis[{i}]")
                           if isinstance(h, dict) else _bad(source, f"hysteresis[{i}]",
                                                            "an object")
                           for i, h in enumerate(d["hysteresis"]))
        m = len(hysteresis)
        if len(d["a"]) != len(d["b"]):
            raise InvalidModelError(f"{source}: 'a' and 'b' need one entry per output, got "
                                    f"{len(d['a'])} and {len(d['b'])}")
        a, b = [], []
        for j, (aj, bj) in enumerate(zip(d["a"], d["b"])):
            aj = _finite_array(aj, source, f"a[{j}]", 1)
            if aj[0] != 1.0:
                raise InvalidModelError(f"{source}: a[{j}] must start with 1 (A(q) = 1 + "
                                        f"a_1 q^-1 + ...), got {aj[0]:g}")
            if np.any(np.abs(np.roots(aj)) >= 1.0):
                raise InvalidModelError(f"{source}: a[{j}] has roots on or outside the unit "
                                        f"circle (unstable dynamics)")
            bj = _finite_array(bj, source, f"b[{j}]", 2)
            if bj.shape[0] != m:
                raise InvalidModelError(f"{source}: b[{j}] needs one row per input ({m}), "
                                        f"got {bj.shape[0]}")
            a.append(aj)
            b.append(bj)
        trusted = d.get("trusted_from", 0.0)
        if (isinstance(trusted, bool) or not isinstance(trusted, (int, float))
                or not 0.0 <= trusted < 0.5):
            raise InvalidModelError(f"{source}: key 'trusted_from' must be a number of "
                                    f"cycles per sample in [0, 0.5), got {trusted!r:.40}")
        orders = d.get("order_trusted_from", [])
        if not isinstance(orders, list) or not all(
                isinstance(t, (int, float)) and not isinstance(t, bool) and 0.0 <= t <= 0.5
                for t in orders):
            raise InvalidModelError(f"{source}: key 'order_trusted_from' must be a list of "
                                    f"numbers of cycles per sample in [0, 0.5], got "
                                    f"{orders!r:.40}")
        offset = d.get("static_offset")
        if offset is not None and (isinstance(offset, bool) or not isinstance(offset, (int, float))
                                   or not np.isfinite(offset)):
            raise InvalidModelError(f"{source}: key 'static_offset' must be a finite number, "
                                    f"got {offset!r:.40}")
        return cls(hysteresis=hysteresis, a=tuple(a), b=tuple(b), trusted_from=float(trusted),
                   order_trusted_from=tuple(float(t) for t in orders),
                   static_offset=None if offset is None else float(offset))

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the model as JSON to ``path`` (the file appears only once complete).

        Parameters
        ----------
        path : str or os.PathLike
            The file to write.

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.dynamics import load_hammerstein
        >>> from pihyst import ClassicalPI
        >>> from pihyst.dynamics import HammersteinModel
        >>> model = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                          a=([1.0, -0.5],), b=([[0.5]],))
        >>> path = os.path.join(tempfile.mkdtemp(), "hammerstein.json")
        >>> model.save(path)
        >>> load_hammerstein(path).a[0].tolist()
        [1.0, -0.5]
        """
        import json

        from pihyst._atomic import write_atomically
        write_atomically(path, json.dumps(self.to_dict(), indent=2) + "\n")


def _bad(source, key, what):
    raise InvalidModelError(f"{source}: {key} must be {what}")


def _finite_array(value, source, key, ndim):
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        _bad(source, key, f"a {'list' if ndim == 1 else 'list of lists'} of numbers")
    if ndim == 2 and arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != ndim or arr.size == 0 or not np.all(np.isfinite(arr)):
        _bad(source, key, f"a non-empty {'list' if ndim == 1 else 'list of lists'} of "
                          f"finite numbers")
    return arr


def _as_records(records):
    out = []
    for u, y in records:
        u = np.atleast_2d(np.asarray(u, dtype=float).T).T
        y = np.atleast_2d(np.asarray(y, dtype=float).T).T
        if u.shape[0] != y.shape[0]:
            raise InvalidArgumentError(f"record {len(out)}: {u.shape[0]} input samples but "
                                       f"{y.shape[0]} output samples (each record needs as "
                                       f"many of both)")
        out.append((u, y))
    return out


def default_thresholds(u: ArrayLike, n_operators: int = 4) -> NDArray[np.float64]:
    """Thresholds 0, ..., about the input's half span: equally spaced on [0, S/2).

    Parameters
    ----------
    u : array_like
        The input; S is its span (max - min).
    n_operators : int
        How many thresholds.

    Returns
    -------
    ndarray
        (n_operators,) thresholds, V.

    Examples
    --------
    >>> from pihyst.dynamics import default_thresholds
    >>> default_thresholds([0.0, 10.0]).tolist()
    [0.0, 1.25, 2.5, 3.75]
    """
    span = float(np.ptp(u))
    return np.arange(n_operators) * (span / 2) / n_operators


def fit_linear(records: Iterable[tuple[ArrayLike, ArrayLike]], na: int, nb: int,
               iterations: int = 5, period: int | None = None
               ) -> tuple[tuple[NDArray[np.float64], ...], tuple[NDArray[np.float64], ...]]:
    """Linear-only MIMO model of the same structure: A_j y_j = sum_i B_ji u_i.

    Parameters
    ----------
    records : iterable of (array_like, array_like)
        ``(u, y)`` pairs, u (N, m) and y (N, p) (or 1-D for one).
    na, nb : int
        Orders of A (its coefficients after the leading 1) and B (coefficients).
    iterations : int
        Steiglitz-McBride iterations towards the output-error fit.
    period : int, optional
        The records are periodic with this many samples per period and in steady
        state over their last period; the fit is then the frequency-domain
        output-error fit of that period.

    Returns
    -------
    a : tuple of ndarray
        Per output, A_j = [1, a_1, ..., a_na].
    b : tuple of ndarray
        Per output, B_ji as (m, nb).

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst import ClassicalPI
    >>> from pihyst.dynamics import HammersteinModel, fit_hammerstein, fit_linear, predict_linear
    >>> true = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
    ...                         a=([1.0, -0.5],), b=([[0.5]],))
    >>> t = np.arange(400)
    >>> u = 5 + 5 * np.sin(2 * np.pi * t / 100) * np.sin(2 * np.pi * t / 400)
    >>> y = true.predict(u)
    >>> a, b = fit_linear([(u, y)], 1, 1)
    >>> a[0].shape, b[0].shape
    ((2,), (1, 1))
    """
    recs = _as_records(records)
    a, b = [], []
    for j in range(recs[0][1].shape[1]):
        if period:
            spectra = [(np.fft.rfft(u[-period:], axis=0), np.fft.rfft(y[-period:, j]))
                       for u, y in recs]
            aj, bj = fit_oe_periodic(spectra, na, nb, period, iterations=2 * iterations)
        else:
            aj, bj = fit_oe([(u, y[:, j]) for u, y in recs], na, nb, iterations)
        a.append(aj)
        b.append(bj)
    return tuple(a), tuple(b)


def predict_linear(a: Sequence[ArrayLike], b: Sequence[ArrayLike],
                   u: ArrayLike) -> NDArray[np.float64]:
    """The outputs of the linear model of :func:`fit_linear`, simulated from rest.

    Parameters
    ----------
    a : sequence of array_like
        Per output, A_j = [1, a_1, ...].
    b : sequence of array_like
        Per output, B_ji as (m, nb).
    u : array_like
        (N, m) inputs, or (N,) for one input.

    Returns
    -------
    ndarray
        (N, p) outputs.

    Examples
    --------
    >>> from pihyst.dynamics import predict_linear
    >>> predict_linear([[1.0, -0.5]], [[[0.5]]], [1.0, 1.0, 1.0]).ravel().tolist()
    [0.5, 0.75, 0.875]
    """
    u = np.atleast_2d(np.asarray(u, dtype=float).T).T
    return np.column_stack([simulate(a[j], b[j], u) for j in range(len(a))])


def fit_hammerstein(records: Iterable[tuple[ArrayLike, ArrayLike]], na: int, nb: int, *,
                    thresholds: Sequence[NDArray[np.float64] | Sequence[float]] | None = None,
                    n_operators: int = 4,
                    input_range: Sequence[tuple[float, float]] | None = None,
                    iterations: int = 5, refinements: int = 10,
                    period: int | None = None) -> HammersteinModel:
    """A :class:`HammersteinModel` fitted to ``records`` (module notes).

    Parameters
    ----------
    records : iterable of (array_like, array_like)
        ``(u, y)`` pairs, u (N, m) and y (N, p) (or 1-D for one).
    na, nb : int
        Orders of A (its coefficients after the leading 1) and B (coefficients).
    thresholds : sequence of array_like, optional
        One array of play thresholds per input (default :func:`default_thresholds` of
        all records' input).
    n_operators : int
        Operators per input when the thresholds are not given.
    input_range : sequence of (float, float), optional
        Per input (default: 1.5 times the data's span about its centre).
    iterations : int
        Steiglitz-McBride iterations of each dynamics fit.
    refinements : int
        At most this many alternations of weights and dynamics.
    period : int, optional
        As for :func:`fit_linear` (the fit then runs on the last period's spectrum; the
        operators are run over the whole record, so the first period settles them).

    Returns
    -------
    HammersteinModel
        The model, never worse on the records than the linear model it starts from.

    Raises
    ------
    InvalidArgumentError
        A record with not as many input as output samples.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst import ClassicalPI
    >>> from pihyst.dynamics import HammersteinModel, fit_hammerstein, fit_linear, predict_linear
    >>> true = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
    ...                         a=([1.0, -0.5],), b=([[0.5]],))
    >>> t = np.arange(400)
    >>> u = 5 + 5 * np.sin(2 * np.pi * t / 100) * np.sin(2 * np.pi * t / 400)
    >>> y = true.predict(u)
    >>> model = fit_hammerstein([(u, y)], 1, 1, n_operators=3)
    >>> a, b = fit_linear([(u, y)], 1, 1)
    >>> hammerstein = np.max(np.abs(model.predict(u) - y))
    >>> linear = np.max(np.abs(predict_linear(a, b, u) - y))
    >>> bool(hammerstein < linear / 5)
    True
    """
    from scipy.optimize import lsq_linear

    recs = _as_records(records)
    m, p = recs[0][0].shape[1], recs[0][1].shape[1]
    allu = np.vstack([u for u, _ in recs])
    if thresholds is None:
        thresholds = [default_thresholds(allu[:, i], n_operators) for i in range(m)]
    if input_range is None:
        c, s = (allu.max(0) + allu.min(0)) / 2, np.ptp(allu, axis=0)
        input_range = [(c[i] - 0.75 * s[i], c[i] + 0.75 * s[i]) for i in range(m)]
    bases = [ClassicalPI(thresholds[i], np.ones(len(thresholds[i])),
                         input_range=input_range[i]) for i in range(m)]   # zero state
    K = [b.n_operators for b in bases]
    phis = [[_operators(bases[i], u[:, i]) for i in range(m)] for u, _ in recs]

    # 1. start from the linear model: w_i = (1, 0, ..., 0) (threshold 0: h_i = u_i)
    w = [np.r_[1.0, np.zeros(K[i] - 1)] for i in range(m)]
    offs = np.cumsum([0] + K)
    skip = max(na, nb)

    if period:
        # spectra of the last period: operator outputs (L x K per input) and outputs
        spec_phi = [[np.fft.rfft(ph[i][-period:], axis=0) for i in range(m)] for ph in phis]
        spec_y = [np.fft.rfft(y[-period:], axis=0) for _, y in recs]

    def dynamics(w):
        if period:
            hs = [np.column_stack([sp[i] @ w[i] for i in range(m)]) for sp in spec_phi]
            return [fit_oe_periodic([(h, Y[:, j]) for h, Y in zip(hs, spec_y)], na, nb,
                                    period, iterations=2 * iterations) for j in range(p)]
        hs = [np.column_stack([ph[i] @ w[i] for i in range(m)]) for ph in phis]
        return [fit_oe([(h, y[:, j]) for h, (_, y) in zip(hs, recs)], na, nb, iterations)
                for j in range(p)]

    def filtered(dyn):
        # y_j = sum_ik w_ik (B_ji / A_j) f_ik: the simulated output is linear in w
        cols, target = [], []
        if period:
            resp = [response(a_j, b_j, period) for a_j, b_j in dyn]
            for sp, Y in zip(spec_phi, spec_y):
                for j in range(p):
                    M = np.hstack([resp[j][:, i:i + 1] * sp[i] for i in range(m)])
                    cols += [M.real, M.imag]
                    target += [Y[:, j].real, Y[:, j].imag]
            return np.vstack(cols), np.concatenate(target)
        for ph, (_, y) in zip(phis, recs):
            for j in range(p):
                a_j, b_j = dyn[j]
                cols.append(np.hstack([_lfilter()(b_j[i], a_j, ph[i], axis=0)
                                       for i in range(m)])[skip:])
                target.append(y[skip:, j])
        return np.vstack(cols), np.concatenate(target)

    def sim_rss(dyn, w):
        X, t = filtered(dyn)
        r = t - X @ np.concatenate(w)
        return float(r @ r)

    dyn = dynamics(w)
    best = (sim_rss(dyn, w), dyn, w)
    # 2. alternate: w by bounded least squares on the simulated output (w >= 0), then
    # the dynamics on the new hysteresis output; a step is kept only if the simulation
    # error on the records goes down
    for _ in range(refinements):
        X, t = filtered(best[1])
        sol = lsq_linear(X, t, bounds=(0.0, np.inf), method="bvls").x
        w_new = [sol[offs[i]:offs[i + 1]] for i in range(m)]
        gains = [max(wi.sum(), 1e-300) for wi in w_new]
        w_new = [wi / g for wi, g in zip(w_new, gains)]      # sum_k w_ik = 1
        # the w step with the gains moved into B, then the dynamics refitted on it
        moved = [(a_j, b_j * np.array(gains)[:, None]) for a_j, b_j in best[1]]
        candidates = [(sim_rss(moved, w_new), moved, w_new)]
        dyn_new = dynamics(w_new)
        candidates.append((sim_rss(dyn_new, w_new), dyn_new, w_new))
        step = min(candidates, key=lambda c: c[0])
        if not step[0] < best[0] * (1 - 1e-6):
            break
        best = step
    _, dyn, w = best
    hyst = tuple(bases[i].replace(weights=w[i]) for i in range(m))
    return HammersteinModel(hysteresis=hyst, a=tuple(d[0] for d in dyn),
                            b=tuple(d[1] for d in dyn))
