"""What learning takes from a model: its static hysteresis (to turn a hysteresis target
into voltages with the exact inverse, and voltages into the hysteresis output) and, for a
Hammerstein model, its linear dynamics as a frequency response on the harmonics of the
period.

The learning works on one period of N samples. With h = H[u] the static hysteresis
output (the voltage itself when there is no model) and y = G h + (what G h misses), the
harmonics k = 0 .. N/2 of the period (rfft lines, f_k = k / (N T)) carry

    Y_k = G_k H_k + D_k,

G_k the dynamics on line k (1 for a static model, the Hammerstein model's B/A on z_k =
exp(-2 pi i k / N)), D_k what the model misses. The static part's inverse turns a
periodic target h_d into voltages: :func:`periodic_inverse` runs the exact inverse over
P periods and keeps the last, from which the hysteresis memory repeats (P = 2 without
creep). A model's creep lags (docs/theory/creep.md) start settled at the period's mean
hysteresis output, where a periodic drive keeps the slow ones (time constants far above
the period T); P is then long enough for the lags of time constants up to 10 T to
settle (three time constants; at most MAX_SAMPLES samples in all). The input delay is
left to the learning, which measures it as a phase like any other dynamics.
"""

from dataclasses import dataclass

import numpy as np

from pihyst.exceptions import InvalidArgumentError
from pihyst.inverse import compensate

MAX_SAMPLES = 100_000


def _without_delay(model):
    return model.replace(delay=0) if getattr(model, "delay", 0) else model


def _without_creep(model):
    return model.replace(creep=None) if getattr(model, "creep", None) is not None else model


@dataclass(frozen=True)
class ModelParts:
    """``static``: a model with an exact inverse, or None (the voltage is the hysteresis
    output); ``dynamics``: (a, b) q^-1 polynomials of a SISO Hammerstein model, or None."""

    static: object = None
    dynamics: tuple | None = None
    sample_period: float = 1.0

    @property
    def creep(self):
        return None if self.static is None else getattr(self.static, "creep", None)

    def periods(self, n):
        """P of the module notes for an n-sample period."""
        if self.creep is None:
            return 2
        period_s = n * self.sample_period
        taus = [tau for tau in self.creep.tau if tau <= 10 * period_s]
        p = 2 + (int(np.ceil(3 * max(taus) / period_s)) if taus else 0)
        return int(min(p, max(2, MAX_SAMPLES // n)))

    def _run_options(self, periods, n, h_period):
        """(t, creep_state) for a run of ``periods`` periods (creep: the lags settled at
        the period's mean hysteresis output ``h_period``)."""
        if self.creep is None:
            return {}
        return {"t": np.arange(periods * n) * self.sample_period,
                "creep_state": np.full(len(self.creep.tau), float(np.mean(h_period)))}

    def hysteresis_output(self, u):
        """h = H[u] over one period in periodic steady state (module notes)."""
        u = np.asarray(u, dtype=float)
        if self.static is None:
            return u.copy()
        p = self.periods(u.size)
        h_static = _without_creep(self.static).predict(np.tile(u, 2))[u.size:]
        if self.creep is None:
            return h_static
        y = self.static.predict(np.tile(u, p), **self._run_options(p, u.size, h_static))
        return y[-u.size:]

    def response(self, n):
        """G_k on the rfft lines of an n-sample period (None without dynamics)."""
        if self.dynamics is None:
            return None
        from pihyst.dynamics._linear import response
        a, b = self.dynamics
        return response(np.asarray(a, dtype=float), np.atleast_2d(b), n)[:, 0]

    def voltage_range(self):
        """(lo, hi) the static model was built for, or None."""
        return None if self.static is None else tuple(self.static.input_range)


def model_parts(model, sample_period=1.0):
    """:class:`ModelParts` of a PI or Bouc-Wen model, a SISO Hammerstein model, or None,
    for periods sampled every ``sample_period`` s."""
    if model is None:
        return ModelParts(sample_period=sample_period)
    from pihyst.dynamics import HammersteinModel
    if isinstance(model, HammersteinModel):
        if model.n_inputs != 1 or model.n_outputs != 1:
            raise InvalidArgumentError(f"learning needs a single-input single-output model, "
                                       f"got {model.n_inputs} input(s) and "
                                       f"{model.n_outputs} output(s)")
        return ModelParts(_without_delay(model.hysteresis[0]),
                          (np.asarray(model.a[0]), np.asarray(model.b[0])), sample_period)
    if not hasattr(model, "predict") or not hasattr(model, "replace"):
        raise InvalidArgumentError(f"model: expected a pihyst model (PI, Bouc-Wen or "
                                   f"Hammerstein) or None, got {type(model).__name__}")
    return ModelParts(_without_delay(model), sample_period=sample_period)


def periodic_inverse(parts, h_target, lo, hi, max_step):
    """Voltages whose static hysteresis output is the periodic ``h_target`` (module
    notes), within [lo, hi] and ``max_step`` per sample; the voltage itself without a
    static model. The caller makes the cycle's wrap feasible (:mod:`._feasible`)."""
    h_target = np.asarray(h_target, dtype=float)
    if parts.static is None:
        return h_target.copy()
    n = h_target.size
    p = parts.periods(n)
    static = parts.static
    if parts.creep is not None:
        # the lags' start: the creep-free inverse's mean hysteresis output
        plain = compensate(_without_creep(static), h_target,
                           u_min=lo, u_max=hi, slew_rate=max_step, sample_period=1.0)
        options = parts._run_options(p, n, plain.displacement)
    else:
        options = {}
    # max_step is volts per sample: a slew rate of max_step V/s at a 1 s sample
    run = compensate(static, np.tile(h_target, p), u_min=lo, u_max=hi, slew_rate=max_step,
                     sample_period=1.0, initial_state=static.initial_state, **options)
    return run.voltage[-n:]
