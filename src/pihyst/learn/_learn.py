"""Inversion-based iterative learning of one period of feedforward voltages
(docs/theory/learning.md).

Trial j plays the voltages u_j (one period, repeated until steady) and measures y_j. With
h_j = H[u_j] the static model's hysteresis output, R, Y_j, H_j the rfft's of the desired
period, the measured one and h_j, and G_k the response on line k (:mod:`._response`), the
next hysteresis target is

    H_{j+1,k} = H_{b,k} + gamma Q_k (R_k - Y_{b,k}) / G_k,          (learning law)

b the best trial so far, gamma the learning gain (1 at first), Q_k the robustness filter:
1 on the lines whose G_k is trusted (measured to ``TRUST_REL_STD``, or the Hammerstein
model's below half its resonance before a measurement there), with |G_k| at least
``MIN_GAIN`` of the static gain and f_k within ``bandwidth_hz``; 0 elsewhere. The
voltages are h_{j+1}'s exact periodic inverse, then made feasible: within [u_min, u_max]
and within the slew limit round the cycle (:mod:`._feasible`), whatever the law asked for.

On a line where G_k is trusted the error then evolves as

    E_{j+1,k} = (1 - gamma Q_k G_k / Ghat_k) E_{j,k},

which shrinks when |1 - gamma G_k / Ghat_k| < 1, i.e. for gamma <= 1 whenever Ghat_k is
within a factor (and 90 degrees of phase) of the true G_k.

Trial 1 learns on the lines trial 0 tells about (those of the desired trajectory, and
the Hammerstein model's). Trial 2 is the probe trial: the best drive so far plus a small
multisine of random phases, PROBE_SNR times the noise level per line, on the lines
nothing is known about yet (between DC and ``bandwidth_hz``), and nothing else, so that
the change it measures is the probe's alone; from trial 3 on the law learns there too.
Where what the model misses is large, it moves with every change of the drive and hides
a probe that small: trial 6 probes again the lines still untrusted whose error is above
PROBE_SNR times the noise level, each with its error's amplitude. A learning trial whose
RMS error is above the best so far is undone (the next update starts again from the
best) and the gain halved; a probe trial that is worse is undone, the gain kept (it
learned nothing). The learning stops after ``trials`` trials, when the gain falls below
MIN_LEARNING_GAIN (no trial improves any more: the error is at what the noise and the
robustness filter allow), or when the error is at ``tolerance``.
"""

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst.exceptions import InvalidArgumentError
from pihyst.learn._feasible import feasible_periodic
from pihyst.learn._model_parts import model_parts, periodic_inverse
from pihyst.learn._response import ResponseEstimate, noise_sigma

MIN_GAIN = 0.1            # lines where |G_k| < MIN_GAIN * the static gain are not learned
MIN_LEARNING_GAIN = 1 / 16
PROBE_SNR = 8.0
PROBE_TRIAL = 2           # trial 1 learns what trial 0 tells; trial 2 probes
SECOND_PROBE_TRIAL = 6    # probes again where the error stays large and nothing is known
SIGMA_FLOOR = 1e-6        # of the desired trajectory's standard deviation


@dataclass(frozen=True)
class LearningResult:
    """What :func:`learn_periodic` learned.

    Parameters
    ----------
    voltage : ndarray
        The best period of voltages found (the lowest RMS error of all trials).
    displacement : ndarray
        The period measured with it.
    rms : ndarray
        RMS tracking error (measured - desired, um) per trial; trial 0: the starting
        feedforward.
    accepted : ndarray of bool
        Per trial: kept (its error not above the best before it) or undone.
    gain : ndarray
        The learning gain of the update each trial played (NaN for trial 0 and the probe
        trial).
    learned_lines : ndarray of int
        Per trial: how many harmonics the robustness filter let learn (0 for trial 0 and
        the probe trial).
    kinds : tuple of str
        Per trial: ``"start"`` (trial 0), ``"learn"`` (the learning law) or ``"probe"``
        (the best drive plus the probe, nothing learned).
    best_trial : int
        The trial whose voltages are ``voltage``.
    reason : str
        Why the learning stopped.
    converged : bool
        It stopped because no trial improved any more or the tolerance was met (not for
        want of trials).
    noise_um : float
        The sensor noise the learning estimated (standard deviation, um).
    response : ndarray of complex
        The estimated response per rfft line of the period (NaN where not known).
    trusted : ndarray of bool
        The lines whose response estimate was trusted at the end.
    voltages, displacements : list of ndarray or None
        With ``keep_trials``: every trial's voltages and measured period; else None.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.learn import learn_periodic
    >>> desired = 10.0 + 5.0 * np.sin(2 * np.pi * np.arange(64) / 64)
    >>> result = learn_periodic(lambda u: 0.2 * u, desired, 1e-3, trials=3)
    >>> result.trials, result.kinds[0], result.voltage.shape
    (4, 'start', (64,))
    """

    voltage: np.ndarray
    displacement: np.ndarray
    rms: np.ndarray
    accepted: np.ndarray
    gain: np.ndarray
    learned_lines: np.ndarray
    kinds: tuple
    best_trial: int
    reason: str
    converged: bool
    noise_um: float
    response: np.ndarray = field(repr=False)
    trusted: np.ndarray = field(repr=False)
    voltages: list[np.ndarray] | None = field(repr=False, default=None)
    displacements: list[np.ndarray] | None = field(repr=False, default=None)

    @property
    def trials(self) -> int:
        """The number of trials played, trial 0 included."""
        return int(self.rms.size)


