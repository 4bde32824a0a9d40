"""The one place that tests the wording of a fit's text report (``print(report)``): golden
texts of two example reports that between them have every kind of line, and a line for
each start state and each penalty of a kernel basis. The reports are made from data of
the declared schema (report_schema.py, checked here), not fitted: the text depends only
on the report's data, and the decisions behind it are tested through that data by the
other tests of the fit.

When the wording changes on purpose, print the example (``print(FitReport(example()))``),
and replace the golden text after reading it.
"""

import pytest
from report_schema import REPORT, problems

from pihyst.identify._report import FitReport


def errors(rms, max_abs=None, pct=None):
    max_abs = 3 * rms if max_abs is None else max_abs
    return {"mean_abs": 0.8 * rms, "max_abs": max_abs, "rms": rms,
            "mean_abs_pct": None if pct is None else 0.8 * pct,
            "max_abs_pct": None if pct is None else 3 * pct,
            "rms_pct": pct}


def family(name, title, n_ops, fit_rms, held_rms, *, chosen=False, excluded=None,
           latency=(0.04, 0.06), by_kind=None, **extra):
    entry = {"family": name, "title": title, "recipe": f"{name}()", "operator_kind": name,
             "chosen": chosen, "n_operators": n_ops, "weights": [0.1] * n_ops,
             "offset": 1.5,
             "errors": {"fit": errors(fit_rms, pct=fit_rms),
                        "held_back": None if held_rms is None else errors(held_rms,
                                                                          pct=held_rms)},
             "held_back_by_kind": by_kind if by_kind is not None else (
                 {} if held_rms is None else {"held-back major cycles": errors(held_rms)}),
             "judged_rms": held_rms if held_rms is not None else fit_rms,
             "latency": None if latency is None else {"typical_us": latency[0],
                                                      "worst_us": latency[1],
                                                      "estimated": "by the cost model"},
             "excluded": excluded, "threshold_choice": None, "notes": [], "warnings": []}
    entry.update(extra)
    return entry


def data(**changes):
    out = {"n_samples": 2000, "input_range": [0.0, 150.0], "output_range": [1.25, 81.5],
           "measured_range": 80.25, "units": {"input": "V", "output": "um"},
           "initial_state": "cycled",
           "initial_state_choice": {"chosen": "cycled", "rule": "the lower probe RMS",
                                    "probe_fitted_rms": {"cycled": 0.0512, "zero": 1.204}},
           "settle_samples": 0, "cycles": 9, "minor_cycles": 5, "holdout": "alternate cycles",
           "fit_samples": 1100, "fit_cycles": 5, "held_back_samples": 900,
           "held_back_cycles": 4, "held_back_minor_cycles": 2, "offset": "fitted",
           "through": [], "validation": None, "fitted_on_samples": 2000,
           "delay": {"samples": 3, "auto": True, "best": 3, "probe": "classical PI, 8 plays",
                     "rule": "3 samples lower the held-back RMS of the probe by 91.8 % and of "
                             "a fitted classical model by 94.0 %, more than 5 %",
                     "tried": [{"samples": 0, "rms": 1.2}, {"samples": 3, "rms": 0.1}],
                     "confirmation": {"family": "classical", "probe_best": 3, "samples": 3,
                                      "rms_0": 1.1, "rms_d": 0.066,
                                      "tried": [{"samples": 0, "rms": 1.1},
                                                {"samples": 3, "rms": 0.066}]}}}
    out.update(changes)
    return out


