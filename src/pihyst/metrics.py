"""Error metrics: plain functions ``f(y_true, y_pred) -> float``.

Examples
--------
>>> import numpy as np
>>> y, y_hat = np.array([0.0, 1.0, 2.0]), np.array([0.0, 1.5, 1.0])
>>> mean_abs_error(y, y_hat), max_abs_error(y, y_hat), round(rms_error(y, y_hat), 4)
(0.5, 1.0, 0.6455)
"""

import numpy as np
from numpy.typing import ArrayLike


def _residual(y_true, y_pred):
    y_true = np.asarray(y_true, dtype=float)
    y_pred = np.asarray(y_pred, dtype=float)
    if y_true.shape != y_pred.shape:
        raise ValueError(f"y_true and y_pred have different shapes {y_true.shape} and "
                         f"{y_pred.shape}")
    if y_true.size == 0:
        raise ValueError("no samples to compare")
    return y_pred - y_true


def mean_abs_error(y_true: ArrayLike, y_pred: ArrayLike) -> float:
    """Mean absolute error, mean_t |y_pred[t] - y_true[t]|.

    Parameters
    ----------
    y_true : array_like
        The measured (or desired) output.
    y_pred : array_like
        The model's output, of the same shape.

    Returns
    -------
    float
        The mean absolute error, in the output's unit.

    Raises
    ------
    ValueError
        If the shapes differ or there are no samples.

    Examples
    --------
    >>> float(mean_abs_error([0, 1], [1, 1]))
    0.5
    """
    return float(np.mean(np.abs(_residual(y_true, y_pred))))


def max_abs_error(y_true: ArrayLike, y_pred: ArrayLike) -> float:
    """Largest absolute error, max_t |y_pred[t] - y_true[t]|.

    Parameters
    ----------
    y_true : array_like
        The measured (or desired) output.
    y_pred : array_like
        The model's output, of the same shape.

    Returns
    -------
    float
        The largest absolute error, in the output's unit.

    Raises
    ------
    ValueError
        If the shapes differ or there are no samples.

    Examples
    --------
    >>> float(max_abs_error([0, 1], [-2, 1]))
    2.0
    """
    return float(np.max(np.abs(_residual(y_true, y_pred))))


def rms_error(y_true: ArrayLike, y_pred: ArrayLike) -> float:
    """Root-mean-square error, sqrt(mean_t (y_pred[t] - y_true[t])^2).

    Parameters
    ----------
    y_true : array_like
        The measured (or desired) output.
    y_pred : array_like
        The model's output, of the same shape.

    Returns
    -------
    float
        The RMS error, in the output's unit.

    Raises
    ------
    ValueError
        If the shapes differ or there are no samples.

    Examples
    --------
    >>> float(rms_error([0, 0], [3, 4]))
    3.5355339059327378
    """
    return float(np.sqrt(np.mean(_residual(y_true, y_pred) ** 2)))


def error_summary(y_true: ArrayLike, y_pred: ArrayLike,
                  measured_range: float) -> dict[str, float | None]:
    """Mean absolute, max absolute and RMS error, each in the output's unit and in % of
    ``measured_range`` (the peak-to-peak of the measured output).

    Parameters
    ----------
    y_true : array_like
        The measured (or desired) output.
    y_pred : array_like
        The model's output, of the same shape.
    measured_range : float
        The peak-to-peak of the measured output, for the percentages.

    Returns
    -------
    dict
        ``mean_abs``, ``max_abs``, ``rms`` and each with ``_pct`` (None when
        ``measured_range`` is not > 0).

    Raises
    ------
    ValueError
        If the shapes differ or there are no samples.

    Examples
    --------
    >>> s = error_summary([0, 10], [1, 10], measured_range=10)
    >>> s["mean_abs"], s["mean_abs_pct"], s["max_abs"]
    (0.5, 5.0, 1.0)
    """
    errors = {"mean_abs": mean_abs_error(y_true, y_pred),
              "max_abs": max_abs_error(y_true, y_pred),
              "rms": rms_error(y_true, y_pred)}
    out: dict[str, float | None] = dict(errors)
    for key, value in errors.items():
        out[f"{key}_pct"] = 100.0 * value / measured_range if measured_range > 0 else None
    return out
