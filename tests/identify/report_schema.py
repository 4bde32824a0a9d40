"""The declared schema of a fit's report (``FitReport.to_dict()``) and of what a saved
model records of its fit (``model.metadata["fit"]``): every key and the type of its
value. test_report_schema.py checks real fits against it; test_report_text.py checks
its example report against it, so the text's golden example has the real shape.

A key that is added, renamed or dropped in pihyst/identify/_report.py (or _creep.py,
_record_fit.py) is declared here in the same change: tools read these dicts
(docs/interfaces.md: the model file's ``metadata``), and the tests elsewhere read the
decisions through them, not through the report's wording.

Specs: a type or tuple of types (``bool`` is not a number); a dict of key -> spec, every
key required unless wrapped in ``Opt``, no other key allowed; ``[spec]``, a list of
specs; ``Map(spec)``, a dict of any str keys to spec; ``Either(a, b, ...)``.
"""

from collections.abc import Mapping


class Opt:
    """A key that may be absent."""

    def __init__(self, spec):
        self.spec = spec


class Map:
    """A dict of free str keys (family names, kinds of held-back data, states)."""

    def __init__(self, spec):
        self.spec = spec


class Either:
    def __init__(self, *specs):
        self.specs = specs


NUM = Either(int, float)          # JSON numbers (int where whole: counts, samples)
NUM_OR_NONE = Either(int, float, type(None))   # None: not finite (JSON null)
STR = str

ERRORS = {k: NUM_OR_NONE for k in ("mean_abs", "max_abs", "rms", "mean_abs_pct",
                                   "max_abs_pct", "rms_pct")}
TRIED = [{"samples": int, "rms": NUM_OR_NONE}]

DELAY = {
    "samples": int, "rule": STR, "best": Either(int, type(None)), "tried": TRIED,
    "confirmation": Either(type(None), {"family": STR, "probe_best": int, "samples": int,
                                        "rms_0": NUM_OR_NONE, "rms_d": NUM_OR_NONE,
                                        "tried": TRIED}),
    "auto": bool, "probe": STR, "refused": Opt(int),
}

START_CHOICE = Either(type(None), {"chosen": STR, "probe_fitted_rms": Map(NUM_OR_NONE),
                                   "rule": STR})

VALIDATION = Either(type(None), {"samples": int, "judged_from": int, "judged_samples": int,
                                 "interior_reversals": int, "mean_error": STR})

DATA = {
    "n_samples": int, "input_range": [NUM], "output_range": [NUM], "measured_range": NUM,
    "units": {"input": STR, "output": STR}, "initial_state": STR,
    "initial_state_choice": START_CHOICE, "settle_samples": int, "cycles": int,
    "minor_cycles": int, "holdout": STR, "fit_samples": int, "fit_cycles": int,
    "held_back_samples": int, "held_back_cycles": int, "held_back_minor_cycles": int,
    "offset": STR, "through": [int], "delay": Either(type(None), DELAY),
    "validation": VALIDATION, "fitted_on_samples": int,
}

THRESHOLD_CHOICE = Either(type(None), {
    "candidates": [NUM], "chosen": [NUM], "judged_on": STR, "search": STR,
    "subsets_evaluated": int, "size_rule": STR,
    "sizes": [{"n_operators": int, "thresholds": [NUM], "rms": NUM_OR_NONE, "search": STR}],
    "reasons": [{"threshold": NUM, "rms_without": NUM_OR_NONE,
                 "increase_without": NUM_OR_NONE, "best_replacement": Either(NUM, type(None)),
                 "rms_with_replacement": NUM_OR_NONE, "text": STR}],
    "note": Opt(STR), "shape_refined": Opt(bool),
})

REGULARIZATION = {
    "lambda": NUM, "scale": NUM, "rule": STR,
    "tried": [{"penalty": STR, "lambda": NUM, "rms": NUM_OR_NONE}], "kernels": int,
    "penalty": STR, "penalty_shape": STR,
    "product_density": Either(type(None), {"held_back_rms": NUM_OR_NONE, "rule": STR}),
    # step 13 of the decision table (identify/_kernel_pruning.py)
    "pruning": Opt(Either(type(None), {"kernels_before": int, "kernels": int,
                                       "tolerance": NUM, "record_rms": NUM,
                                       "probe_rms": NUM})),
}

LATENCY = Either(type(None), {"typical_us": NUM, "worst_us": NUM,
                              "estimated": Opt(STR), "measured": Opt(STR)})

# what each family's recipe adds (Family.options)
FAMILY_OPTIONS = {"shape": Opt({"U": NUM, "a": NUM, "b": NUM, "h": NUM}),
                  "input_function_segments": Opt(int), "grid": Opt(int),
                  "n": Opt(Either(NUM, type(None)))}

FAMILY = {
    "family": STR, "title": STR, "recipe": STR, "operator_kind": STR, "chosen": bool,
    "n_operators": int, "thresholds": Opt([NUM]), "kernels": Opt([[int]]),
    "regularization": Opt(REGULARIZATION), **FAMILY_OPTIONS,
    "weights": [NUM], "offset": NUM,
    "errors": {"fit": ERRORS, "held_back": Either(type(None), ERRORS),
               "validation": Opt(Either(type(None), ERRORS))},
    "held_back_by_kind": Map(ERRORS), "judged_rms": NUM_OR_NONE, "latency": LATENCY,
    "excluded": Either(type(None), STR), "threshold_choice": THRESHOLD_CHOICE,
    "notes": [STR], "warnings": [STR],
}

