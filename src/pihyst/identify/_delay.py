"""The delay between input and output that a rate-independent model fits best.

A PI-type model is rate-independent: y[k] depends on u[0..k] only through its
reversals. A record whose output lags its input by d samples (sensor filter, amplifier,
logging) looks to such a model like a wider loop, and a model fitted to it mispredicts
every trajectory whose speed differs. Fitting

    y[k + d] ~ H[u](k),      d = 0, 1, ..., d_max                                 (1)

and judging each d on the held-back cycles finds the lag the data support. The probe
structure is the modified PI with every candidate threshold (linear in all its
weights, one Gram pass per d, asymmetric loops allowed), so the choice does not depend
on a threshold search. d_max is ``MAX_FRACTION`` of the median cycle length (at most
``MAX_SAMPLES``).
"""

import numpy as np

from pihyst.identify._families import ModifiedPI

MAX_FRACTION = 0.05
MAX_SAMPLES = 50


def max_delay(rec):
    """Largest delay tried on the record ``rec``: a fraction of its median cycle."""
    lengths = [z - a for a, z, role in rec.layout.segments if role != "settle"]
    return int(min(MAX_SAMPLES, max(1, MAX_FRACTION * np.median(lengths))))


def probe_rms(fitter):
    """Judged RMS of the probe structure on ``fitter``'s record (held-back, or fitted if
    nothing is held back)."""
    rec = fitter.rec
    fam = ModifiedPI()
    cand = fam.candidates(rec.S, fitter.n_candidates)
    template = fam.template(cand, rec.S)
    _, parts, rows = fitter.grams(fam, template)
    names = [f"r={r:g}" for r in cand] + [f"input segment {j}" for j in range(fam.n_fixed)]
    prob = fitter.problem(fam, parts, rows, len(cand), names)
    cols, x = prob.solve(tuple(range(len(cand))))
    return np.inf if x is None else prob.judge.rms(cols, x)


def scan(make_fitter, d_max):
    """[{"samples": d, "rms": judged RMS of (1)}] for d = 0..d_max; ``make_fitter(d)``
    builds a FamilyFitter of the record shifted by d."""
    return [{"samples": d, "rms": float(probe_rms(make_fitter(d)))} for d in range(d_max + 1)]
