"""MIMO Hammerstein models with state-space dynamics, from periodic multisine records
(docs/theory/hammerstein.md).

For inputs u_i (i = 1..m) and outputs y (p):

    h_i = H_i(u_i) = sum_k w_ik f_ik(u_i)        (a classical PI model per input)
    y = G(q) h,   G a stable state-space model (A, B, C, D) of :mod:`._statespace`.

Identification (:func:`fit_hammerstein_ss`), the play thresholds r_ik fixed:

1. the linear model: w_i = (1, 0, ..., 0) (the threshold-0 operator is u_i itself) and
   G fitted to the records by :func:`~pihyst.dynamics.fit_state_space` (order chosen by
   validation unless given);
2. alternate: with G fixed, the steady-state output is linear in w, line by line of the
   DFT of one period (averaged over the steady-state periods, F_ik the spectrum of f_ik):

       Y_j(k) = sum_i G_ji(z_k) sum_k' w_ik' F_ik'(k),

   fitted by bounded least squares over all records and lines but DC (w >= 0: each H_i
   monotone with pihyst's exact inverse); sum_k w_ik = 1, the gain moved into G's i-th
   input column. With w fixed, G is refitted on (h, y): refined by nonlinear least
   squares on the BLA of (h, y) from the current G (``refine``, :mod:`._refine`), or
   else identified anew at the same order by FSID. A step is kept only
   while the steady-state simulation error on the records decreases, so the model never
   fits its records worse than the linear model it starts from.
"""

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst.dynamics._bla import estimate_bla, period_spectra, periodic_records
from pihyst.dynamics._fit_state_space import (
    DEFAULT_ORDERS,
    bla_weights,
    fit_state_space,
    steady_state_rms,
)
from pihyst.dynamics._refine import refine as refined
from pihyst.dynamics._statespace import StateSpace
from pihyst.exceptions import InvalidArgumentError
from pihyst.model import ClassicalPI


