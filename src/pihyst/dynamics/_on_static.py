"""Linear dynamics after a given static model: a Hammerstein model whose hysteresis is a
model fitted on slow records (``pihyst.fit``, any family) and whose dynamics are
identified on fast periodic records (docs/theory/hammerstein.md, "Dynamics after a
static model").

For periodic records (u, y), in steady state over their last period of N samples, with
h = H[u] the static model's output over that period (run over two periods from its
initial state: the hysteresis memory then repeats; without its creep and delay, which
the dynamics measure), the dynamics

    y = G(q) h,   G = B(q^-1) / A(q^-1),

are fitted line by line of the period's DFT by the output-error fit of
:func:`pihyst.dynamics._linear.fit_oe_periodic`, for each candidate order (na, nb) on all
records but one; the first order (the simplest) whose output error on the held-back
record is within 1 % of the best wins, and is refitted on all records. Then

    B <- B A(1) / B(1):   G(1) = 1.

The static model holds the gain at rest; the dynamics only add what changes with rate.
As the rate goes to zero the Hammerstein inverse becomes the static inverse (h_d -> r),
so it cannot be worse than the static inverse there, whatever the fit's error at DC
(creep, the hysteresis model's error on the fast records, noise).
"""

import numpy as np

from pihyst.dynamics._hammerstein import HammersteinModel
from pihyst.dynamics._linear import fit_oe_periodic, response
from pihyst.exceptions import InvalidArgumentError

#: (na, nb) tried: a mode, a mode and a lag, two modes, each with one or two zeros more
DEFAULT_ORDERS = ((2, 2), (2, 3), (4, 4), (4, 5), (6, 6))


def _plain(model):
    """The static model without creep and input delay (the dynamics measure both)."""
    if getattr(model, "creep", None) is not None:
        model = model.replace(creep=None)
    if getattr(model, "delay", 0):
        model = model.replace(delay=0)
    return model


def _spectra(H, records, period):
    out = []
    for i, (u, y) in enumerate(records):
        u, y = np.asarray(u, dtype=float).ravel(), np.asarray(y, dtype=float).ravel()
        if u.size != y.size or u.size < period or u.size % period:
            raise InvalidArgumentError(f"record {i}: {u.size} input and {y.size} output "
                                       f"samples; need as many of both, a whole number of "
                                       f"periods of {period}")
        last = u[-period:]
        h = H.predict(np.tile(last, 2))[period:]
        out.append((np.fft.rfft(h)[:, None], np.fft.rfft(y[-period:])))
    return out


def _output_error(a, b, spectra, period):
    G = response(a, b, period)[:, 0]
    return float(sum(np.sum(np.abs(Y - G * V[:, 0]) ** 2) for V, Y in spectra))


def fit_dynamics(static, records, period, *, orders=DEFAULT_ORDERS, validation=-1,
                 tolerance=0.01):
    """A SISO :class:`HammersteinModel`: ``static`` (without creep and delay) followed by
    unit-static-gain dynamics fitted on ``records`` (module notes).

    ``records``: list of (u, y), each a whole number of periods of ``period`` samples of a
    periodic drive, the last period in steady state. ``validation``: the index of the
    record that chooses the order (fitted on the others, then refitted on all): the first
    of ``orders`` whose output error there is within ``tolerance`` of the best (or
    within 1e-9 of the output: noise-free data); None takes the first of ``orders``."""
    if period < 4:
        raise InvalidArgumentError(f"period must be at least 4 samples, got {period}")
    H = _plain(static)
    spectra = _spectra(H, records, int(period))
    orders = [tuple(int(v) for v in o) for o in orders]
    if not orders or any(na < 1 or nb < 1 for na, nb in orders):
        raise InvalidArgumentError(f"orders must be (na, nb) pairs of positive integers, "
                                   f"got {orders!r}")
    if validation is not None and len(orders) > 1:
        if len(spectra) < 2:
            raise InvalidArgumentError("choosing the order needs at least two records "
                                       "(one held back); give validation=None")
        held = spectra[validation]
        fit_on = [s for i, s in enumerate(spectra) if i != validation % len(spectra)]
        errors = np.sqrt([_output_error(*fit_oe_periodic(fit_on, na, nb, period), [held],
                                        period) for na, nb in orders])
        floor = 1e-9 * np.sqrt(np.sum(np.abs(held[1]) ** 2))
        na, nb = orders[int(np.flatnonzero(errors <= (1 + tolerance) * errors.min()
                                           + floor)[0])]
    else:
        na, nb = orders[0]
    a, b = fit_oe_periodic(spectra, na, nb, period)
    gain = float(np.sum(b) / np.sum(a))
    if not abs(gain) > 1e-12:
        raise InvalidArgumentError("the fitted dynamics have no static gain (B(1) = 0): "
                                   "the records do not excite the static model's output")
    return HammersteinModel(hysteresis=(H,), a=(a,), b=(b / gain,))
