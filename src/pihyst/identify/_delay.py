"""The delay between input and output that a rate-independent model fits best.

A PI-type model is rate-independent: y[k] depends on u[0..k] only through its
reversals. A record whose output lags its input by d samples (sensor filter, amplifier,
logging) looks to such a model like a wider loop, and a model fitted to it mispredicts
every trajectory whose speed differs. Fitting

    y[k + d] ~ H[u](k),      d = 0, 1, ..., d_max                                 (1)

and judging each d on the held-back cycles finds the lag the data support. The probe
structure is a classical PI with ``PROBE_PLAYS`` equally spaced plays (linear in all its
weights, one fast Gram pass per d), so the choice does not depend on a threshold
search. (On the P-885 record a modified PI probe, which also fits asymmetric loops,
finds the same delay at 3x the cost.) d_max is ``MAX_FRACTION`` of the
median cycle length (at most ``MAX_SAMPLES``). The record's cycles are cut once, on the
input; each d only delays the output. To bound the cost on long records the probe runs
on the whole cycles within the first ``WINDOW`` samples (when they include fitted and
held-back ones), each delayed record subsampled to about ``PROBE_SAMPLES`` samples plus
every input extremum (exact operator outputs, fewer squares summed), and beyond
``FULL_SCAN`` delays the scan is coarse then fine (every integer between the best
coarse delay's neighbours).
"""

import numpy as np

from pihyst.exceptions import FitError
from pihyst.identify._families import Classical

MAX_FRACTION = 0.05
MAX_SAMPLES = 50
PROBE_PLAYS = 8
WINDOW = 100_000
PROBE_SAMPLES = 20_000
FULL_SCAN = 12
MIN_PROBE_SAMPLES = 20
PROBE = Classical


def max_delay(rec):
    """Largest delay tried on the record ``rec``: a fraction of its median cycle."""
    lengths = [z - a for a, z, role in rec.layout.segments if role != "settle"]
    return int(min(MAX_SAMPLES, max(1, MAX_FRACTION * np.median(lengths))))


def window(rec):
    """End of the probe's window: the end of the first cycle reaching ``WINDOW`` samples,
    if the cycles before it include every role of the record (fitted, held back); else
    None (the whole record)."""
    if rec.u.size <= WINDOW:
        return None
    stop = next((z for a, z, role in rec.layout.segments if z >= WINDOW), rec.u.size)
    inside = {r for a, z, r in rec.layout.segments if z <= stop} - {"settle"}
    everywhere = {r for *_, r in rec.layout.segments} - {"settle"}
    return stop if inside == everywhere else None


def probe_rms(fitter):
    """Judged RMS of the probe structure on ``fitter``'s record (held-back, or fitted if
    nothing is held back)."""
    rec = fitter.rec
    fam = PROBE()
    cand = fam.candidates(rec.S, PROBE_PLAYS)
    template = fam.template(cand, rec.S)
    _, parts, rows = fitter.grams(fam, template)
    names = [f"r={r:g}" for r in cand] + [f"fixed {j}" for j in range(fam.n_fixed)]
    prob = fitter.problem(fam, parts, rows, len(cand), names)
    cols, x = prob.solve(tuple(range(len(cand))))
    return np.inf if x is None else prob.judge.rms(cols, x)


def scan(rec, fitter_of, d_max):
    """[{"samples": d, "rms": judged RMS of (1)}] over the delays probed, in order;
    ``fitter_of(record)`` builds a FamilyFitter."""
    base = rec.shifted(0, window(rec))
    keep = base.sample_indices(PROBE_SAMPLES)
    if keep is None:
        keep = np.arange(base.u.size)
    done = {}

    def probe(d):
        if d not in done:
            delayed = base.taken(keep, d)
            if delayed.layout.count("fit") < MIN_PROBE_SAMPLES:
                done[d] = np.inf             # too little left to fit
            else:
                try:
                    done[d] = float(probe_rms(fitter_of(delayed)))
                except FitError:
                    done[d] = np.inf
        return done[d]

    if d_max <= FULL_SCAN:
        for d in range(d_max + 1):
            probe(d)
    else:
        coarse = sorted({int(round(x)) for x in np.linspace(0, d_max, FULL_SCAN)})
        best = min(coarse, key=probe)
        k = coarse.index(best)
        for d in range(coarse[max(k - 1, 0)], coarse[min(k + 1, len(coarse) - 1)] + 1):
            probe(d)
    return [{"samples": d, "rms": done[d]} for d in sorted(done)]