@dataclass(frozen=True)
class _Trial:
    rms: float
    voltage: np.ndarray
    displacement: np.ndarray
    probe: np.ndarray          # the probe's spectrum in the drive (zeros: none)
    kind: str                  # "start", "learn" or "probe"


def _response(estimate, G_model, model_lines):
    """(G, trusted) per line: the trials' estimate where trusted, else the Hammerstein
    model's on the lines it is trusted on before a measurement."""
    G, rel = estimate.estimate()
    trusted = estimate.trusted(rel)
    if model_lines is not None:
        use_model = ~trusted & model_lines
        G = np.where(use_model, G_model, G)
        trusted = trusted | use_model
    return G, trusted


def _rms(e):
    return float(np.sqrt(np.mean(np.square(e))))


def _checked(desired, sample_period, u_min, u_max, slew_rate, trials):
    desired = np.asarray(desired, dtype=float)
    if desired.ndim != 1 or desired.size < 4:
        raise InvalidArgumentError(f"desired must be one period of at least 4 samples, got "
                                   f"shape {desired.shape}")
    if not np.all(np.isfinite(desired)):
        bad = np.flatnonzero(~np.isfinite(desired))[0]
        raise InvalidArgumentError(f"desired sample {bad} is not a finite number")
    if not (np.isfinite(sample_period) and sample_period > 0):
        raise InvalidArgumentError(f"sample_period must be > 0 s, got {sample_period!r}")
    if not (np.isfinite(u_min) and np.isfinite(u_max) and u_min < u_max):
        raise InvalidArgumentError(f"need finite u_min < u_max, got {u_min!r}, {u_max!r}")
    if slew_rate is not None and not (np.isfinite(slew_rate) and slew_rate > 0):
        raise InvalidArgumentError(f"slew_rate must be > 0 V/s or None, got {slew_rate!r}")
    if int(trials) != trials or trials < 0:
        raise InvalidArgumentError(f"trials must be a whole number >= 0, got {trials!r}")
    return desired


def _start(parts, desired, G_model, model_lines, lo, hi, max_step):
    """Trial 0's voltages: the model's inverse (with its dynamics inverted on the lines
    it is trusted on), or without a model the desired shape over the middle half of the
    voltage range."""
    if parts.static is None and G_model is None:
        span = max(float(np.ptp(desired)), 1e-300)
        return (lo + hi) / 2 + (desired - desired.mean()) / span * (hi - lo) / 2
    R = np.fft.rfft(desired)
    if G_model is not None:
        R = np.where(model_lines, R / np.where(model_lines, G_model, 1.0), R)
    return periodic_inverse(parts, np.fft.irfft(R, desired.size), lo, hi, max_step)


def _probe(lines, amplitude, static_gain, rng):
    """The probe's spectrum on ``lines`` (never on DC nor the Nyquist line, whose phase is
    not free): ``amplitude`` per line (the output's, um in rfft units) through the static
    gain into the hysteresis output, random phases."""
    lines = lines.copy()
    lines[0] = lines[-1] = False
    with np.errstate(over="ignore", invalid="ignore"):
        size = amplitude / static_gain
        return np.where(lines, size * np.exp(2j * np.pi * rng.random(lines.size)), 0.0)