def example():
    """Held-back cycles of both kinds and a validation record, a delay adopted, creep kept
    (estimated with two kinds of model, the record not at rest), a family skipped and
    one excluded, the chosen one with a shape, thresholds and their reasons."""
    kinds = {"held-back major cycles": errors(0.08), "held-back minor cycles": errors(0.1),
             "validation record": errors(3.75)}
    choice = {"candidates": [0.0, 10.0, 140.0], "chosen": [0.0, 40.0, 90.0],
              "judged_on": "held_back", "search": "exhaustive", "subsets_evaluated": 832,
              "size_rule": "smallest number of operators within 1 % of the lowest "
                           "held-back RMS",
              "sizes": [{"n_operators": 1, "thresholds": [20.0], "rms": 2.638,
                         "search": "exhaustive"},
                        {"n_operators": 3, "thresholds": [0.0, 40.0, 90.0], "rms": 0.07096,
                         "search": "exhaustive"}],
              "reasons": [{"threshold": 0.0, "rms_without": 5.012, "increase_without": 4.941,
                           "best_replacement": 10.0, "rms_with_replacement": 1.069,
                           "text": "r = 0: the first reason"},
                          {"threshold": 40.0, "rms_without": 2.246, "increase_without": 2.175,
                           "best_replacement": None, "rms_with_replacement": None,
                           "text": "r = 40: the second reason"}],
              "note": "a note on the choice"}
    families = [
        family("classical", "classical PI", 5, 0.078, 0.088, by_kind=kinds),
        family("multislope-identified", "multislope PI (identified shape)", 3, 0.0504,
               0.0747, chosen=True, by_kind=kinds, thresholds=[0.0, 39.61, 89.12],
               shape={"U": 150.0, "a": 0.1562, "b": 1.005, "h": 0.9467},
               threshold_choice=choice, notes=["a note on the fit"],
               warnings=["a warning of the fit"]),
        family("kp", "Krasnoselskii-Pokrovskii", 130, 0.031, 0.042, latency=None,
               by_kind={"held-back major cycles": errors(0.042)},
               excluded="130 operators, more than max_operators = 10"),
    ]
    val = {"samples": 398, "judged_from": 79, "judged_samples": 319, "interior_reversals": 6,
           "mean_error": "removed"}
    return {
        "data": data(validation=val), "families": families,
        "skipped": [{"family": "multislope", "reason": "the reason it was skipped"}],
        "chosen": "multislope-identified", "criterion": "the criterion",
        "undetermined": ["the first thing undetermined", "the second"],
        "final": {"refit": True, "errors": {"fit": errors(0.0534), "held_back": errors(0.0644),
                                            "validation": errors(3.757)}},
        "creep": {"kept": True, "reason": "the reason creep is kept",
                  "held_back_rms_without": 0.09, "family_without": "classical",
                  "held_back_rms_with": 0.07, "family_with": "multislope-identified",
                  "creep_total_on_fitted_cycles": 0.05,
                  "creep_estimated_with": [
                      {"family": "classical", "family_with": "multislope-identified",
                       "held_back_rms_with": 0.07},
                      {"family": "bouc-wen", "family_with": "bouc-wen",
                       "held_back_rms_with": 0.123456}],
                  "record_start": {"settled": False, "decay_rms": 0.2, "decay_share": 0.4,
                                   "note": "the note on the record's start"}},
    }


GOLDEN = "\n".join([
    'pihyst fit: 2000 samples, input 0 .. 150 V, output 1.25 .. 81.5 µm (range 80.25 µm)',
    'initial state: at rest at the bottom of the range after a full cycle (docs/interface'
    's.md) (chosen from the record: its probe fits 0.0512 from rest after a full cycle, 1'
    '.204 from the zero state)',
    '9 cycles (5 not spanning the whole range: minor); fitted: 5 cycles, 1100 samples; he'
    'ld back: 4 cycles, 900 samples (alternate cycles); offset fitted',
    '',
    'errors in µm (judged on held-back data; RMS unless stated), compensator latency per '
    'sample (typical / worst case):',
    '  family                    ops   fit RMS  held-back RMS       minor  validation   m'
    'ax |e|  % range      latency µs',
    '  classical                   5     0.078          0.088         0.1        3.75    '
    ' 0.264   0.088%    0.04 /  0.06',
    '* multislope-identified       3    0.0504         0.0747         0.1        3.75    '
    '0.2241  0.0747%    0.04 /  0.06',
    'x kp                        130     0.031          0.042           -           -    '
    ' 0.126   0.042%               -',
    '  multislope               skipped: the reason it was skipped',
    'x kp: not chosen, 130 operators, more than max_operators = 10',
    'validation record: 398 samples, judged from sample 79 (once its input had swept its '
    'range), 6 reversals inside the range; mean error removed',
    'delay: the output follows the input by 3 samples (3 samples lower the held-back RMS '
    'of the probe by 91.8 % and of a fitted classical model by 94.0 %, more than 5 %); th'
    'e model maps u[k] to y[k + 3] and carries it (model.delay)',
    'creep: kept, the reason creep is kept',
    '  creep estimated with classical: multislope-identified holds back 0.07 with creep',
    '  creep estimated with bouc-wen: bouc-wen holds back 0.1235 with creep',
    "  record start: NOT at rest (the note on the record's start)",
    'what the data could not determine:',
    '  - the first thing undetermined',
    '  - the second',
    '',
    'chosen: multislope-identified (multislope PI (identified shape)), the criterion',
    'weights refitted on all used cycles: RMS 0.0534 (fitted cycles), 0.0644 (held-back c'
    'ycles), 3.757 (validation record) µm',
    'shape: U = 150 V, a = 0.1562, b = 1.005, h = 0.9467',
    'thresholds (V, from the bottom of the range): 0, 39.61, 89.12',
    'chosen from 3 candidates (0 .. 140), exhaustive (832 subsets fitted and judged on th'
    'e held-back data); size: smallest number of operators within 1 % of the lowest held-'
    'back RMS',
    'held-back RMS of the best set of each size: 1: 2.638, 3: 0.07096*',
    'why each threshold:',
    '  r = 0: the first reason',
    '  r = 40: the second reason',
    '  (a note on the choice)',
    'note: a note on the fit',
    'warning: a warning of the fit',
])


