"""Compensation of a single-input single-output Hammerstein model: a stable inverse of
the dynamics, then the exact inverse of the hysteresis (docs/theory/hammerstein.md).

With y = G(q) h, G = q^-d B_s(q^-1) B_u(q^-1) / A(q^-1) (the zeros of B split into
those inside the unit circle, B_s with B's leading coefficient, and the others, B_u
monic of degree n_u), the zero-phase error tracking prefilter

    h_d[t] = A(q^-1) B_u*(q^-1) / (B_s(q^-1) B_u(1)^2) r[t + d + n_u],

with B_u*(q^-1) = q^-n_u B_u(q) (B_u's coefficients reversed), makes
G h_d = B_u(q^-1) B_u(q) / B_u(1)^2 r: zero phase, unit static gain, exact where B has
no zeros outside the unit circle. It looks d + n_u samples ahead, so it needs the
trajectory in advance (offline, or with that much preview); the trajectory is held at
its ends. The hysteresis output h_d is then inverted by :func:`pihyst.compensate`, whose
voltage and slew limits hold for every output whatever h_d is.

For a periodic trajectory (one period of N samples, repeated) the stable inverse needs no
approximation: on every harmonic k of the period (rfft line, z_k = exp(2 pi i k / N))

    H_d(k) = R(k) / G(z_k),

the non-causal inverse of the unstable zeros being as periodic as the rest (the whole
period is the preview). Lines where |G| is below ``1e-9`` of its largest value (a zero
on the unit circle) are left out.

**Below the measured band.** A model from :func:`pihyst.dynamics.fit_dynamics` has unit
static gain, and its dynamics were measured from its slowest fast record's fundamental
f_t up (``HammersteinModel.trusted_from``, cycles per sample); below f_t only the slow
record and G(1) = 1 pin it. There the static model, fitted on slow records, is what is
known: its loop has absorbed part of the stage's lag (the converter delay, the mode's
phase) as a rate-independent width, so the static inverse already leads by part of what
G^-1 would add, and adding the whole G^-1 there makes the error larger (7 % at 10 Hz on
the paper-beam stage, docs/theory/learning.md). The correction G^-1 - 1 is therefore
faded in over the FADE_OCTAVES = 2 octaves above f_t,

    H_d(k) = R(k) (1 + W(f_k) (1 / G(z_k) - 1)),
    W(f) = clip(log2(f / f_t) / 2, 0, 1):   0 up to f_t, 1 from 4 f_t,

(f_k = k / N): at low rates the Hammerstein inverse is the static inverse, well within
the measured band the full one. Two octaves, not one: from f_t to a few f_t the
dynamics' correction of a scan's fundamental is a phase of a degree or less, the size of
the static model's own phase error on that fundamental (a loop width that is right to a
degree at the rate it was fitted at), and the two are correlated (the slow fit holds
part of the stage's lag as width), so the full correction there made the fundamental
worse (bench_learn.py, random stage 5003 at fmode/20 = 35 Hz: 0.5 % above the static
inverse with one octave, 0.7 % below with two; paper-beam at 40 Hz: 1.6 % below and 6 %
below). With f_t = 0 (the default) W = 1. The ZPETC path applies the
same W to h_d - r, by FFT over the trajectory with ``len(r)`` samples of rest on each
side (the correction is zero at rest: unit static gain).

**Order by order** (periodic trajectories). A model from :func:`fit_dynamics` also
records, per harmonic order k, from which frequency its records, each held back, showed
the correction to bring harmonic k closer than the static model alone
(``HammersteinModel.order_trusted_from``, pihyst.dynamics._on_static's notes). On line k
of a period the weight is then at most trust_weight from that frequency (0 where it is
0.5, "never", and on lines past the tuple's end): :func:`periodic_weight`. Where every
line's weight is 0, h_d is r itself. The ZPETC path has no harmonic orders and uses f_t
alone.

**The voltage's mean** (periodic trajectories, a model with ``static_offset``). The
correction changes the shape of h_d, not its mean (G(1) = 1), yet the hysteresis
inverse turns a change of shape into a change of the voltage's mean, du = mean(u_ham) -
mean(u_static): the static model's loop says that much is needed to hold the mean
output. The dynamics do not measure that (they act at DC as 1), and a stage whose loop
differs from the model's follows the mean voltage instead, its mean output moving by up
to g du (g = span(r) / span(u_static), the static inverse's mean slope): between the
two, the stage's mean output moves by x - lambda g du for a held-back part h = x / g of
du (u = u_ham - h) and an unknown lambda in [0, 1]. The static model's mean error on the
identification's slow record, E (``static_offset``, measured minus modelled), is what is
known of the scan's. :func:`held_mean` takes

    x = clip(E + g du / 2, between 0 and g du),

the x that keeps the worst mean error over lambda, max(|E - x|, |E + g du - x|), least
among the shifts between the model's (x = 0) and none (x = g du): when g |du| <= 2 |E|
the mean error is then never larger than the static inverse's |E|, whichever lambda;
otherwise at most g |du| / 2 (a second-order amount, where the static model is right at
DC). Random stage 7306 (a static model 1 um off at DC, the stage's mean following the
voltage's): the correction moved the mean voltage by 0.01-0.12 V, the stage's mean by
0.3 um/V, and the Hammerstein inverse was 0.2-0.4 % worse than the static inverse at
50-152 Hz although it reduced every other line's error; with the mean held, 0.2-2 %
better. Assumed: the scan's mean error has the sign of E where it matters (where |E| is
large against g |du|).

**The mean error** (the same models). The change of shape also moves the stage's mean
output through the stage's own loop, whatever the mean voltage does (random stage 7500:
the mean voltage held to 1e-4 V, the mean output 1.5-5 nm further onto a 3.6 um mean
error, 0.03-0.05 % above the static inverse although every other line improved). Per
unit of the correction's RMS, ||d|| = rms(h_d - r), that move was at most 0.17 on 34
simulated stages (either sign); MEAN_COUPLING = c = 0.2 bounds it. With the static
inverse's error E at DC plus the part d the correction removes, a share W of the
correction leaves at worst

    (|E| + c W ||d||)^2 + (1 - W)^2 ||d||^2  <=  E^2 + ||d||^2
    <=>  W (1 + c^2) <= 2 - 2 c |E| / ||d||,

so :func:`mean_error_share` applies W = clip((2 - 2 c |E| / ||d||) / (1 + c^2), 0, 1)
of it (E: ``static_offset``): all of it where the static model is right at DC or the
correction is large, none where its mean error dwarfs the correction. The cost: no gain
on stages whose static inverse is off by a micrometre or more at DC (random 7007, 7008,
7300 at 100 Hz: 0.97-0.99 of the static inverse before, 1 now).

A square MIMO :class:`StateSpaceHammerstein` (as many inputs as outputs) is compensated
the same way for a periodic trajectory of all outputs, R(k) a vector per line:

    H_d(k) = G(z_k)^-1 R(k)       (least squares where G(z_k) is singular),

then each input's hysteresis inverted on its own (its own limits and slew).
"""

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst.exceptions import InvalidArgumentError
from pihyst.inverse import compensate