@dataclass(frozen=True, eq=False)
class StateSpaceHammerstein:
    """Static hysteresis per input followed by MIMO state-space dynamics.

    Parameters
    ----------
    hysteresis : tuple of PIModel
        One model per input (ClassicalPI from :func:`fit_hammerstein_ss`).
    dynamics : StateSpace
        The dynamics from the hysteresis outputs to the outputs (m inputs).

    Examples
    --------
    >>> from pihyst import ClassicalPI
    >>> from pihyst.dynamics import StateSpace, StateSpaceHammerstein
    >>> model = StateSpaceHammerstein((ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
    ...                               StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]]))
    >>> model.n_inputs, model.n_outputs
    (1, 1)
    """

    hysteresis: tuple[Any, ...]
    dynamics: StateSpace

    @property
    def n_inputs(self):
        return len(self.hysteresis)

    @property
    def n_outputs(self):
        return self.dynamics.n_outputs

    def hysteresis_output(self, u: ArrayLike) -> NDArray[np.float64]:
        """h_i = H_i(u_i) from the zero operator state.

        Parameters
        ----------
        u : array_like
            (N, m) inputs, or (N,) for one input.

        Returns
        -------
        ndarray
            (N, m) the hysteresis outputs.

        Raises
        ------
        InvalidArgumentError
            ``u`` has not as many columns as the model has inputs.

        Examples
        --------
        >>> from pihyst import ClassicalPI
        >>> from pihyst.dynamics import StateSpace, StateSpaceHammerstein
        >>> model = StateSpaceHammerstein((ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                               StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]]))
        >>> model.hysteresis_output([0.0, 4.0, 0.0]).ravel().tolist()
        [0.0, 5.0, 1.0]
        """
        inputs = np.atleast_2d(np.asarray(u, dtype=float).T).T
        if inputs.shape[1] != self.n_inputs:
            raise InvalidArgumentError(f"the model has {self.n_inputs} inputs; u has "
                                       f"{inputs.shape[1]} columns")
        return np.column_stack([H.predict(inputs[:, i], initial_state=np.zeros(H.n_operators))
                                for i, H in enumerate(self.hysteresis)])

    def predict(self, u: ArrayLike) -> NDArray[np.float64]:
        """The outputs for inputs ``u``, simulated from rest.

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
        >>> from pihyst.dynamics import StateSpace, StateSpaceHammerstein
        >>> model = StateSpaceHammerstein((ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                               StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]]))
        >>> model.predict([1.0, 1.0, 1.0]).ravel().tolist()
        [0.0, 1.0, 1.5]
        """
        return self.dynamics.predict(self.hysteresis_output(u))

    def predict_steady(self, u: ArrayLike, period: int) -> NDArray[np.float64]:
        """Outputs over the last period of u in periodic steady state, from the DFT of
        the last period's hysteresis output (the same criterion as the fit).

        Parameters
        ----------
        u : array_like
            (N, m) inputs, or (N,) for one input; its last ``period`` samples repeat.
        period : int
            Samples per period.

        Returns
        -------
        ndarray
            (period, p) the steady-state outputs.

        Examples
        --------
        >>> import numpy as np
        >>> from pihyst import ClassicalPI
        >>> from pihyst.dynamics import StateSpace, StateSpaceHammerstein
        >>> model = StateSpaceHammerstein((ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                               StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]]))
        >>> u = np.tile(10 + np.sin(2 * np.pi * np.arange(16) / 16), 3)
        >>> steady = model.predict_steady(u, 16)
        >>> bool(np.allclose(steady, model.predict(np.tile(u, 4))[-16:]))
        True
        """
        h = self.hysteresis_output(u)[-period:]
        H = np.fft.rfft(h, axis=0)
        w = 2 * np.pi * np.arange(H.shape[0]) / period
        Y = np.einsum("kpm,km->kp", self.dynamics.response(w), H)
        return np.fft.irfft(Y, n=period, axis=0)

    def to_dict(self) -> dict[str, Any]:
        """The model as JSON values (:meth:`from_dict` reads them back).

        Returns
        -------
        dict
            ``family`` ("hammerstein-state-space"), ``hysteresis`` (each model's dict)
            and ``dynamics`` (:meth:`StateSpace.to_dict`).

        Examples
        --------
        >>> from pihyst import ClassicalPI
        >>> from pihyst.dynamics import StateSpace, StateSpaceHammerstein
        >>> model = StateSpaceHammerstein((ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                               StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]]))
        >>> model.to_dict()["dynamics"]["A"]
        [[0.5]]
        """
        return {"family": "hammerstein-state-space",
                "hysteresis": [H.to_dict() for H in self.hysteresis],
                "dynamics": self.dynamics.to_dict()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "StateSpaceHammerstein":
        """The model a dict of :meth:`to_dict` describes.

        Parameters
        ----------
        d : dict
            With ``hysteresis`` and ``dynamics``.

        Returns
        -------
        StateSpaceHammerstein
            The model.

        Examples
        --------
        >>> from pihyst import ClassicalPI
        >>> from pihyst.dynamics import StateSpace, StateSpaceHammerstein
        >>> model = StateSpaceHammerstein((ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
        ...                               StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]]))
        >>> StateSpaceHammerstein.from_dict(model.to_dict()).predict([1.0, 1.0]).ravel().tolist()
        [0.0, 1.0]
        """
        from pihyst.model import PIModel
        return cls(hysteresis=tuple(PIModel.from_dict(h) for h in d["hysteresis"]),
                   dynamics=StateSpace.from_dict(d["dynamics"]))


def _thresholds(u, n_operators):
    span = float(np.ptp(u))
    return np.arange(n_operators) * (span / 2) / n_operators


def fit_hammerstein_ss(records: Iterable[tuple[Any, Any]], period: int,
                       order: int | None = None, *,
                       thresholds: Sequence[NDArray[np.float64] | Sequence[float]] | None = None,
                       n_operators: int = 4,
                       input_range: Sequence[tuple[float, float]] | None = None,
                       refinements: int = 3, orders: Sequence[int] = DEFAULT_ORDERS,
                       validation: Sequence[int] | None = None, discard: int = 1,
                       weighted: bool = False, linear: StateSpace | None = None,
                       refine: bool = True, max_nfev: int = 30) -> StateSpaceHammerstein:
    """A :class:`StateSpaceHammerstein` fitted to periodic multisine records (module
    notes).

    Parameters
    ----------
    records : iterable of (array_like, array_like)
        ``(u, y)`` pairs, u (N, m) and y (N, p) (or 1-D for one), N a multiple of
        ``period``.
    period : int
        Samples per period.
    order : int, optional
        As for :func:`~pihyst.dynamics.fit_state_space` (the order is chosen once, for
        the linear start).
    thresholds : sequence of array_like, optional
        One array per input (default: ``n_operators`` equally spaced on [0, S/2) of
        the input's span S).
    n_operators : int
        Operators per input when the thresholds are not given.
    input_range : sequence of (float, float), optional
        Per input (default 1.5 times the span about its centre).
    refinements : int
        At most this many alternations of weights and dynamics, >= 0.
    orders, validation, discard, weighted, refine, max_nfev
        As for :func:`~pihyst.dynamics.fit_state_space`.
    linear : StateSpace, optional
        The linear start of step 1 if already fitted to these records (m inputs; its
        order is kept).

    Returns
    -------
    StateSpaceHammerstein
        The model, never worse on the records than its linear start.

    Raises
    ------
    InvalidArgumentError
        Records that are not whole periods, options that are not valid.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst import ClassicalPI
    >>> from pihyst.dynamics import StateSpace, StateSpaceHammerstein, fit_hammerstein_ss
    >>> true = StateSpaceHammerstein((ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
    ...                              StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]]))
    >>> def multisine(seed, t=np.arange(64), k=np.arange(1, 8)):
    ...     phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, k.size)
    ...     return 10 + np.cos(2 * np.pi * np.outer(t, k) / 32 + phase).sum(axis=1)
    >>> records = [(u, true.predict(u)) for u in map(multisine, range(3))]
    >>> model = fit_hammerstein_ss(records, 32, 1, n_operators=3)
    >>> model.n_inputs, model.dynamics.order, model.hysteresis[0].n_operators
    (1, 1, 3)
    """
    from scipy.optimize import lsq_linear

    recs = periodic_records(records, period)
    m = recs[0][0].shape[1]
    if not isinstance(refinements, (int, np.integer)) or refinements < 0:
        raise InvalidArgumentError(f"refinements must be a non-negative integer, not "
                                   f"{refinements!r}")
    allu = np.vstack([u for u, _ in recs])
    if thresholds is None:
        thresholds = [_thresholds(allu[:, i], n_operators) for i in range(m)]
    if input_range is None:
        c, s = (allu.max(0) + allu.min(0)) / 2, np.ptp(allu, axis=0)
        input_range = [(c[i] - 0.75 * s[i], c[i] + 0.75 * s[i]) for i in range(m)]
    if len(thresholds) != m or len(input_range) != m:
        raise InvalidArgumentError(f"thresholds and input_range need one entry per input "
                                   f"({m})")
    bases = [ClassicalPI(thresholds[i], np.ones(len(thresholds[i])),
                         input_range=input_range[i]) for i in range(m)]
    K = [b.n_operators for b in bases]
    offs = np.cumsum([0] + K)
    # operator outputs from the zero state over whole records (the discarded periods
    # settle them), then their steady-state spectra without DC
    phis = [[b.operators(u[:, i], initial_state=np.zeros(b.n_operators))
             for i, b in enumerate(bases)] for u, _ in recs]
    F = [[period_spectra(ph[i], period, discard)[1:] for i in range(m)] for ph in phis]
    Y = [period_spectra(y, period, discard)[1:] for _, y in recs]
    omega = 2 * np.pi * np.arange(1, period // 2 + 1) / period

    def hysteresis_records(w):
        return [(np.column_stack([ph[i] @ w[i] for i in range(m)]), y)
                for ph, (_, y) in zip(phis, recs)]

    def cost(dyn, w):
        return steady_state_rms(dyn, hysteresis_records(w), period, discard)

    w = [np.r_[1.0, np.zeros(K[i] - 1)] for i in range(m)]
    if linear is None:
        dyn = fit_state_space(recs, period, order, orders=orders, validation=validation,
                              discard=discard, weighted=weighted, refine=refine,
                              max_nfev=max_nfev)
    elif not isinstance(linear, StateSpace) or linear.n_inputs != m or \
            linear.n_outputs != recs[0][1].shape[1]:
        raise InvalidArgumentError(f"linear must be a StateSpace model with {m} inputs and "
                                   f"{recs[0][1].shape[1]} outputs")
    else:
        dyn = linear
    order = dyn.order
    best = (cost(dyn, w), dyn, w)
    for _ in range(refinements):
        G = best[1].response(omega)                                       # (L, p, m)
        rows, target = [], []
        for Fr, Yr in zip(F, Y):
            M = np.concatenate([G[:, :, i:i + 1] * Fr[i][:, None, :] for i in range(m)],
                               axis=2)                                    # (L, p, sum K)
            M = M.reshape(-1, offs[-1])
            rows += [M.real, M.imag]
            target += [Yr.ravel().real, Yr.ravel().imag]
        sol = lsq_linear(np.vstack(rows), np.concatenate(target), bounds=(0.0, np.inf),
                         method="bvls").x
        w_new = [sol[offs[i]:offs[i + 1]] for i in range(m)]
        if any(wi.sum() <= 0 for wi in w_new):
            break
        gains = np.array([wi.sum() for wi in w_new])
        w_new = [wi / g for wi, g in zip(w_new, gains)]
        moved = best[1].scaled_inputs(gains)
        candidates = [(cost(moved, w_new), moved, w_new)]
        if refine:
            frf = estimate_bla(hysteresis_records(w_new), period, discard=discard)
            refit = refined(moved, frf.omega, frf.G, bla_weights(frf, weighted),
                            max_nfev=max_nfev)
        else:
            refit = fit_state_space(hysteresis_records(w_new), period, order,
                                    discard=discard, weighted=weighted, refine=False)
        candidates.append((cost(refit, w_new), refit, w_new))
        step = min(candidates, key=lambda c: c[0])
        if not step[0] < best[0] * (1 - 1e-6):
            break
        best = step
    _, dyn, w = best
    return StateSpaceHammerstein(hysteresis=tuple(bases[i].replace(weights=w[i])
                                                  for i in range(m)), dynamics=dyn)
