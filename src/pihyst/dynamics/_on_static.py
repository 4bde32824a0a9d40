"""Linear dynamics after a given static model: a Hammerstein model whose hysteresis is a
model fitted on slow records (``pihyst.fit``, any family) and whose dynamics are measured
by playing one periodic drive shape at several rates (docs/theory/hammerstein.md,
"Dynamics after a static model").

Why not fit the dynamics on y against the static model's output H[u]: the static model is
not exact (its loop's width and slope on the drive used are off by a few per cent), and a
fit of G on (H[u], y) takes that error for dynamics: a phase lag half the true one on a
resonant stage, a gain 12 % off on a beam's minor loops, poles fitted to it between the
lines the records excite. The inverse built on such a G then undoes errors the static
inverse did not make, and is worse than the static inverse at low rates.

The ratio of two rates does not see the hysteresis. Play one period u(theta) of a drive
shape (phase theta = t / T) at a slow rate and at faster ones, each in periodic steady
state. A rate-independent hysteresis gives the same output per phase at every rate, so
its harmonics H_k are the same in every record, and on harmonic k

    Y_slow,k = G(k f_slow) H_k ~= H_k     (k f_slow far below the dynamics),
    Y_f,k    = G(k f) H_k,

    =>  Y_f,k = G(k f) Y_slow,k,                                    (ratio model)

whatever H is: neither the static model nor its error enters. G = B(q^-1) / A(q^-1) is
fitted to these by the output-error fit of :func:`pihyst.dynamics._linear.fit_oe_periodic`
(the harmonics of every fast record placed on the lines of a common period that all their
periods divide; nothing on the others), with G(1) = 1 as one more data point: the DC
line, weighted like all the harmonics together.

The order. Each candidate (na, nb) is fitted on all fast records but one, each fast record
held back in turn (``validation="each"``); an order clearly beats another when its output
error summed over the held-back records is lower by more than ``tolerance`` (5 %) and
it is the lower on more than half of them, and the first candidate (the simplest) that
no other clearly beats wins and is refitted on all. One held-back record alone (the
former rule, ``validation=-1``) is a noisy judge (tests/dynamics/test_on_static.py: on
noisy records of a (2, 3) system it picks higher orders on some seeds, this rule on none).

The poles are the stage's. With them fixed, B is refitted on the static model's own
output over the same records (``numerator_on_static``, the default): on each record's
drive harmonics Y_k A(z_k) = B(z_k) H_k, H_k the harmonics of H[u], linear least squares
in b. The numerator then also takes what the static model gets wrong at these rates as
a linear correction (a loop too wide by a converter delay the slow fit absorbed acts as
a phase lead; the ratio model, which does not see the static model, would expose it),
while the poles, measured without the static model, cannot move to fit it. Then

    B <- B A(1) / B(1):   G(1) = 1.

The static model holds the gain at rest; the dynamics add only what changes with rate. As
the rate goes to zero the Hammerstein inverse becomes the static inverse (h_d -> r).

Creep (``sample_period=``). The ratio assumes the static part gives the same output per
phase at every rate; creep does not: its fast lags (time constants of 0.1 s and up) lag
the slow record's harmonics more than the fast ones'. The ratio then takes the creep's
change between the rates for dynamics (on one random stage a real pole at 1.8 Hz, whose
inverse made the Hammerstein inverse 28 % worse than the static one at 50 Hz), and a
compensator that inverts the static model's creep as well undoes it twice. With the
records' sample period the static model's own periodic output with its creep, C_k (lags
settled at the period's mean), is computed per record, and the ratio is taken relative
to what it predicts between the rates:

    Y_f,k = G(k f) Y_slow,k C_f,k / C_slow,k,

the hysteresis cancelling in C_f,k / C_slow,k as in the ratio itself; the numerator is
refitted on C_k, the output the compensator inverts. Without creep C_f,k / C_slow,k = 1.

Below the slowest fast record's fundamental f_t = 1 / n (n its samples per period) the
dynamics are not measured: only the slow record's harmonics (where G ~ 1 to within the
static model's own error) and G(1) = 1 pin them. The model records f_t
(``HammersteinModel.trusted_from``, ``fade=True``) and the compensators leave the
dynamics' correction out below it and fade it in over the two octaves above
(:func:`pihyst.dynamics.trust_weight`): the static model, fitted on slow records, has
absorbed part of the stage's lag as loop width, which the full G^-1 would add a second
time; up to a few f_t the correction of a scan's fundamental is no larger than the
static model's own phase error there (pihyst.dynamics._compensate's notes).

Held back, order by order (``HammersteinModel.order_trusted_from``). The static model
is not exact either: its loop, fitted through the stage's lag, is off by a phase of up
to a few degrees on the drive's fundamental, the same at every rate. Where the
dynamics' lag on a harmonic is less than about twice that, correcting the dynamics
leaves the static model's error bare and the harmonic is worse than with the static
inverse alone. The records say where: with the chosen order refitted without fast
record i, on each drive harmonic k of that record the compensator's error would be

    static inverse:       |Y_k / C_k - 1|,
    Hammerstein inverse:  |Y_k / (G(z_k) C_k) - 1|

(C_k the static model's output, with its creep where given). The correction of a
period's k-th harmonic then starts at k / n of the fastest record (n its samples per
period) on whose harmonic k it lost, faded in over FADE_OCTAVES above; where it lost on
none, at k / n of the slowest record (where harmonic k was first measured); never where
it lost on the fastest record (nothing above says it helps) or on harmonics the drive
does not have, nor on harmonics past the drive's last (not measured). Between the
static inverse and the whole correction the error on a harmonic is no larger than the
larger of the two (it is affine in the weight), so a partial weight where the whole
correction wins still wins. At low rates the periodic Hammerstein inverse is then
exactly the static inverse. Assumed: the scan has the identification drive's shape
(the static model's error per harmonic order carries over from one to the other).

The mean (``HammersteinModel.static_offset``). The rule above judges the drive's
harmonics only. The correction also moves the compensator's mean voltage (the
hysteresis inverse of another shape), which the dynamics do not measure and the stage
may follow where the static model says it should not; where the static model is off at
DC that adds to its largest error (random stage 7306: 1 um off, 0.2-0.4 % worse than the
static inverse from 50 Hz). The model records the static model's mean error on the slow
record, mean(y_slow - C_slow) (with its creep where given), and the periodic
compensation moves the mean voltage only as far as that error proves safe
(:func:`pihyst.dynamics.held_mean`, pihyst.dynamics._compensate's notes).
"""

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from pihyst.dynamics._hammerstein import HammersteinModel
from pihyst.dynamics._linear import fit_oe_periodic, response
from pihyst.exceptions import InvalidArgumentError

