"""Identification: :func:`fit`, the procedure of docs/theory/identification.md ("The
procedure") from the user's arguments to the returned model.

``fit(u, y)`` checks its options once (:class:`~pihyst.identify._options.FitOptions`),
fits the record without creep step by step (:func:`~pihyst.identify._record_fit.fit_record`:
fitting frame, start state, delay, cycles and held-back data, every family's candidate
operators, weights and structure, the choice, the refit, the report) and, with sample
times, decides on creep (:func:`~pihyst.identify._creep.fit_with_creep`). Each step
returns a frozen decision (:mod:`pihyst.identify._decisions`); every number that decides
something is in :mod:`pihyst.identify._constants`.
"""

import functools
from collections.abc import Callable, Sequence
from typing import Any, TypeVar, cast

from numpy.typing import ArrayLike

from pihyst._arguments import real_array
from pihyst.identify._creep import fit_with_creep
from pihyst.identify._families import FAMILY_NAMES
from pihyst.identify._family_fit import INITIAL_STATES, cycled_state
from pihyst.identify._options import DEFAULT_N_CANDIDATES, FitOptions
from pihyst.identify._progress import Steps
from pihyst.identify._record_fit import fit_record
from pihyst.identify._report import FitResult
from pihyst.identify._subsets import DEFAULT_MAX_EXHAUSTIVE

__all__ = ["fit", "FAMILY_NAMES", "INITIAL_STATES", "cycled_state"]


_F = TypeVar("_F", bound=Callable[..., Any])


def _one_blas_thread(function: _F) -> _F:
    """Runs ``function`` with BLAS on one thread: the fit's matrices are small (tens to a
    few hundred columns), where a second thread only waits (on a loaded 2-core machine
    an SVD of 300 x 150 took 15 times longer with two), and the sums then run in one
    order, so the same record gives the same model bit for bit whatever the core count."""
    @functools.wraps(function)
    def wrapped(*args: Any, **kwargs: Any) -> Any:
        import scipy.linalg  # noqa: F401  SciPy's own BLAS: limited only once loaded
        from threadpoolctl import threadpool_limits

        with threadpool_limits(1, user_api="blas"):
            return function(*args, **kwargs)
    return cast(_F, wrapped)