def example_on_fitted_data():
    """Nothing held back (a long record fitted on a subsample), no delay adopted, creep
    not kept (the other kind not tried, the record at rest), a kernel basis chosen."""
    reg = {"lambda": 0.01, "scale": 1.0, "rule": "default", "tried": [], "kernels": 136,
           "penalty": "the penalty", "penalty_shape": "width", "product_density": None}
    families = [family("kp", "Krasnoselskii-Pokrovskii", 41, 0.0312, None, chosen=True,
                       kernels=[[0, 1]] * 41, grid=16, regularization=reg)]
    return {
        "data": data(holdout="none", held_back_samples=0, held_back_cycles=0,
                     held_back_minor_cycles=0, fit_samples=2000, fit_cycles=9,
                     initial_state="zero", settle_samples=0, fitted_on_samples=1500,
                     offset="fixed at 0.5", units={"input": "mV", "output": "nm"},
                     initial_state_choice={
                         "chosen": "zero", "rule": "the lowest probe RMS",
                         "probe_fitted_rms": {"rise": 0.5, "fall": 0.75, "zero": 0.0625}},
                     delay={"samples": 0, "auto": True, "best": 0, "tried": [],
                            "confirmation": None, "probe": "classical PI, 8 plays",
                            "rule": "no delay lowers the probe's held-back RMS"}),
        "families": families, "skipped": [], "chosen": "kp",
        "criterion": "lowest BIC on the fitted data (nothing held back)",
        "undetermined": [], "final": {"refit": False, "errors": None},
        "creep": {"kept": False, "reason": "the reason creep is not kept",
                  "other_kind_not_tried": "bouc-wen: the reason",
                  "record_start": {"settled": True, "decay_rms": 0.01, "decay_share": 0.02,
                                   "note": "the note"}},
    }


GOLDEN_ON_FITTED_DATA = "\n".join([
    'pihyst fit: 2000 samples, input 0 .. 150 mV, output 1.25 .. 81.5 nm (range 80.25 nm)',
    'initial state: all operator outputs zero (a record from the zero state: its first ri'
    'se is the initial loading curve) (chosen from the record: its first full sweep comes'
    ' too late to settle the operators; its probe fits 0.5 after a rise from the bottom, '
    '0.75 after a fall from the top, 0.0625 from the zero state)',
    '9 cycles (5 not spanning the whole range: minor); fitted: 9 cycles, 2000 samples; he'
    'ld back: none; offset fixed at 0.5',
    'fitted and judged on 1500 of the 2000 samples (evenly spaced, and every input extrem'
    "um: the operators' outputs there are exactly the whole record's)",
    '',
    'errors in nm (on the fitted data; RMS unless stated), compensator latency per sample'
    ' (typical / worst case):',
    '  family                    ops   fit RMS   max |e|  % range      latency µs',
    '* kp                         41    0.0312    0.0936  0.0312%    0.04 /  0.06',
    "delay: none (no delay lowers the probe's held-back RMS)",
    'creep: not kept, the reason creep is not kept',
    '  other kind not tried: bouc-wen: the reason',
    '  record start: at rest (the note)',
    '',
    'chosen: kp (Krasnoselskii-Pokrovskii), lowest BIC on the fitted data (nothing held b'
    'ack)',
    '136 kernels on a grid, 41 with non-zero weight; regularized towards a density of the'
    ' loop width, lambda = 0.01 (default)',
])


@pytest.mark.parametrize("make, golden", [(example, GOLDEN),
                                          (example_on_fitted_data, GOLDEN_ON_FITTED_DATA)])
def test_the_text_report(make, golden):
    report = make()
    assert problems(report, REPORT) == []        # the example has the real report's shape
    assert str(FitReport(report)) == golden


@pytest.mark.parametrize("state, text", [
    ("cycled", "at rest at the bottom of the range after a full cycle (docs/interfaces.md)"),
    ("settle", "unknown; settled by the first full sweep of the input range (not fitted) "
               "(120 samples)"),
    ("zero", "all operator outputs zero (a record from the zero state: its first rise is "
             "the initial loading curve)"),
    ("rise", "at rest at the first input, reached by a rise from rest at the bottom of the "
             "range"),
    ("fall", "at rest at the first input, reached by a fall from rest at the top of the "
             "range"),
    ("explicit", "given"),
])
def test_the_start_state_line(state, text):
    report = example_on_fitted_data()
    report["data"].update(initial_state=state, initial_state_choice=None,
                          settle_samples=120 if state == "settle" else 0)
    assert str(FitReport(report)).splitlines()[1] == f"initial state: {text}"


@pytest.mark.parametrize("shape, product, lines", [
    ("separable", None, ["regularized towards a separable density with a smooth reversible "
                         "part, lambda = 0.01 (default)"]),
    ("other", None, ["regularized towards its penalty, lambda = 0.01 (default)"]),
    ("separable", {"held_back_rms": 0.5, "rule": "the product density's rule"},
     ["regularized towards a separable density with a smooth reversible part, lambda = "
      "0.01 (default)", "the product density's rule"]),
])
def test_the_regularization_lines(shape, product, lines):
    report = example_on_fitted_data()
    reg = report["families"][0]["regularization"]
    reg.update(penalty_shape=shape, product_density=product)
    text = str(FitReport(report)).splitlines()
    start = next(i for i, line in enumerate(text) if line.startswith("136 kernels"))
    assert text[start].endswith(lines[0]) and text[start + 1:] == lines[1:]