#: (na, nb) tried: a mode, a mode and a lag, two modes, each with a zero or two more
DEFAULT_ORDERS = ((2, 2), (2, 3), (4, 4), (4, 5), (6, 6))
SHAPE_TOLERANCE = 1e-3     # of the largest drive harmonic: the records' shapes must agree
HARMONIC_FLOOR = 1e-3      # drive harmonics below this (of the largest) are not used
MAX_COMMON_PERIOD = 1_000_000
#: a higher order must fit the held-back records this much better to be chosen
ORDER_TOLERANCE = 0.05


def _plain(model):
    """The static model without creep and input delay (the dynamics measure both)."""
    if getattr(model, "creep", None) is not None:
        model = model.replace(creep=None)
    if getattr(model, "delay", 0):
        model = model.replace(delay=0)
    return model


#: creep lags up to this many periods are settled by running the period (longer ones
#: start, and stay, at the period's mean), and at most this many samples are run
CREEP_SETTLED_PERIODS, CREEP_MAX_SAMPLES = 10, 100_000


def _creep_output(static, sample_period):
    """u -> the static model's output over one settled period of u with its creep, or
    None without creep or without ``sample_period``. As the learning's periodic inverse
    runs it (pihyst.learn._model_parts): the lags start at the period's mean hysteresis
    output, and P periods are run, P long enough for three time constants of the lags up
    to CREEP_SETTLED_PERIODS periods (at most CREEP_MAX_SAMPLES samples); the last is
    returned."""
    if sample_period is None or getattr(static, "creep", None) is None:
        return None
    model = static.replace(delay=0) if getattr(static, "delay", 0) else static
    plain = model.replace(creep=None)
    T = float(sample_period)

    def output(u):
        n = u.size
        h = plain.predict(np.tile(u, 2))[n:]
        taus = [tau for tau in model.creep.tau if tau <= CREEP_SETTLED_PERIODS * n * T]
        p = 2 + (int(np.ceil(3 * max(taus) / (n * T))) if taus else 0)
        p = int(min(p, max(2, CREEP_MAX_SAMPLES // n)))
        y = model.predict(np.tile(u, p), t=np.arange(p * n) * T,
                          creep_state=np.full(len(model.creep.tau), float(np.mean(h))))
        return y[-n:]
    return output


def _one_period(record, i):
    u, y = (np.asarray(v, dtype=float).ravel() for v in record)
    if u.size != y.size or u.size < 4:
        raise InvalidArgumentError(f"record {i}: {u.size} input and {y.size} output "
                                   f"samples; need one period (at least 4) of both")
    return u, y


def _harmonics(slow):
    """The drive harmonics k used (those above HARMONIC_FLOOR of the largest, k >= 1)."""
    U = np.fft.rfft(slow[0])[1:]
    return 1 + np.flatnonzero(np.abs(U) > HARMONIC_FLOOR * np.abs(U).max())


def _ratio_spectra(slow, fast, ks, period, static_output=None):
    """(V, Y) per fast record on the lines of ``period``: V = Y_slow,k, Y = Y_f,k; with
    ``static_output`` (u -> the static model's periodic output, its creep included),
    V = Y_slow,k C_f,k / C_slow,k (module notes, "Creep")."""
    U0, Y0 = (np.fft.rfft(v)[ks] / v.size for v in slow)
    if static_output is not None:
        C0 = np.fft.rfft(static_output(slow[0]))[ks] / slow[0].size
    out = []
    for i, (u, y) in enumerate(fast):
        n = u.size
        if ks.max() >= n / 2:
            raise InvalidArgumentError(f"record {i}: {n} samples per period hold no "
                                       f"harmonic {ks.max()} of the drive (need more than "
                                       f"{2 * ks.max()})")
        U, Y = np.fft.rfft(u)[ks] / n, np.fft.rfft(y)[ks] / n
        if np.max(np.abs(U - U0)) > SHAPE_TOLERANCE * np.abs(U0).max():
            raise InvalidArgumentError(f"record {i}: not the slow record's drive shape "
                                       f"(its harmonics differ by more than "
                                       f"{SHAPE_TOLERANCE:g} of the largest)")
        V_line = np.zeros(period // 2 + 1, complex)
        Y_line = np.zeros(period // 2 + 1, complex)
        V_line[ks * (period // n)] = Y0
        if static_output is not None:
            V_line[ks * (period // n)] *= (np.fft.rfft(static_output(u))[ks] / n) / C0
        Y_line[ks * (period // n)] = Y
        out.append((V_line[:, None], Y_line))
    return out


def _unit_dc(spectra, period):
    """G(1) = 1 as data: the DC line, weighted like all the harmonics together."""
    w = math.sqrt(sum(float(np.sum(np.abs(V) ** 2)) for V, _ in spectra))
    V, Y = np.zeros(period // 2 + 1, complex), np.zeros(period // 2 + 1, complex)
    V[0] = Y[0] = w
    return (V[:, None], Y)


def _output_error(a, b, spectra, period):
    G = response(a, b, period)[:, 0]
    return float(sum(np.sum(np.abs(Y - G * V[:, 0]) ** 2) for V, Y in spectra))


def _numerator_on_static(a, nb, records, outputs):
    """B with A fixed, fitted on the static model's output: on the drive harmonics k of
    each record (u, y), Y_k A(z_k) = B(z_k) H_k with H_k of h (``outputs``, the static
    model's settled period for u), linear least squares in b (z_k = exp(-2 pi i k / n))."""
    rows, target = [], []
    for (u, y), h in zip(records, outputs):
        n = u.size
        U = np.fft.rfft(u)[1:(n + 1) // 2]
        k = 1 + np.flatnonzero(np.abs(U) > HARMONIC_FLOOR * np.abs(U).max())
        z = np.exp(-2j * np.pi * np.outer(k, np.arange(max(a.size, nb))) / n)
        M = z[:, :nb] * (np.fft.rfft(h)[k] / (z[:, :a.size] @ a))[:, None] / n
        Y = np.fft.rfft(y)[k] / n
        rows += [M.real, M.imag]
        target += [Y.real, Y.imag]
    return np.linalg.lstsq(np.vstack(rows), np.concatenate(target), rcond=None)[0][None, :]


def _fit_ratio(spectra, na, nb, period):
    """(a, b) of the ratio model on ``spectra`` with G(1) = 1 as one more data point."""
    return fit_oe_periodic(spectra + [_unit_dc(spectra, period)], na, nb, period)


def _choose_order(spectra, orders, period, tolerance, held):
    """The first of ``orders`` that no other clearly beats on the records ``held``, each
    held back in turn with the order fitted on the others: an order clearly beats another
    when its output error summed over them is below the other's by more than
    ``tolerance`` (relative) and it is the lower on more than half of them (module
    notes; noise-free data: errors within 1e-9 of the records' output count as equal)."""
    errors = np.zeros((len(orders), len(held)))
    for col, i in enumerate(held):
        fit_on = [s for j, s in enumerate(spectra) if j != i]
        errors[:, col] = [_output_error(*_fit_ratio(fit_on, na, nb, period), [spectra[i]],
                                        period) for na, nb in orders]
    floor = 1e-9 * math.sqrt(sum(float(np.sum(np.abs(spectra[i][1]) ** 2)) for i in held))
    errors = np.sqrt(errors)
    total = np.sqrt(np.sum(errors ** 2, axis=1))

    def beats(o, c):
        return (total[o] * (1 + tolerance) + floor < total[c]
                and np.sum(errors[o] + floor < errors[c]) > len(held) / 2)
    for c in range(len(orders)):
        if not any(beats(o, c) for o in range(len(orders))):
            return orders[c]
    return orders[int(np.argmin(total))]      # not reached: the least total is not beaten


#: order_trusted_from's value for an order the dynamics' correction never applies to
NEVER = 0.5


def _dynamics(spectra, na, nb, period, refit, records, outputs):
    """(a, b) with unit static gain: the ratio fit on ``spectra``, then (``refit``) the
    numerator on the static model's ``outputs`` of ``records``."""
    a, b = _fit_ratio(spectra, na, nb, period)
    if refit:
        b = _numerator_on_static(a, nb, records, outputs)
    gain = float(np.sum(b) / np.sum(a))
    if not abs(gain) > 1e-12:
        raise InvalidArgumentError("the fitted dynamics have no static gain (B(1) = 0)")
    return a, b / gain


def _order_trust(spectra, na, nb, period, refit, slow, fast, outputs, ks):
    """order_trusted_from (module notes, "Held back, order by order"): per harmonic order
    k = 1..max(ks), the frequency (cycles per sample) from which the dynamics'
    correction is applied on a period's k-th harmonic: k / n of the fastest record
    (n its samples per period) whose k-th harmonic the correction, fitted without that
    record, does not bring closer to the measured output than the static model alone,
    else k / n of the slowest record; NEVER where the fastest record fails or the
    drive has no harmonic k."""
    better = np.zeros((len(fast), ks.size), bool)
    for i, (u, y) in enumerate(fast):
        keep = [j for j in range(len(fast)) if j != i]
        a, b = _dynamics([spectra[j] for j in keep], na, nb, period, refit,
                         [slow] + [fast[j] for j in keep],
                         [outputs[0]] + [outputs[1 + j] for j in keep])
        n = u.size
        Y, C = np.fft.rfft(y)[ks] / n, np.fft.rfft(outputs[1 + i])[ks] / n
        z = np.exp(-2j * np.pi * np.outer(ks, np.arange(max(a.size, b.shape[1]))) / n)
        G = (z[:, :b.shape[1]] @ b[0]) / (z[:, :a.size] @ a)
        # the compensator's error on line k: the static inverse makes Y / C of R, the
        # Hammerstein inverse Y / (G C) of R
        better[i] = np.abs(Y / (G * C) - 1) < np.abs(Y / C - 1)
    sizes = np.array([u.size for u, _ in fast])
    fastest = int(np.argmin(sizes))
    trust = np.full(int(ks.max()), NEVER)
    for j, k in enumerate(ks):
        failing = sizes[~better[:, j]]
        if not better[fastest, j]:
            continue
        trust[k - 1] = k / (failing.min() if failing.size else sizes.max())
    return tuple(float(t) for t in trust)


def fit_dynamics(static: Any, slow: tuple[Any, Any], fast: Sequence[tuple[Any, Any]], *,
                 orders: Sequence[Sequence[int]] = DEFAULT_ORDERS,
                 validation: int | str | None = "each", tolerance: float = ORDER_TOLERANCE,
                 numerator_on_static: bool = True, keep_creep: bool = False,
                 fade: bool = True, sample_period: float | None = None) -> HammersteinModel:
    """A SISO :class:`HammersteinModel`: ``static`` (without creep and delay) followed by
    unit-static-gain dynamics measured by the ratio of rates (module notes).

    Parameters
    ----------
    static : PIModel or BoucWenModel
        The static model (``pihyst.fit``, any family).
    slow : (array_like, array_like)
        ``(u, y)``, one period of the drive at a rate far below the dynamics (its
        harmonics where G ~ 1), in periodic steady state.
    fast : sequence of (array_like, array_like)
        ``(u, y)`` pairs, one period each of the same drive shape at faster rates (the
        same harmonics, another number of samples per period).
    orders : sequence of (int, int)
        The candidate (na, nb).
    validation : "each", int or None
        "each": every fast record held back in turn chooses the order (module notes,
        "The order"); an index: that record alone (the first of ``orders`` whose output
        error there is within ``tolerance`` of the best); None takes the first of
        ``orders``. Errors within 1e-9 of the output (noise-free data) count as equal.
    tolerance : float
        Relative, as above.
    numerator_on_static : bool
        Then refit B, the poles kept, on the static model's output (module notes).
    keep_creep : bool
        The returned model's hysteresis keeps the static model's creep (for
        :func:`pihyst.learn.learn_periodic`, which runs it on the period's time base;
        :meth:`HammersteinModel.predict` and :func:`compensate_hammerstein` do not time
        it: leave it off for them). The dynamics are fitted without it either way.
    fade : bool
        Record the slowest fast record's fundamental (cycles per sample) as the
        model's ``trusted_from``, below which the compensators fade the dynamics'
        correction out, and (with two fast records or more) per harmonic order where
        the held-back records show the correction to help, ``order_trusted_from``,
        and the static model's mean error on the slow record, ``static_offset``
        (module notes); False: none of them, the whole inverse everywhere.
    sample_period : float, optional
        The records' sample period (s). With a static model with creep, the dynamics
        are then measured relative to the creep the static model predicts between the
        rates, and the numerator refitted on its output with that creep (module notes,
        "Creep"): for compensators that invert the creep too (the learning's periodic
        inverse, ``keep_creep``). Without it the creep is left out of both.

    Returns
    -------
    HammersteinModel
        One input, one output, the dynamics' static gain 1.

    Raises
    ------
    InvalidArgumentError
        No fast record, orders that are not valid, a constant drive, periods without a
        small common multiple, dynamics without static gain.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst import ClassicalPI
    >>> from pihyst.dynamics import HammersteinModel, fit_dynamics
    >>> static = ClassicalPI([0.0, 2.0], [1.0, 0.5])
    >>> true = HammersteinModel(hysteresis=(static,), a=([1.0, -0.5],), b=([[0.5]],))
    >>> def one_period(model, n):
    ...     u = 5 + 4 * np.sin(2 * np.pi * np.arange(n) / n)
    ...     return u, model.predict(np.tile(u, 4))[-n:, 0]
    >>> u_slow = 5 + 4 * np.sin(2 * np.pi * np.arange(400) / 400)
    >>> slow = u_slow, static.predict(np.tile(u_slow, 2))[-400:]
    >>> model = fit_dynamics(static, slow, [one_period(true, 20), one_period(true, 40)],
    ...                      orders=[(1, 1)], validation=None)
    >>> np.round(model.a[0], 2).tolist(), np.round(model.static_gain(), 6).tolist()
    ([1.0, -0.5], [[1.0]])
    """
    slow = _one_period(slow, "slow")
    fast = [_one_period(r, i) for i, r in enumerate(fast)]
    if not fast:
        raise InvalidArgumentError("fast: at least one record at a faster rate")
    orders = [tuple(int(v) for v in o) for o in orders]
    if not orders or any(na < 1 or nb < 1 for na, nb in orders):
        raise InvalidArgumentError(f"orders must be (na, nb) pairs of positive integers, "
                                   f"got {orders!r}")
    ks = _harmonics(slow)
    if ks.size == 0:
        raise InvalidArgumentError("slow: the drive is constant (no harmonic to measure)")
    period = math.lcm(*(u.size for u, _ in fast))
    if period > MAX_COMMON_PERIOD:
        sizes = ", ".join(str(u.size) for u, _ in fast)
        raise InvalidArgumentError(f"the fast records' periods ({sizes} samples) have no "
                                   f"common multiple up to {MAX_COMMON_PERIOD:,} samples")
    if sample_period is not None and not sample_period > 0:
        raise InvalidArgumentError(f"sample_period must be > 0 s, got {sample_period!r}")
    H = _plain(static)
    static_output = _creep_output(static, sample_period)
    spectra = _ratio_spectra(slow, fast, ks, period, static_output)
    if validation is not None and len(orders) > 1:
        if len(spectra) < 2:
            raise InvalidArgumentError("choosing the order needs at least two fast records "
                                       "(one held back); give validation=None")
        if validation == "each":
            held = list(range(len(spectra)))
        elif isinstance(validation, (int, np.integer)) and not isinstance(validation, bool):
            held = [int(validation) % len(spectra)]
        else:
            raise InvalidArgumentError(f"validation must be 'each', a record's index or "
                                       f"None, got {validation!r}")
        na, nb = _choose_order(spectra, orders, period, tolerance, held)
    else:
        na, nb = orders[0]
    plain_output = static_output or (lambda u: H.predict(np.tile(u, 2))[u.size:])
    outputs = [plain_output(u) for u, _ in [slow] + fast]
    a, b = _dynamics(spectra, na, nb, period, numerator_on_static, [slow] + fast, outputs)
    if keep_creep and getattr(static, "creep", None) is not None:
        H = static.replace(delay=0) if getattr(static, "delay", 0) else static
    trusted_from = 1.0 / max(u.size for u, _ in fast) if fade else 0.0
    order_trusted_from: tuple[float, ...] = ()
    if fade and len(fast) > 1:
        order_trusted_from = _order_trust(spectra, na, nb, period, numerator_on_static,
                                          slow, fast, outputs, ks)
    # the static model's mean error on the slow record (module notes, "The mean")
    static_offset = float(np.mean(slow[1] - outputs[0])) if fade else None
    return HammersteinModel(hysteresis=(H,), a=(a,), b=(b,), trusted_from=trusted_from,
                            order_trusted_from=order_trusted_from,
                            static_offset=static_offset)