RECORD_START = {"settled": bool, "decay_rms": NUM_OR_NONE, "decay_share": NUM_OR_NONE,
                "note": STR}

# the decision on creep (fit(..., t=t)): "kept" and "reason" always; the figures it was
# judged on when it was judged (not when decided before any trial)
CREEP_DECISION = {
    "kept": bool, "reason": STR, "held_back_rms_without": Opt(NUM_OR_NONE),
    "family_without": Opt(STR), "held_back_rms_with": Opt(NUM_OR_NONE),
    "family_with": Opt(STR), "creep_total_on_fitted_cycles": Opt(NUM),
    "creep_estimated_with": Opt([{"family": STR, "family_with": STR,
                                  "held_back_rms_with": NUM_OR_NONE}]),
    "other_kind_not_tried": Opt(STR), "record_start": Opt(RECORD_START),
}

REPORT = {
    "data": DATA, "families": [FAMILY], "skipped": [{"family": STR, "reason": STR}],
    "chosen": STR, "criterion": STR, "undetermined": [STR],
    "final": {"refit": bool, "errors": Either(type(None), {
        "fit": ERRORS, "held_back": Either(type(None), ERRORS),
        "validation": Opt(Either(type(None), ERRORS))})},
    "creep": Opt(CREEP_DECISION),
}

# model.metadata["fit"]: the chosen family's entry without its per-size search, the
# data, the decisions, every family's judged RMS, and what predictions continue from
_SUMMARY_CHOICE = Either(type(None), {k: v for k, v in
                                      THRESHOLD_CHOICE.specs[1].items() if k != "sizes"})
MODEL_FIT = {
    **{k: FAMILY[k] for k in ("family", "title", "recipe", "operator_kind", "n_operators",
                              "thresholds", "kernels", "regularization", "errors",
                              "held_back_by_kind", "judged_rms", "latency", "notes")},
    "shape": FAMILY["shape"], "input_function_segments": FAMILY["input_function_segments"],
    "grid": FAMILY["grid"],
    "threshold_choice": Opt(_SUMMARY_CHOICE),
    "data": DATA, "criterion": STR, "undetermined": [STR], "final": REPORT["final"],
    "compared": Map(NUM_OR_NONE), "threshold_frame": STR,
    "record_start": Opt(Either(type(None), [NUM])),
    "settled": Opt({"sample": int, "state": Either([NUM], NUM), "pending_input": Opt([NUM])}),
    "creep": Opt({
        "decision": CREEP_DECISION,
        "tau_s": Opt([NUM]), "gain": Opt([NUM]), "dt_s": Opt(NUM), "creep_total": Opt(NUM),
        "qp_passes": Opt(int), "rms_without_creep": Opt(NUM_OR_NONE),
        "rms_with_creep": Opt(NUM_OR_NONE), "record_start": Opt(RECORD_START),
        "weights": Opt(STR), "note": Opt(STR)}),
}
# a fit with creep fitted regardless (creep=True) has no decision
MODEL_FIT["creep"].spec["decision"] = Opt(CREEP_DECISION)


def problems(value, spec, where="$"):
    """Every place where ``value`` does not follow ``spec``, as "path: what" strings."""
    if isinstance(spec, Opt):
        spec = spec.spec
    if isinstance(spec, Either):
        found = [problems(value, s, where) for s in spec.specs]
        if any(not f for f in found):
            return []
        # a dict (list) is reported against the dict (list) it should have been
        same = [f for s, f in zip(spec.specs, found)
                if isinstance(value, Mapping) and isinstance(s, (dict, Map))
                or isinstance(value, (list, tuple)) and isinstance(s, list)]
        return min(same or found, key=len)
    if isinstance(spec, Map):
        if not isinstance(value, Mapping):
            return [f"{where}: {type(value).__name__}, not a dict"]
        out = []
        for k, v in value.items():
            out += ([f"{where}: key {k!r} is not a str"] if not isinstance(k, str) else [])
            out += problems(v, spec.spec, f"{where}[{k!r}]")
        return out
    if isinstance(spec, dict):
        if not isinstance(value, Mapping):
            return [f"{where}: {type(value).__name__}, not a dict"]
        out = [f"{where}: unexpected key {k!r}" for k in value if k not in spec]
        for k, s in spec.items():
            if k in value:
                out += problems(value[k], s, f"{where}[{k!r}]")
            elif not isinstance(s, Opt):
                out.append(f"{where}: missing key {k!r}")
        return out
    if isinstance(spec, list):
        if not isinstance(value, (list, tuple)):
            return [f"{where}: {type(value).__name__}, not a list"]
        return [p for i, v in enumerate(value) for p in problems(v, spec[0], f"{where}[{i}]")]
    types = spec if isinstance(spec, tuple) else (spec,)
    if isinstance(value, bool) and bool not in types:
        return [f"{where}: a bool, not {'/'.join(t.__name__ for t in types)}"]
    if not isinstance(value, types):
        return [f"{where}: {type(value).__name__}, not {'/'.join(t.__name__ for t in types)}"]
    return []