@_one_blas_thread
def fit(u: ArrayLike, y: ArrayLike, *, family: Any = None,
        thresholds: ArrayLike | None = None, n_operators: int | None = None,
        candidates: ArrayLike | None = None, n_candidates: int = DEFAULT_N_CANDIDATES,
        offset: bool | float = True, nonnegative: bool = True,
        bounds: tuple[Any, Any] | None = None, through: str | Sequence[int] | None = None,
        initial_state: str | ArrayLike = "auto", holdout: str | float | None = "alternate",
        refit: bool = True, input_range: tuple[float, float] | None = None,
        validate: tuple[ArrayLike, ArrayLike] | None = None, delay: int | str = "auto",
        max_operators: int | None = None, max_latency: float | None = None,
        max_exhaustive: int = DEFAULT_MAX_EXHAUSTIVE, t: ArrayLike | None = None,
        creep: str | bool | ArrayLike = "auto",
        progress: Callable[[str], Any] | None = None) -> FitResult:
    """Fit PI-type hysteresis models to a measured record and keep the smallest, fastest
    one of those that generalize best.

    Parameters
    ----------
    u, y : array_like
        Input (e.g. voltage) and measured output (e.g. displacement), same length.
    family : str, family object, or a list of them, optional
        The fitting families (:mod:`pihyst.identify`): ``"classical"``
        (:class:`~pihyst.identify.Classical`), ``"multislope"``
        (:class:`~pihyst.identify.Multislope`: the paper's shape a = 0.8, b = 1.2,
        h = 0.5 on the data's range, or ``Multislope(shape={...})``),
        ``"multislope-identified"`` (:class:`~pihyst.identify.MultislopeIdentified`: shape
        fitted to the data), ``"modified-pi"`` (:class:`~pihyst.identify.ModifiedPI`:
        classical + monotone input function of ``segments`` pieces), ``"kp"``
        (:class:`~pihyst.identify.KrasnoselskiiPokrovskii`: a ``grid`` of kernels). A
        name stands for the family with its default options. ``"bouc-wen"``
        (:class:`~pihyst.identify.BoucWen`) is not a PI family: a
        :class:`~pihyst.model.BoucWenModel` (docs/theory/bouc-wen.md).
        Default: every family (``FAMILY_NAMES``: the PI families and Bouc-Wen),
        judged on held-back data (and ``validate``); of those within 2 % of the lowest
        judged RMS, a piecewise-linear compensator (PI) before an iterative one
        (Bouc-Wen), then the fewest operators, then the lowest judged error, is returned.
        When the data do not determine the minor loops (no reversals inside the range),
        families whose structure or regularization fixes them plausibly (classical,
        modified-pi, kp, Bouc-Wen; not multislope) are preferred.
    thresholds : array_like, optional
        Use exactly these thresholds (input units, measured from the bottom of the input
        range) instead of choosing them (families with thresholds only).
    n_operators : int, optional
        Number of operators to choose from the candidates. Default: chosen from the data
        (the smallest number within 1 % of the lowest held-back RMS).
    candidates : array_like, optional
        Candidate thresholds; default ``n_candidates`` equally spaced ones over the
        family's useful range ([0, S/2) classical, [0, (1-a)U/(1-ah)] multislope).
    n_candidates : int
        Size of the default candidate grid (16, as in the paper).
    offset : bool or float
        True: fit a constant offset (the sensor's zero is arbitrary); a number: fixed.
    nonnegative : bool
        Constrain the weights to w >= 0 (monotone, invertible model).
    bounds : (lower, upper), optional
        Bounds on the weights (scalars, or per operator with explicit thresholds).
    through : "top" or list of int, optional
        Sample indices the model must pass through exactly ("top": the sample at the
        highest input).
    initial_state : "auto", "cycled", "settle", "zero", "rise", "fall" or array_like
        Operator state before the first sample. "cycled": at rest at the bottom of the
        range after a full bottom -> top -> bottom cycle (records made as in
        docs/interfaces.md); "settle": unknown, the first full sweep of the input range settles the
        operators and is not fitted; "rise" / "fall": at rest at the first input after
        a rise from the bottom / a fall from the top; "auto": at the bottom of the
        range "cycled" or "zero", whichever the record shows, else "settle", or (when
        the first full sweep comes after more than half the record) "rise", "fall" or
        "zero", whichever the record shows. An array (needs ``thresholds``) is used as
        given.
    holdout : "alternate", float or None
        Held-back cycles: every other cycle (major and minor separately), the last
        fraction of the record, or none (choices then judged on the fitted data).
    refit : bool
        Refit the chosen model's weights on all cycles (fitted and held-back) after the
        choice. The report's held-back errors are those of the fit before the refit.
    input_range : (min, max), optional
        Input range of the model; default the data's span.
    validate : (u2, y2), optional
        A second record (another trajectory), judged but not fitted: every family's
        error on it is reported, and counts in the choice (the worse of it and the
        held-back cycles). Its mean error is removed (the sensor's zero differs between
        records); it is judged once its input has swept its own range.
    delay : int or "auto"
        Samples by which the output lags the input (a dead time): the models are fitted
        to u[k] -> y[k + delay] and carry it (``model.delay``: ``model.predict(u)`` is
        the delayed output, ``pihyst.compensate`` previews the trajectory). "auto"
        (default): the delay with the lowest held-back RMS of a probe model, 0 to 5 % of
        a cycle, adopted only when it lowers the held-back RMS of that probe and of the
        fitted structure by more than 5 % (docs/theory/identification.md), else 0. The
        report states the delay used and why; with 0 it still says which delay the
        record favours.
    max_operators : int, optional
        Choose only among models with at most this many operators.
    max_latency : float, optional
        Choose only among models whose compensator's worst-case time per sample
        (estimated from the model's structure by a calibrated cost model, never timed:
        the same record gives the same model on every run; see the report) is at most
        this many seconds.
    max_exhaustive : int
        Largest number of subsets of the requested size searched exhaustively (the
        automatic size search uses at most 600 per size, then greedy selection + swaps).
    t : array_like, optional
        Sample times (s). With them the default fit also tries creep (``creep="auto"``).
    creep : "auto", bool or array_like
        Fit creep (docs/theory/creep.md): first-order lags of the hysteresis output
        with half-decade time constants (or these time constants, s), their gains fitted
        with the weights in one QP. The model then carries ``model.creep``. ``True``
        (or time constants): always. ``"auto"`` (default): when ``t`` is given, creep is
        fitted on the fitted cycles and kept only if it lowers the held-back RMS by more
        than 2 % (the report's ``creep`` entry says which and why); without ``t``, none.
        ``False``: none.
    progress : callable, optional
        Called with one line of text as each step ends (the step and its time in
        seconds): the command line prints them on a terminal.

    Returns
    -------
    FitResult
        ``.model`` (the fitted model, with the fit recorded in ``model.metadata["fit"]``),
        ``.report`` (a :class:`FitReport`: errors per kind of held-back data, compensator
        latency and operator count per family, threshold choice and its reasons, what
        the data could not determine; ``print(report)`` or ``report.to_json()``) and
        ``.models`` (every family's fitted model by name).

    Raises
    ------
    FitError
        Too few samples, constant input, NaN, a threshold the input never reaches,
        infeasible constraints (:class:`~pihyst.exceptions.InfeasibleConstraintsError`),
        an unknown family.

    Warns
    -----
    IllConditionedWarning
        When the chosen model's weights are not all determined by the data.

    Examples
    --------
    Recover a classical PI from data it generated:

    >>> import numpy as np
    >>> import pihyst
    >>> true = pihyst.ClassicalPI([0, 15, 30], [0.3, 0.2, 0.1])
    >>> u = np.r_[np.linspace(0, 150, 151), np.linspace(150, 0, 151)[1:],
    ...           np.linspace(0, 100, 101)[1:], np.linspace(100, 40, 61)[1:],
    ...           np.linspace(40, 150, 111)[1:], np.linspace(150, 0, 151)[1:]]
    >>> res = pihyst.fit(u, true.predict(u), family="classical", thresholds=[0, 15, 30],
    ...                  initial_state="zero", offset=False)
    >>> [round(float(w), 6) for w in res.model.weights]
    [0.3, 0.2, 0.1]

    A family with its own options:

    >>> res = pihyst.fit(u, true.predict(u), family=pihyst.identify.ModifiedPI(segments=2),
    ...                  n_operators=2)
    >>> res.report.chosen, res.model.family
    ('modified-pi', 'pwl')
    """
    real_array(u, "u"), real_array(y, "y"), real_array(t, "t")
    options = FitOptions.from_arguments(
        family=family, thresholds=thresholds, n_operators=n_operators,
        candidates=candidates, n_candidates=n_candidates, offset=offset,
        nonnegative=nonnegative, bounds=bounds, through=through,
        initial_state=initial_state, holdout=holdout, refit=refit, input_range=input_range,
        validate=validate, delay=delay, max_operators=max_operators,
        max_latency=max_latency, max_exhaustive=max_exhaustive, has_times=t is not None,
        creep=creep)
    steps = Steps(progress)
    if options.creep == "off":
        return fit_record(u, y, options, steps, t=t).result
    return fit_with_creep(u, y, t, options, steps)
