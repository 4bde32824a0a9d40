"""Where a record that starts at the bottom of its range starts from (``fit``'s default
``initial_state="auto"``; docs/theory/identification.md, "Initial state and settling").

A record that begins at the bottom of the range is taken to start at rest there after a
full cycle (docs/interfaces.md): every play operator at z_r = r, every relay off. An
actuator that was never cycled since it was last at zero — a new or depoled one, and
every play-operator model whose operators start at 0, as in most PI code — starts from
the zero state instead, z_r = 0, and its first rise is the initial loading curve, not the
ascending branch. The two differ only until the input first reaches the top (which wipes
out both), but a fit that assumes the wrong one distorts every weight to fit that first
rise: a classical PI actuator recorded from zero on decaying triangles was 1.4-1.6 % of
range off on staircases with the cycled assumption, 0.02 % with the zero state.

Both are tried with the delay probe's structure (a classical PI with equally spaced
plays, one fast Gram pass each) on the same samples, and the zero state is taken when it
fits the record clearly better: a fitted RMS lower by more than :data:`ZERO_GAIN`
(half). The
held-back cycles cannot tell (they come after the first rise); the fitted samples can,
since the two assumptions differ only on the first rise, which both fit with the same
number of weights.
"""

import numpy as np

from pihyst.exceptions import FitError
from pihyst.identify import _delay
from pihyst.identify._constants import ZERO_GAIN


def start_state(rec, record_in, fitter_of):
    """(record, choice): ``rec`` (framed with the cycled rest state) or the same record
    framed from the zero state (``record_in("zero")``), and what was compared; for a
    record framed from ``"rise"`` (one that starts inside its range and is not settled
    soon enough by its first full sweep, identify/_family_fit.py), the state reached by a
    rise from the bottom, by a fall from the top, or the zero state, whichever the probe
    fits best."""
    if rec.state_mode == "rise":
        modes, favoured = ("rise", "fall", "zero"), None
    else:
        modes, favoured = ("cycled", "zero"), "cycled"
    probed = {}
    for mode in modes:
        r = rec if mode == rec.state_mode else record_in(mode)
        base, keep = _delay._probe_record(r)
        try:
            probed[mode] = (r, _delay.probe_rms(fitter_of(base.taken(keep, 0)), on="fitted"))
        except FitError:
            probed[mode] = (r, np.inf)
    first, second = probed[modes[0]][1], probed[modes[1]][1]
    if favoured is None:
        chosen = min(modes, key=lambda m: probed[m][1])
        rule = (f"the record starts inside its range and its first full sweep comes too late "
                f"to settle the operators: at rest at its first input after a rise from the "
                f"bottom, after a fall from the top, or from the zero state (every operator "
                f"output 0, as in play-operator code started there), whichever the probe "
                f"({_delay.PROBE_PLAYS} equally spaced plays) fits best")
    else:
        chosen = "zero" if second < (1.0 - ZERO_GAIN) * first else "cycled"
        rule = (f"the zero state when the probe ({_delay.PROBE_PLAYS} equally spaced "
                f"plays) fits the record more than {100 * ZERO_GAIN:g} % better "
                f"from it than from rest after a full cycle")
    choice = {"chosen": chosen, "probe_fitted_rms": {m: probed[m][1] for m in modes},
              "rule": rule}
    return probed[chosen][0], choice
