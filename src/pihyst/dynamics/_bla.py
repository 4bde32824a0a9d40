"""Best linear approximation (BLA) of a MIMO system from periodic multisine records.

Each record r is a periodic excitation (random-phase multisine) with P periods of N
samples, u_r of shape (P N, m), y_r of shape (P N, p). The first ``discard`` periods hold
the start-up transient and are left out; the others are averaged period by period into
the DFT spectra U_r(k) (m) and Y_r(k) (p) of one period. On every excited line k the BLA
is the least-squares solution of Y(k) = G(k) U(k) over the R >= m records (columns):

    G(k) = Y(k) U(k)^H (U(k) U(k)^H)^-1,        U(k) = [U_1(k) ... U_R(k)]  (m x R).

With R > m the residuals give the BLA's noise (+ nonlinear distortion) variance,

    var G_ji(k) = |E_j(k)|^2 / (R - m) [(U U^H)^-1]_ii,     E(k) = Y(k) - G(k) U(k),

used to weight the parametric fit. A line is excited when the records' summed input
power on it exceeds ``threshold`` times its largest value.
"""

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from pihyst.exceptions import InvalidArgumentError


@dataclass(frozen=True)
class FrequencyResponse:
    """A frequency response on DFT lines, as :func:`estimate_bla` returns it.

    Parameters
    ----------
    lines : ndarray of int
        (L,) the DFT lines k of one period.
    period : int
        Samples per period N.
    G : ndarray of complex
        (L, p, m) the response on each line.
    variance : ndarray or None
        (L, p, m) the variance of G's estimate, or None when there are only m records.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import FrequencyResponse
    >>> fr = FrequencyResponse(np.array([1, 2]), 8, np.ones((2, 1, 1), complex), None)
    >>> fr.omega.round(4).tolist()
    [0.7854, 1.5708]
    """

    lines: np.ndarray
    period: int
    G: np.ndarray
    variance: np.ndarray | None

    @property
    def omega(self):
        """Normalised angular frequencies 2 pi k / N (rad/sample)."""
        return 2 * np.pi * self.lines / self.period


def periodic_records(records, period):
    """(u, y) pairs as 2-D float arrays, checked for a whole number (>= 1) of periods."""
    if not isinstance(period, (int, np.integer)) or period < 4:
        raise InvalidArgumentError(f"period must be an integer >= 4, not {period!r}")
    out = []
    for r, rec in enumerate(records):
        try:
            u, y = rec
        except (TypeError, ValueError):
            raise InvalidArgumentError(f"record {r} must be a pair (u, y)") from None
        u = np.atleast_2d(np.asarray(u, dtype=float).T).T
        y = np.atleast_2d(np.asarray(y, dtype=float).T).T
        if u.ndim != 2 or y.ndim != 2 or u.shape[0] != y.shape[0]:
            raise InvalidArgumentError(f"record {r}: u and y must be (N, m) and (N, p) arrays "
                                       f"with the same N, not {u.shape} and {y.shape}")
        if u.shape[0] % period or u.shape[0] < period:
            raise InvalidArgumentError(f"record {r}: {u.shape[0]} samples are not a whole "
                                       f"number of periods of {period}")
        if not (np.all(np.isfinite(u)) and np.all(np.isfinite(y))):
            raise InvalidArgumentError(f"record {r} holds NaN or infinite samples")
        if out and (u.shape[1], y.shape[1]) != (out[0][0].shape[1], out[0][1].shape[1]):
            raise InvalidArgumentError(f"record {r} has {u.shape[1]} inputs and {y.shape[1]} "
                                       f"outputs, record 0 {out[0][0].shape[1]} and "
                                       f"{out[0][1].shape[1]}")
        out.append((u, y))
    if not out:
        raise InvalidArgumentError("no records given")
    return out


def period_spectra(x, period, discard):
    """rfft of the mean over the periods after the first ``discard`` ones: (L, channels)."""
    P = x.shape[0] // period
    keep = x[min(discard, P - 1) * period:].reshape(-1, period, x.shape[1]).mean(axis=0)
    return np.fft.rfft(keep, axis=0)


def estimate_bla(records: Iterable[tuple[Any, Any]], period: int, *, discard: int = 1,
                 threshold: float = 1e-6) -> FrequencyResponse:
    """The best linear approximation of periodic multisine records (module notes).

    Parameters
    ----------
    records : iterable of (array_like, array_like)
        ``(u, y)`` pairs: (P N, m) inputs and (P N, p) outputs (or 1-D for one), a whole
        number of periods each; at least m records of independent inputs.
    period : int
        Samples per period N, >= 4.
    discard : int
        Leading periods left out (the start-up transient).
    threshold : float
        A line is excited when its input power exceeds this times the largest.

    Returns
    -------
    FrequencyResponse
        G and, with more than m records, its variance on the excited lines.

    Raises
    ------
    InvalidArgumentError
        Records that are not pairs of whole periods, too few or dependent inputs.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import StateSpace, estimate_bla
    >>> plant = StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]])
    >>> k = np.arange(32)
    >>> u = np.sin(2 * np.pi * k / 16) + np.cos(2 * np.pi * 3 * k / 16)
    >>> fr = estimate_bla([(u, plant.predict(u))], 16, discard=1)
    >>> fr.lines.tolist()
    [1, 3]
    >>> bool(np.allclose(fr.G, plant.response(fr.omega), atol=1e-3))
    True
    """
    recs = periodic_records(records, period)
    m = recs[0][0].shape[1]
    if len(recs) < m:
        raise InvalidArgumentError(f"a MIMO frequency response of {m} inputs needs at least "
                                   f"{m} records (realisations), not {len(recs)}")
    U = np.stack([period_spectra(u, period, discard) for u, _ in recs], axis=2)  # (K, m, R)
    Y = np.stack([period_spectra(y, period, discard) for _, y in recs], axis=2)  # (K, p, R)
    power = np.sum(np.abs(U) ** 2, axis=(1, 2))
    power[0] = 0.0                                    # DC: an offset, not an excitation
    lines = np.flatnonzero(power > threshold * power.max())
    U, Y = U[lines], Y[lines]
    UU = U @ np.conj(np.swapaxes(U, 1, 2))            # (L, m, m)
    cond = np.linalg.cond(UU)
    if np.any(~np.isfinite(cond)) or np.max(cond) > 1e12:
        k = int(lines[np.argmax(np.where(np.isfinite(cond), cond, np.inf))])
        raise InvalidArgumentError(f"the records' inputs are not independent on line {k}: "
                                   f"use different random-phase realisations")
    UUi = np.linalg.inv(UU)
    G = (Y @ np.conj(np.swapaxes(U, 1, 2))) @ UUi
    R = len(recs)
    variance = None
    if R > m:
        E = Y - G @ U
        s2 = np.sum(np.abs(E) ** 2, axis=2) / (R - m)                  # (L, p)
        variance = s2[:, :, None] * np.real(np.diagonal(UUi, axis1=1, axis2=2))[:, None, :]
    return FrequencyResponse(lines=lines, period=int(period), G=G, variance=variance)