ZERO_TOLERANCE = 1e-12   # leading coefficients of B below this (relative): pure delay
FADE_OCTAVES = 2.0       # the dynamics' correction fades in from f_t to 2**FADE_OCTAVES f_t


def _lfilter():
    from scipy.signal import lfilter
    return lfilter


def zpetc(a: ArrayLike, b: ArrayLike, r: ArrayLike,
          settle: int | None = None) -> NDArray[np.float64]:
    """The zero-phase error tracking prefilter h_d of the module notes (SISO).

    Parameters
    ----------
    a : array_like
        A(q^-1) = [1, a_1, ...].
    b : array_like
        B(q^-1), 1-D (its leading zeros a pure delay).
    r : array_like
        The reference trajectory.
    settle : int, optional
        Samples of ``r[0]`` held before the start (default: as many as ``r`` has).

    Returns
    -------
    ndarray
        h_d, as many samples as ``r``.

    Examples
    --------
    >>> from pihyst.dynamics import zpetc
    >>> zpetc([1.0, -0.5], [0.25, 0.25], [0.0, 1.0, 1.0, 1.0]).round(6).tolist()
    [1.0, 1.5, 1.0, 1.0]
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float).ravel()
    r = np.asarray(r, dtype=float)
    big = np.flatnonzero(np.abs(b) > ZERO_TOLERANCE * np.abs(b).max())
    d, c = int(big[0]), b[big[0]:big[-1] + 1]
    zeros = np.roots(c) if c.size > 1 else np.zeros(0)
    unstable = np.abs(zeros) >= 1.0
    bs = c[0] * np.atleast_1d(np.real(np.poly(zeros[~unstable])))
    bu = np.atleast_1d(np.real(np.poly(zeros[unstable])))
    nu = bu.size - 1
    lead = d + nu
    # the trajectory held at its ends: before the start (rest) and past the end
    pre = r.size if settle is None else int(settle)
    ext = np.r_[np.full(pre, r[0]), r, np.full(lead, r[-1])]
    h = _lfilter()(np.convolve(a, bu[::-1]), bs, ext) / bu.sum() ** 2
    return h[pre + lead:pre + lead + r.size]


def trust_weight(f: ArrayLike, trusted_from: float) -> NDArray[np.float64]:
    """W(f) of the module notes: the share of the dynamics' correction applied at the
    frequencies ``f`` (cycles per sample) of a model measured from ``trusted_from`` up.

    Parameters
    ----------
    f : array_like
        Frequencies, cycles per sample (>= 0).
    trusted_from : float
        f_t, cycles per sample; 0: W = 1 everywhere.

    Returns
    -------
    ndarray
        W, between 0 and 1.

    Examples
    --------
    >>> from pihyst.dynamics import trust_weight
    >>> trust_weight([0.0, 0.01, 0.02, 0.03, 0.04, 0.3], 0.01).round(3).tolist()
    [0.0, 0.0, 0.5, 0.792, 1.0, 1.0]
    """
    return _trust_weight_from(f, trusted_from)


def _faded(r, h_d, trusted_from):
    """r + W (h_d - r) for a trajectory that is at rest before and after (ZPETC path)."""
    if not trusted_from > 0:
        return h_d
    r = np.asarray(r, dtype=float)
    n = r.size
    d = np.r_[np.zeros(n), h_d - r, np.zeros(n)]
    W = trust_weight(np.fft.rfftfreq(d.size), trusted_from)
    return r + np.fft.irfft(W * np.fft.rfft(d), d.size)[n:2 * n]


def periodic_weight(n: int, trusted_from: float = 0.0,
                    order_trusted_from: Any = ()) -> NDArray[np.float64]:
    """W on the rfft lines k = 0 .. n // 2 of an n-sample period (module notes): on line
    k, :func:`trust_weight` of k / n from ``trusted_from`` and, when
    ``order_trusted_from`` is given, at most its weight from that tuple's entry k
    (an entry of 0.5: 0; lines past its end: 0).

    Parameters
    ----------
    n : int
        Samples per period.
    trusted_from : float
        f_t, cycles per sample (0: no limit).
    order_trusted_from : sequence of float
        Per harmonic order k = 1, 2, ..., where its weight starts (cycles per sample).

    Returns
    -------
    ndarray
        W per line, between 0 and 1.

    Examples
    --------
    >>> from pihyst.dynamics import periodic_weight
    >>> periodic_weight(8, 0.01).round(3).tolist()
    [0.0, 1.0, 1.0, 1.0, 1.0]
    >>> periodic_weight(8, 0.01, (0.0625, 0.5, 0.09375)).round(3).tolist()
    [0.0, 0.5, 0.0, 1.0, 0.0]
    """
    f = np.arange(n // 2 + 1) / n
    W = trust_weight(f, trusted_from)
    orders = np.asarray(order_trusted_from, dtype=float).ravel()
    if orders.size:
        start = np.full(W.size, 0.5)
        m = min(orders.size, W.size - 1)
        start[1:m + 1] = orders[:m]
        W = np.minimum(W, np.where(start >= 0.5, 0.0, _trust_weight_from(f, start)))
    return W


def _trust_weight_from(f, start):
    """:func:`trust_weight` with a start per frequency (1 where it is not above 0)."""
    f, start = np.broadcast_arrays(np.asarray(f, dtype=float), np.asarray(start, dtype=float))
    out = np.ones(f.shape)
    some = start > 0
    # log2 f - log2 f_t, not log2(f / f_t): the quotient overflows for a subnormal f_t
    with np.errstate(divide="ignore"):
        out[some] = np.clip((np.log2(f[some]) - np.log2(start[some])) / FADE_OCTAVES,
                            0.0, 1.0)
    return out


def periodic_inverse_dynamics(a: ArrayLike, b: ArrayLike, r: ArrayLike,
                              trusted_from: float = 0.0,
                              order_trusted_from: Any = ()) -> NDArray[np.float64]:
    """The exact inverse of the dynamics for one period ``r`` of a periodic reference
    (SISO; module notes: H_d(k) = R(k) / G(z_k), faded out below ``trusted_from`` and,
    on the period's k-th harmonic, below ``order_trusted_from[k - 1]``).

    Parameters
    ----------
    a : array_like
        A(q^-1) = [1, a_1, ...].
    b : array_like
        B(q^-1), 1-D or one row.
    r : array_like
        One period of the reference.
    trusted_from : float
        f_t of the module notes (cycles per sample; needs unit static gain); 0: the
        whole inverse at every frequency.
    order_trusted_from : sequence of float
        Per harmonic order, where the correction starts on it (module notes, "Order by
        order"; ``HammersteinModel.order_trusted_from``); empty: ``trusted_from`` alone.

    Returns
    -------
    ndarray
        One period of h_d, as many samples as ``r``.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import periodic_inverse_dynamics, predict_linear
    >>> r = 10 + 5 * np.sin(2 * np.pi * np.arange(50) / 50)
    >>> h = periodic_inverse_dynamics([1.0, -0.5], [0.5], r)
    >>> y = predict_linear([[1.0, -0.5]], [[[0.5]]], np.tile(h, 3))[100:, 0]
    >>> bool(np.allclose(y, r))
    True
    """
    from pihyst.dynamics._linear import response
    r = np.asarray(r, dtype=float)
    G = response(np.asarray(a, dtype=float), np.atleast_2d(np.asarray(b, dtype=float)),
                 r.size)[:, 0]
    R = np.fft.rfft(r)
    usable = np.abs(G) > 1e-9 * np.abs(G).max()
    H = np.where(usable, R / np.where(usable, G, 1.0), 0.0)
    W = periodic_weight(r.size, trusted_from, order_trusted_from)
    # r plus the correction: exactly r where W is 0 on every line
    return r + np.fft.irfft(W * (H - R), r.size)


#: the most a zero-mean change of a stage's drive shape moves its mean output, per unit of
#: the change's RMS (measured on 34 simulated stages, 0.17 at most: module notes)
MEAN_COUPLING = 0.2


def mean_error_share(r: ArrayLike, h_d: ArrayLike, static_offset: float | None,
                     coupling: float = MEAN_COUPLING) -> float:
    """The share W of the dynamics' correction h_d - r that cannot make the error worse
    through the stage's mean output (module notes, "The mean error"):
    W = clip((2 - 2 c |E| / rms(h_d - r)) / (1 + c^2), 0, 1), c = MEAN_COUPLING,
    E = ``static_offset``; 1 where it is None.

    Parameters
    ----------
    r : array_like
        One period of the trajectory.
    h_d : array_like
        One period of the hysteresis output the dynamics need.
    static_offset : float or None
        The static model's mean error (``HammersteinModel.static_offset``).
    coupling : float
        c, the bound on the stage's mean coupling (>= 0; 0: W = 1, the correction
        applied on trust).

    Returns
    -------
    float
        W, between 0 and 1.

    Examples
    --------
    >>> from pihyst.dynamics import mean_error_share
    >>> r = [0.0, 1.0, 2.0, 1.0]
    >>> mean_error_share(r, [0.1, 1.1, 1.9, 0.9], 0.0), mean_error_share(r, r, 1.0)
    (1.0, 0.0)
    >>> round(mean_error_share(r, [0.1, 1.1, 1.9, 0.9], 0.3), 3)
    0.769
    """
    c = float(coupling)
    if not c >= 0:
        raise InvalidArgumentError(f"mean_coupling must be >= 0, got {coupling!r}")
    if static_offset is None or c == 0:
        return 1.0
    size = float(np.sqrt(np.mean(np.square(np.asarray(h_d, dtype=float)
                                             - np.asarray(r, dtype=float)))))
    if not size > 0:
        return 0.0
    return float(np.clip((2 - 2 * c * abs(static_offset) / size) / (1 + c * c), 0.0, 1.0))


def held_mean(u_ham: ArrayLike, u_static: ArrayLike, r: ArrayLike,
              static_offset: float | None, u_min: float | None = None,
              u_max: float | None = None) -> NDArray[np.float64]:
    """One period of the Hammerstein inverse's voltage with its mean moved only as far as
    the static model's mean error proves safe (module notes, "The voltage's mean").

    Parameters
    ----------
    u_ham : array_like
        One period of the Hammerstein inverse's voltage.
    u_static : array_like
        One period of the static inverse's voltage for the same trajectory.
    r : array_like
        One period of the trajectory.
    static_offset : float or None
        E of the module notes (``HammersteinModel.static_offset``); None: ``u_ham``.
    u_min, u_max : float, optional
        Voltage limits (the result is clipped into them).

    Returns
    -------
    ndarray
        u_ham - x / g, as many samples as ``u_ham``.

    Examples
    --------
    >>> from pihyst.dynamics import held_mean
    >>> r, u_static = [0.0, 1.0, 2.0, 1.0], [0.0, 10.0, 20.0, 10.0]
    >>> held_mean([1.0, 11.0, 21.0, 11.0], u_static, r, 0.5).tolist()   # E > 0: held
    [0.0, 10.0, 20.0, 10.0]
    >>> held_mean([1.0, 11.0, 21.0, 11.0], u_static, r, -0.5).tolist()  # E < 0: kept
    [1.0, 11.0, 21.0, 11.0]
    """
    u_ham = np.asarray(u_ham, dtype=float)
    if static_offset is None:
        return u_ham
    u_static = np.asarray(u_static, dtype=float)
    span = float(np.ptp(u_static))
    if not span > 0:
        return u_ham
    g = float(np.ptp(np.asarray(r, dtype=float))) / span
    s = g * float(np.mean(u_ham) - np.mean(u_static))
    x = float(np.clip(static_offset + s / 2, min(0.0, s), max(0.0, s)))
    u = u_ham - (x / g if g > 0 else 0.0)
    lo = -np.inf if u_min is None else u_min
    hi = np.inf if u_max is None else u_max
    return np.clip(u, lo, hi)


def periodic_inverse_mimo(model, r):
    """H_d of the module notes for one period ``r`` (N, p) of all outputs of a square
    state-space Hammerstein model: (N, m)."""
    r = np.asarray(r, dtype=float)
    R = np.fft.rfft(r, axis=0)
    w = 2 * np.pi * np.arange(R.shape[0]) / r.shape[0]
    G = model.dynamics.response(w)
    H = np.stack([np.linalg.lstsq(G[k], R[k], rcond=None)[0] for k in range(R.shape[0])])
    return np.fft.irfft(H, n=r.shape[0], axis=0)


def _per_input(value, m, name):
    """``value`` (None, one number or one per input) as a list of m."""
    if value is None:
        return [None] * m
    values = np.atleast_1d(np.asarray(value, dtype=float))
    if values.size == 1:
        values = np.repeat(values, m)
    if values.shape != (m,):
        raise InvalidArgumentError(f"{name}: one value or one per input ({m}), got "
                                   f"{values.size}")
    return [float(v) for v in values]


def compensate_mimo(model: Any, desired: ArrayLike, *, u_min: ArrayLike | None = None,
                    u_max: ArrayLike | None = None, slew_rate: ArrayLike | None = None,
                    sample_period: float | None = None
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64], list[Any]]:
    """Voltages that make a square :class:`StateSpaceHammerstein` follow one period of a
    repeated trajectory: the dynamics inverted per harmonic, then each input's
    hysteresis inverted over two periods (the second returned), within its limits and
    slew.

    A :class:`ScheduledStateSpace` (dynamics whose modes follow the drive amplitude) is
    compensated by :func:`compensate_scheduled` (``u_min`` and ``u_max`` required, no
    ``slew_rate``); the tuple is then (voltage, voltage, [ScheduledCompensation]).

    Parameters
    ----------
    model : StateSpaceHammerstein or ScheduledStateSpace
        As many inputs as outputs.
    desired : array_like
        (N, p) one period of every output's trajectory.
    u_min, u_max : float or array_like, optional
        Voltage limits: one value or one per input (default: the models' input ranges).
    slew_rate : float or array_like, optional
        V/s: one value or one per input.
    sample_period : float, optional
        Seconds between samples (needed with ``slew_rate``).

    Returns
    -------
    voltage : ndarray
        (N, m) one period of voltages.
    h_desired : ndarray
        (N, m) the hysteresis outputs the dynamics need.
    results : list of CompensationResult
        :func:`pihyst.compensate`'s result per input (over two periods).

    Raises
    ------
    InvalidArgumentError
        A model that is not square, or ``desired`` or limits of the wrong shape.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst import ClassicalPI
    >>> from pihyst.dynamics import StateSpace, StateSpaceHammerstein, compensate_mimo
    >>> model = StateSpaceHammerstein((ClassicalPI([0.0], [1.0]), ClassicalPI([0.0], [1.0])),
    ...                               StateSpace(0.5 * np.eye(2), np.eye(2), 0.5 * np.eye(2),
    ...                                          np.zeros((2, 2))))
    >>> t = np.arange(40)
    >>> desired = np.column_stack([10 + np.sin(2 * np.pi * t / 40), 20 + 0 * t])
    >>> voltage, h, results = compensate_mimo(model, desired)
    >>> y = model.predict(np.tile(voltage, (3, 1)))[80:]
    >>> bool(np.allclose(y, desired))
    True
    """
    from pihyst.dynamics._scheduled import ScheduledStateSpace
    if isinstance(model, ScheduledStateSpace):
        from pihyst.dynamics._compensate_scheduled import compensate_mimo_scheduled
        return compensate_mimo_scheduled(model, desired, u_min, u_max, slew_rate)
    m, p = model.n_inputs, model.n_outputs
    if m != p:
        raise InvalidArgumentError(f"compensate_mimo needs as many inputs as outputs, got "
                                   f"{m} input(s) and {p} output(s)")
    desired = np.asarray(desired, dtype=float)
    if desired.ndim != 2 or desired.shape[1] != p or desired.shape[0] < 2:
        raise InvalidArgumentError(f"desired must be (N, {p}): one column per output, got "
                                   f"shape {desired.shape}")
    lows, highs = _per_input(u_min, m, "u_min"), _per_input(u_max, m, "u_max")
    slews = _per_input(slew_rate, m, "slew_rate")
    h_d = periodic_inverse_mimo(model, desired)
    n = desired.shape[0]
    results = [compensate(H, np.tile(h_d[:, i], 2), u_min=lows[i], u_max=highs[i],
                          slew_rate=slews[i], sample_period=sample_period)
               for i, H in enumerate(model.hysteresis)]
    voltage = np.column_stack([res.voltage[n:] for res in results])
    return voltage, h_d, results


def compensate_hammerstein(model: Any, desired: ArrayLike, *, u_min: float | None = None,
                           u_max: float | None = None, slew_rate: float | None = None,
                           sample_period: float | None = None, periodic: bool = False,
                           mean_coupling: float = MEAN_COUPLING
                           ) -> tuple[NDArray[np.float64], NDArray[np.float64], Any]:
    """Voltages that make a SISO :class:`HammersteinModel` follow ``desired``: the
    ZPETC prefilter, then the hysteresis inverse from the hysteresis model's initial
    state (module notes; the dynamics' correction faded out below the model's
    ``trusted_from``).

    Parameters
    ----------
    model : HammersteinModel
        One input, one output.
    desired : array_like
        The desired output; with ``periodic``, one period of a repeated trajectory.
    u_min, u_max : float, optional
        Voltage limits, as for :func:`pihyst.compensate`.
    slew_rate : float, optional
        V/s, as for :func:`pihyst.compensate`.
    sample_period : float, optional
        Seconds between samples (needed with ``slew_rate``).
    periodic : bool
        Invert the dynamics exactly per harmonic, and the hysteresis over two periods
        (the second returned, from which the hysteresis memory repeats); with the
        model's ``static_offset``, the voltage's mean then moved only as far as
        :func:`held_mean` allows (a constant shift within the limits: the slew is
        unchanged).
    mean_coupling : float
        With ``periodic`` and the model's ``static_offset``: the bound on how far the
        stage's mean output follows a change of the drive's shape, per unit of the
        correction's RMS (:func:`mean_error_share`; default MEAN_COUPLING = 0.2); 0:
        the whole correction where the held-back rules allow it.

    Returns
    -------
    voltage : ndarray
        The voltages, as many as ``desired``.
    h_desired : ndarray
        The hysteresis output the dynamics need.
    result : CompensationResult
        :func:`pihyst.compensate`'s result (over two periods with ``periodic``; before
        :func:`held_mean`).

    Raises
    ------
    InvalidArgumentError
        A model that is not single-input single-output.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst import ClassicalPI
    >>> from pihyst.dynamics import HammersteinModel, compensate_hammerstein
    >>> model = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
    ...                          a=([1.0, -0.5],), b=([[0.5]],))
    >>> r = 10 + 5 * np.sin(2 * np.pi * np.arange(50) / 50)
    >>> voltage, h, result = compensate_hammerstein(model, r, periodic=True)
    >>> y = model.predict(np.tile(voltage, 3))[100:, 0]
    >>> bool(np.allclose(y, r))
    True
    """
    if model.n_inputs != 1 or model.n_outputs != 1:
        raise InvalidArgumentError(f"compensate_hammerstein needs a single-input "
                                   f"single-output model, got {model.n_inputs} input(s) and "
                                   f"{model.n_outputs} output(s)")
    H = model.hysteresis[0]
    if not periodic:
        h_d = _faded(desired, zpetc(model.a[0], model.b[0][0], desired),
                     getattr(model, "trusted_from", 0.0))
        res = compensate(H, h_d, u_min=u_min, u_max=u_max, slew_rate=slew_rate,
                         sample_period=sample_period)
        return res.voltage, h_d, res
    desired = np.asarray(desired, dtype=float)
    h_d = periodic_inverse_dynamics(model.a[0], model.b[0][0], desired,
                                    getattr(model, "trusted_from", 0.0),
                                    getattr(model, "order_trusted_from", ()))
    offset = getattr(model, "static_offset", None)
    h_d = desired + mean_error_share(desired, h_d, offset, mean_coupling) * (h_d - desired)
    res = compensate(H, np.tile(h_d, 2), u_min=u_min, u_max=u_max, slew_rate=slew_rate,
                     sample_period=sample_period)
    voltage = res.voltage[h_d.size:]
    if offset is not None:
        static = compensate(H, np.tile(desired, 2), u_min=u_min, u_max=u_max,
                            slew_rate=slew_rate, sample_period=sample_period)
        voltage = held_mean(voltage, static.voltage[desired.size:], desired, offset,
                            u_min=u_min, u_max=u_max)
    return voltage, h_d, res
