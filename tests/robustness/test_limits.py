"""Resource limits are checked before the work: a desired trajectory longer than a
simulated beam runs at once (track), a signal longer than simulate makes."""

from harness import DESIRED, GOOD_MODEL, judge, run

from pihyst.cli import track
from pihyst.sim import signals


def test_track_refuses_a_trajectory_longer_than_the_limit(tmp_path, monkeypatch):
    monkeypatch.setattr(track, "MAX_SAMPLES", 10)
    out = str(tmp_path / "out.csv")
    outcome = run(["track", GOOD_MODEL, DESIRED, "-o", out])
    assert not judge(outcome, 2, out, "more than the 10 a simulated beam runs at once")


def test_simulate_counts_samples_before_making_them(tmp_path):
    out = str(tmp_path / "out.csv")
    n = signals.MAX_SAMPLES
    outcome = run(["simulate", "-o", out, "--period", "1", "--dt", "0.1",
                   "--cycles", str(n // 5)])
    assert not judge(outcome, 2, out, "samples, more than the 2,000,000")
