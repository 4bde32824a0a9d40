"""validate_model and its cut of a record into input cycles."""

import numpy as np
import pytest

import pihyst
from pihyst.exceptions import InvalidArgumentError
from pihyst.io import validate_model
from pihyst.io._validation import cycle_starts

CLASSICAL = "examples/paper_table1_classical.json"


def triangles(cycles, n=100, peak=150.0):
    up = np.linspace(0, peak, n + 1)
    return np.r_[np.tile(np.r_[up, up[-2:0:-1]], cycles), 0.0]


def test_cycles_of_a_record_that_starts_at_the_top():
    u = triangles(3)[100:]          # from the top: down, then two full cycles
    np.testing.assert_array_equal(cycle_starts(u), [0, 100, 300])


def test_cycles_of_a_record_that_starts_in_the_middle_and_rises():
    u = triangles(2)[40:]           # at 60 V rising: the first valley is sample 0
    np.testing.assert_array_equal(cycle_starts(u), [0, 160])


def test_validation_judged_from_the_top_of_a_sweep():
    model = pihyst.load_model(CLASSICAL)
    u = triangles(3)
    result = validate_model(model, u, model.predict(u), first=100)
    assert result.first == 100 and result.errors.samples == u.size - 100
    assert [(a, b) for a, b, _ in result.cycles] == [(100, 200), (200, 400), (400, u.size)]


@pytest.mark.parametrize("first", [-1, 601, 700])
def test_validation_with_nothing_to_judge_is_refused(first):
    model = pihyst.load_model(CLASSICAL)
    u = triangles(3)
    with pytest.raises(InvalidArgumentError, match=f"first = {first}: no sample of the 601"):
        validate_model(model, u, model.predict(u), first=first)