def learning_law(H_best, E_best, G, Q, gamma, probe_best):
    """The next hysteresis target's spectrum (module notes):

        H_{j+1,k} = H_{b,k} + gamma Q_k E_{b,k} / G_k - (1 - Q_k) P_{b,k},

    E_b = R - Y_b the best trial's error and P_b the probe its drive still carries, taken
    out where the law does not learn. A step that overflows (a plant
    that hardly responds) is not finite; the drive made of it is then made feasible
    like any other (:func:`pihyst.learn.feasible_periodic`)."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        step = np.where(Q, gamma * E_best / np.where(Q, G, 1.0), 0.0)
    return H_best + step - np.where(Q, 0.0, probe_best)


def _probe_lines(trial, untrusted, E, noise_line):
    """(lines, amplitude per line) of the probe trial ``trial`` is, or (None, None):
    trial PROBE_TRIAL on every untrusted line at PROBE_SNR noise levels; trial
    SECOND_PROBE_TRIAL on the untrusted lines whose error is above that, at its error."""
    if trial == PROBE_TRIAL:
        return untrusted, PROBE_SNR * noise_line
    if trial == SECOND_PROBE_TRIAL:
        return untrusted & (np.abs(E) > PROBE_SNR * noise_line), np.abs(E)
    return None, None


def _model_lines(G_model):
    """Lines where the Hammerstein model's response is trusted before any measurement:
    below half the frequency of its largest gain when that is a resonance (> 1.5 times
    the static gain), else all of them."""
    if G_model is None:
        return None
    mag = np.abs(G_model)
    peak = int(np.argmax(mag))
    if mag[peak] > 1.5 * mag[0]:
        return np.arange(mag.size) <= peak // 2
    return np.ones(mag.size, dtype=bool)


def learn_periodic(run_period: Callable[[NDArray[np.float64]], ArrayLike], desired: ArrayLike,
                   sample_period: float, model: Any = None, u_min: float = 0.0,
                   u_max: float = 150.0, slew_rate: float | None = None, trials: int = 10, *,
                   bandwidth_hz: float | None = None, tolerance: float | None = None,
                   seed: int = 0, keep_trials: bool = False) -> LearningResult:
    """Learn one period of feedforward voltages that make the actuator follow ``desired``
    (module notes; docs/theory/learning.md).

    Parameters
    ----------
    run_period : callable u -> y
        Plays one period of voltages ``u`` on the actuator (repeated until steady) and
        returns one period measured (um), as many samples as ``u``.
    desired : array_like
        One period of the desired displacement (um), a sample every ``sample_period``.
    sample_period : float
        Seconds between samples.
    model : PI, Bouc-Wen or SISO Hammerstein model, or None
        The starting feedforward is its inverse; the learning inverts its hysteresis
        exactly and, for a Hammerstein model, starts from its dynamics. None: the
        voltages themselves are learned (starting from the desired shape over the middle
        half of [u_min, u_max]).
    u_min, u_max : float
        Voltage limits: no trial sends a voltage outside them.
    slew_rate : float or None
        V/s: no trial steps faster, round the whole cycle.
    trials : int
        Learning trials after trial 0 (the starting feedforward).
    bandwidth_hz : float, optional
        Learn only harmonics up to this frequency (default: up to Nyquist).
    tolerance : float, optional
        Stop once the RMS error is at most this (um).
    seed : int
        Seed of the probe's random phases.
    keep_trials : bool
        Keep every trial's voltages and measured period in ``result.voltages`` and
        ``result.displacements``.

    Returns
    -------
    LearningResult
        The best period of voltages, and every trial's error, gain and kind.

    Raises
    ------
    InvalidArgumentError
        When the arguments are not valid (empty or non-finite ``desired``, limits,
        slew rate, trials), or ``run_period`` returns a period of another length.

    Examples
    --------
    A plant of 0.2 um/V with no hysteresis, learned from no model:

    >>> import numpy as np
    >>> from pihyst.learn import learn_periodic
    >>> desired = 10.0 + 5.0 * np.sin(2 * np.pi * np.arange(64) / 64)
    >>> result = learn_periodic(lambda u: 0.2 * u, desired, 1e-3, trials=5)
    >>> bool(result.rms[result.best_trial] < 1e-6 * result.rms[0])
    True
    """
    target = _checked(desired, sample_period, u_min, u_max, slew_rate, trials)
    parts = model_parts(model, float(sample_period))
    n = target.size
    lo, hi = float(u_min), float(u_max)
    max_step = None if slew_rate is None else float(slew_rate) * float(sample_period)
    freqs = np.fft.rfftfreq(n, sample_period)
    in_band = np.ones(freqs.size, dtype=bool) if bandwidth_hz is None else freqs <= bandwidth_hz
    G_model = parts.response(n)
    model_lines = _model_lines(G_model)
    R = np.fft.rfft(target)
    sigma_floor = SIGMA_FLOOR * max(float(np.std(target)), 1e-12)
    rng = np.random.default_rng(seed)
    estimate = ResponseEstimate(target)

    def play(u):
        u = feasible_periodic(u, lo, hi, max_step)
        y = np.asarray(run_period(u.copy()), dtype=float)
        if y.shape != u.shape:
            raise InvalidArgumentError(f"run_period returned {y.shape} samples for a period "
                                       f"of {u.shape}")
        return u, y

    u, y = play(_start(parts, target, G_model, model_lines, lo, hi, max_step))
    sigma = noise_sigma(y, sigma_floor)
    estimate.add(parts.hysteresis_output(u), y, sigma)
    trial = [_Trial(_rms(y - target), u, y, np.zeros(R.size, dtype=complex), "start")]
    best = 0
    accepted, gains, learned = [True], [np.nan], [0]
    gamma, reason, converged = 1.0, None, False
    G, trusted = None, None
    for j in range(1, int(trials) + 1):
        if tolerance is not None and trial[best].rms <= tolerance:
            reason, converged = (f"the RMS error {trial[best].rms:.4g} µm is within the "
                                 f"tolerance {tolerance:g} µm"), True
            break
        if gamma < MIN_LEARNING_GAIN:
            reason = (f"no trial improved on trial {best} after the gain fell to "
                      f"{2 * gamma:g}: the error is at what the noise and the robustness "
                      f"filter allow")
            converged = True
            break
        G, trusted = _response(estimate, G_model, model_lines)
        static_gain = estimate.reference_gain()
        if not trusted[0]:
            G[0], trusted[0] = static_gain, True      # DC: learned with the static gain
        magnitude = np.abs(np.nan_to_num(G))
        Q = trusted & in_band & (magnitude >= MIN_GAIN * static_gain) & (magnitude > 0)
        b = trial[best]
        H_b = np.fft.rfft(parts.hysteresis_output(b.voltage))
        untrusted = ~Q & in_band
        untrusted[0] = False
        E = R - np.fft.rfft(b.displacement)
        noise_line = np.sqrt(n) * sigma
        lines, amplitude = _probe_lines(j, untrusted, E, noise_line)
        if lines is not None and np.any(lines[1:-1]) and static_gain > 0:
            # a probe trial: the best drive plus the probe, nothing learned
            kind, probe = "probe", _probe(lines, amplitude, static_gain, rng)
            H_next = H_b + probe
        else:
            # the learning law; the best trial's probe leaves the lines not learned
            kind, probe = "learn", np.zeros(R.size, dtype=complex)
            H_next = learning_law(H_b, E, G, Q, gamma, b.probe)
        # a step that overflowed (learning_law, _probe) stays non-finite through the
        # inverse transform; periodic_inverse makes that drive feasible like any other
        with np.errstate(over="ignore", invalid="ignore"):
            h_next = np.fft.irfft(H_next, n)
        u, y = play(periodic_inverse(parts, h_next, lo, hi, max_step))
        sigma = min(noise_sigma(y, sigma_floor), estimate.sigma)
        estimate.add(parts.hysteresis_output(u), y, sigma, parent=best)
        trial.append(_Trial(_rms(y - target), u, y, probe, kind))
        gains.append(gamma if kind == "learn" else np.nan)
        learned.append(int(np.count_nonzero(Q)) if kind == "learn" else 0)
        accepted.append(trial[-1].rms <= b.rms)
        if accepted[-1]:
            best = j
        elif kind == "learn":
            gamma /= 2
    if reason is None:
        reason = (f"all {len(trial) - 1} learning trials done" if trials
                  else "no learning trials")
    G, trusted = _response(estimate, G_model, model_lines)
    return LearningResult(voltage=trial[best].voltage, displacement=trial[best].displacement,
                          rms=np.array([t.rms for t in trial]), accepted=np.array(accepted),
                          gain=np.array(gains), learned_lines=np.array(learned),
                          kinds=tuple(t.kind for t in trial), best_trial=best, reason=reason,
                          converged=converged, noise_um=float(estimate.sigma), response=G,
                          trusted=trusted,
                          voltages=[t.voltage for t in trial] if keep_trials else None,
                          displacements=([t.displacement for t in trial] if keep_trials
                                         else None))
