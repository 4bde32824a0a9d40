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
finds the same delay at 3x the cost.) d_max is ``DELAY_MAX_FRACTION`` of the
median cycle length (at most ``MAX_SAMPLES``). The record's cycles are cut once, on the
input; each d only delays the output. To bound the cost on long records the probe runs
on the whole cycles within the first ``WINDOW`` samples (when they include fitted and
held-back ones), each delayed record subsampled to about ``PROBE_SAMPLES`` samples plus
every input extremum (exact operator outputs, fewer squares summed), and beyond
``FULL_SCAN`` delays the scan is coarse then fine (every integer between the best
coarse delay's neighbours).

A delay is adopted (``fit``'s default ``delay="auto"``) only when it is clearly better:

    rms_C(d*) < (1 - ADOPT_GAIN) rms_C(0)   and   rms_F(d*) < (1 - ADOPT_GAIN) rms_F(0),  (2)

both RMS judged on held-back cycles (with nothing held back no delay is adopted: a
shift fitted and judged on the same samples always looks a little better), d* the best
delay of the classical probe C, F the fitted structure itself (the requested
family if one with thresholds was given, else the modified PI of ``CONFIRM``: plays plus
a monotone input function, thresholds chosen from the candidates) fitted and judged on
the same samples as the probe. A dead time belongs to the record, so the structure that
will be fitted gains from removing it too; a shift that only the probe likes imitates a
loop shape or a threshold the probe's equally spaced plays cannot fit (the simulated
lens beam: the probe gains 14 % at 17 samples, the modified PI loses there; a single
play beyond the probe's plays: the probe gains 45 % at 1 sample, the exact structure
nothing). Otherwise the delay stays 0. Once (2) holds, the delay adopted is the fitted
structure's own best near d*,

    d = a local minimum of rms_F, reached from d* one sample at a time,           (3)

since the probe's shape error can move its minimum (a 10-sample lag on the simulated
paper beam: the probe's best is 8, the modified PI's 10).
"""

import numpy as np

from pihyst.exceptions import FitError
from pihyst.identify._constants import ADOPT_GAIN, DELAY_MAX_FRACTION
from pihyst.identify._families import Classical, ModifiedPI

MAX_SAMPLES = 50
PROBE_PLAYS = 8
WINDOW = 100_000
PROBE_SAMPLES = 20_000
FULL_SCAN = 12
MIN_PROBE_SAMPLES = 20
PROBE = Classical
CONFIRM = ModifiedPI


def max_delay(rec):
    """Largest delay tried on the record ``rec``: a fraction of its median cycle."""
    lengths = [z - a for a, z, role in rec.layout.segments if role != "settle"]
    return int(min(MAX_SAMPLES, max(1, DELAY_MAX_FRACTION * np.median(lengths))))


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


def probe_rms(fitter, probe=PROBE, on="judged"):
    """Judged RMS of the probe structure on ``fitter``'s record (held-back, or fitted if
    nothing is held back); ``on="fitted"``: its RMS on the fitted samples."""
    rec = fitter.rec
    fam = probe()
    cand = fam.candidates(rec.S, PROBE_PLAYS)
    template = fam.template(cand, rec.S)
    _, parts, rows = fitter.grams(fam, template)
    names = [f"r={r:g}" for r in cand] + [f"fixed {j}" for j in range(fam.n_fixed)]
    prob = fitter.problem(fam, parts, rows, len(cand), names)
    cols, x = prob.solve(tuple(range(len(cand))))
    if x is None:
        return np.inf
    return float((prob.fit if on == "fitted" else prob.judge).rms(cols, x))


def _probe_record(rec):
    """The record the probes run on (windowed) and the samples they keep."""
    base = rec.shifted(0, window(rec))
    keep = base.sample_indices(PROBE_SAMPLES)
    return base, (np.arange(base.u.size) if keep is None else keep)


def _judged(base, keep, d, fitter_of, probe):
    """The judged RMS with the output delayed by d (inf when it cannot be fitted) of the
    probe structure ``probe`` (a family class), or of the family object ``probe`` fitted
    as ``fit`` does."""
    delayed = base.taken(keep, d)
    if delayed.layout.count("fit") < MIN_PROBE_SAMPLES:
        return np.inf                 # too little left to fit
    try:
        if isinstance(probe, type):
            return float(probe_rms(fitter_of(delayed), probe))
        return float(fitter_of(delayed).fit(probe).judged_rms)
    except FitError:
        return np.inf


def scan(rec, fitter_of, d_max):
    """[{"samples": d, "rms": judged RMS of (1)}] over the delays probed, in order;
    ``fitter_of(record)`` builds a FamilyFitter."""
    base, keep = _probe_record(rec)
    done = {}

    def probe(d):
        if d not in done:
            done[d] = _judged(base, keep, d, fitter_of, PROBE)
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


def gain(rms_at_d, rms_at_0):
    """1 - rms(d) / rms(0): the share of the judged RMS a delay removes."""
    if not np.isfinite(rms_at_d):
        return -np.inf
    return 1.0 if not np.isfinite(rms_at_0) or rms_at_0 == 0 else 1.0 - rms_at_d / rms_at_0


def confirming_family(families):
    """F of (2): the one requested family if it is a PI family with thresholds, else
    ``CONFIRM`` (for kernels, Bouc-Wen or several families)."""
    if len(families) == 1 and families[0].operators_key == "thresholds" and \
            families[0].name != "bouc-wen":
        return families[0]
    return CONFIRM()


def adopted(rec, fitter_of, tried, family):
    """The delay rule (2) on a scan ``tried``, confirmed by fitting ``family``:
    (samples, reason, confirmation) with the confirmation {"family", "samples", "rms_0",
    "rms_d"} when it ran."""
    rms = {t["samples"]: t["rms"] for t in tried}
    finite = [d for d in rms if np.isfinite(rms[d])]
    if not finite:
        return 0, "no delay could be judged (the probe cannot be fitted): none assumed", None
    best = min(finite, key=lambda d: rms[d])
    if best == 0:
        return 0, "no delay lowers the probe's held-back RMS", None
    if not rec.has_held_back:
        # the fitted error always falls a little with one more thing fitted to it
        return 0, ("nothing is held back to judge a delay on (the fitted error is no "
                   "evidence): none assumed"), None
    g = gain(rms[best], rms.get(0, np.inf))
    if g <= ADOPT_GAIN:
        return 0, (f"{best} samples lower the probe's RMS by only {100 * g:.1f} % "
                   f"(a delay needs more than {100 * ADOPT_GAIN:g} %)"), None
    base, keep = _probe_record(rec)
    at = {}

    def fitted(d):
        if d not in at:
            at[d] = _judged(base, keep, d, fitter_of, family)
        return at[d]

    g2 = gain(fitted(best), fitted(0))
    if g2 <= ADOPT_GAIN:
        change = (f"by only {100 * g2:.1f} %" if g2 >= 0 else
                  f"not at all (RMS {at[best]:.3g} against {at[0]:.3g})")
        return 0, (f"{best} samples lower the probe's RMS by {100 * g:.1f} % but a fitted "
                   f"{family.name} model's {change} (a delay needs more than "
                   f"{100 * ADOPT_GAIN:g} %): a shape the probe cannot fit, not a dead "
                   f"time"), _confirmation(family, best, best, at)
    # (3): the fitted structure's own best delay, by descent from the probe's
    d, top = best, max(rms)
    while True:
        steps = [n for n in (d - 1, d + 1) if 1 <= n <= top]
        n = min(steps, key=fitted, default=d)
        if not fitted(n) < fitted(d):
            break
        d = n
    near = "" if d == best else f" (the probe's best: {best})"
    return d, (f"{d} samples{near} lower the held-back RMS of the probe by "
               f"{100 * gain(rms.get(d, rms[best]), rms.get(0, np.inf)):.1f} % and of a "
               f"fitted {family.name} model by {100 * gain(at[d], at[0]):.1f} %, more than "
               f"{100 * ADOPT_GAIN:g} %"), _confirmation(family, best, d, at)


def _confirmation(family, best, used, at):
    """What the report says of the fitted structure's check: its judged RMS per delay."""
    return {"family": family.name, "probe_best": best, "samples": used,
            "rms_0": at[0], "rms_d": at[used],
            "tried": [{"samples": k, "rms": at[k]} for k in sorted(at)]}
