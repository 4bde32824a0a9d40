"""The result of :func:`pihyst.fit`: the model and a report of how it was chosen.

The report is a plain JSON-ready dict (``report.to_dict()``, ``report.to_json()``) and
prints as a table (``print(report)``).
"""

import copy
import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pihyst.identify._assess import KINDS
from pihyst.model._units import display_unit


def _state_choice_text(choice: dict[str, Any] | None) -> str:
    """How "auto" chose the initial state, when it compared (identify/_start_state.py)."""
    if not choice:
        return ""
    rms = choice["probe_fitted_rms"]
    if "rise" in rms:
        return (f" (chosen from the record: its first full sweep comes too late to settle "
                f"the operators; its probe fits {rms['rise']:.4g} after a rise from the "
                f"bottom, {rms['fall']:.4g} after a fall from the top, {rms['zero']:.4g} from "
                f"the zero state)")
    return (f" (chosen from the record: its probe fits {rms['cycled']:.4g} from rest after a "
            f"full cycle, {rms['zero']:.4g} from the zero state)")


_STATE_TEXT = {
    "cycled": "at rest at the bottom of the range after a full cycle (docs/interfaces.md)",
    "settle": "unknown; settled by the first full sweep of the input range (not fitted)",
    "zero": "all operator outputs zero (a record from the zero state: its first rise is "
            "the initial loading curve)",
    "rise": "at rest at the first input, reached by a rise from rest at the bottom of the "
            "range",
    "fall": "at rest at the first input, reached by a fall from rest at the top of the "
            "range",
    "explicit": "given",
}


@dataclass
class FitResult:
    """What :func:`pihyst.fit` returns.

    Parameters
    ----------
    model : PIModel or BoucWenModel
        The most accurate model (weights refitted on all cycles unless ``refit=False``).
    report : FitReport
        Errors, the comparison of families, the threshold choice and its reasons.
    models : dict
        Every fitted family's model by family name.

    Examples
    --------
    >>> import numpy as np
    >>> import pihyst
    >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
    >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
    >>> res = pihyst.fit(u, y, family="classical", thresholds=[0, 30])
    >>> res.report.chosen, sorted(res.models)
    ('classical', ['classical'])
    >>> [round(float(w), 6) for w in res.model.weights]
    [0.3, 0.2]
    """

    model: Any
    report: "FitReport"
    models: dict[str, Any] = field(default_factory=dict)


def _num(x: Any) -> Any:
    if x is None:
        return None
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_num(v) for v in x]
    if isinstance(x, dict):
        return {k: _num(v) for k, v in x.items()}
    if isinstance(x, (bool, str)):
        return x
    if isinstance(x, (int, np.integer)):
        return int(x)
    v = float(x)
    return v if np.isfinite(v) else None


class FitReport:
    """Report of a fit; ``to_dict()`` gives the data, ``str()`` a table.

    :func:`pihyst.fit` builds it (:meth:`build`); ``FitReport(report.to_dict())`` is the
    same report again.

    Parameters
    ----------
    data : dict
        The report's JSON-ready data, as :meth:`to_dict` returns it.

    Examples
    --------
    >>> import numpy as np
    >>> import pihyst
    >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
    >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
    >>> report = pihyst.fit(u, y, family="classical", thresholds=[0, 30]).report
    >>> report.chosen
    'classical'
    >>> FitReport(report.to_dict()).to_dict() == report.to_dict()
    True
    """

    def __init__(self, data: dict[str, Any]) -> None:
        self._data = data

    @classmethod
    def build(cls, rec: Any, start: Any, choice: Any, skipped: list[dict[str, Any]], *,
              refit: bool, final_errors: dict[str, Any] | None, delay: dict[str, Any] | None,
              validation: dict[str, Any] | None, undetermined: list[str],
              fitted_on: int | None = None) -> "FitReport":
        """The report of a fit of the framed record ``rec`` from the decisions made on it.

        Parameters
        ----------
        rec : FramedRecord
            The record in the fitting frame (``pihyst.identify._family_fit``).
        start : StartState
            The start state decided (``pihyst.identify._decisions``).
        choice : Choice
            The families compared and the one chosen (``pihyst.identify._decisions``).
        skipped : list of dict
            The families skipped, each ``{"family": name, "reason": text}``.
        refit : bool
            Whether the chosen structure's weights were refitted on all cycles.
        final_errors : dict or None
            The refitted model's errors (``"fit"``, ``"held_back"``, ``"validation"``).
        delay : dict or None
            The delay's report entry.
        validation : dict or None
            The validation record's description.
        undetermined : list of str
            What the data could not determine.
        fitted_on : int, optional
            The samples a long record was fitted and judged on (all if None).

        Returns
        -------
        FitReport
            The report, its data JSON-ready.

        Examples
        --------
        :func:`pihyst.fit` calls it as its last step; the result is its report:

        >>> import numpy as np
        >>> import pihyst
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> report = pihyst.fit(u, y, family="classical", thresholds=[0, 30]).report
        >>> isinstance(report, FitReport)
        True
        """
        lay = rec.layout
        candidates, chosen = choice.candidates, choice.chosen.name
        units = dict(candidates[0].fitted.model.units)
        data = {
            "n_samples": int(rec.u.size),
            "input_range": [rec.lo, rec.lo + rec.S],
            "output_range": [float(rec.y.min()), float(rec.y.max())],
            "measured_range": rec.measured_range,
            "units": units,
            "initial_state": start.mode,
            "initial_state_choice": start.compared,
            "settle_samples": int(lay.settle_end),
            "cycles": lay.n_cycles,
            "minor_cycles": lay.n_minor,
            "holdout": lay.holdout,
            "fit_samples": lay.count("fit"),
            "fit_cycles": lay.cycles("fit"),
            "held_back_samples": lay.count("held_back"),
            "held_back_cycles": lay.cycles("held_back"),
            "held_back_minor_cycles": lay.cycles("held_back", "minor"),
            "offset": "fitted" if rec.fit_offset else f"fixed at {rec.fixed_offset:g}",
            "through": list(rec.through),
            "delay": delay,
            "validation": validation,
            "fitted_on_samples": int(rec.u.size if fitted_on is None else fitted_on),
        }
        families = [cls._family_entry(c, c.name == chosen, rec.S) for c in candidates]
        out = {"data": data, "families": families, "skipped": list(skipped),
               "chosen": chosen, "criterion": choice.criterion, "undetermined": list(undetermined),
               "final": {"refit": refit, "errors": final_errors}}
        return cls(_num(out))

    @staticmethod
    def _family_entry(c: Any, is_chosen: bool, S: float) -> dict[str, Any]:
        r = c.fitted
        fam = r.family
        entry = {"family": r.name, "title": fam.title, "recipe": repr(fam),
                 "operator_kind": r.model.family, "chosen": is_chosen,
                 "n_operators": r.n_operators}
        entry[fam.operators_key] = ([list(p) for p in r.operators]
                                    if fam.operators_key == "kernels"
                                    else [float(t) for t in r.operators])
        if r.regularization is not None:
            entry["regularization"] = r.regularization
        entry.update(fam.options(S))
        entry["weights"] = [float(w) for w in r.weights]
        entry["offset"] = r.offset
        entry["errors"] = r.errors
        entry["held_back_by_kind"] = {KINDS[k]: e for k, e in c.by_kind.items()}
        entry["judged_rms"] = c.judged_rms
        entry["latency"] = None if c.latency is None else c.latency.to_dict()
        entry["excluded"] = c.excluded
        entry["threshold_choice"] = r.threshold_choice
        entry["notes"] = list(r.notes)
        entry["warnings"] = list(r.warnings)
        return entry

    def with_creep(self, decision: dict[str, Any]) -> "FitReport":
        """This report with the decision on creep (``fit(..., t=t)``) added.

        Parameters
        ----------
        decision : dict
            The decision on creep: ``"kept"``, ``"reason"`` and what it was judged on.

        Returns
        -------
        FitReport
            A new report; this one is unchanged.

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> report = pihyst.fit(u, y, family="classical", thresholds=[0, 30]).report
        >>> report.with_creep({"kept": False, "reason": "example"}).to_dict()["creep"]
        {'kept': False, 'reason': 'example'}
        """
        data = self.to_dict()
        data["creep"] = _num(decision)
        return type(self)(data)

    # ------------------------------------------------------------------ access
    def to_dict(self) -> dict[str, Any]:
        """The report as a JSON-ready dict (a copy).

        Returns
        -------
        dict
            ``"data"``, ``"families"``, ``"skipped"``, ``"chosen"``, ``"criterion"``,
            ``"undetermined"``, ``"final"`` (and ``"creep"`` when decided).

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> report = pihyst.fit(u, y, family="classical", thresholds=[0, 30]).report
        >>> report.to_dict()["data"]["n_samples"]
        453
        """
        return copy.deepcopy(self._data)

    def to_json(self, indent: int | None = 2) -> str:
        """The report as JSON text.

        Parameters
        ----------
        indent : int or None
            Indentation of the JSON text (None: one line).

        Returns
        -------
        str
            The JSON text of :meth:`to_dict`.

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> report = pihyst.fit(u, y, family="classical", thresholds=[0, 30]).report
        >>> import json
        >>> json.loads(report.to_json())["chosen"]
        'classical'
        """
        return json.dumps(self._data, indent=indent)

    @property
    def chosen(self) -> str:
        """Name of the family returned."""
        return self._data["chosen"]

    @property
    def families(self) -> list[dict[str, Any]]:
        """Per-family entries, as dicts."""
        return copy.deepcopy(self._data["families"])

    def family(self, name: str) -> dict[str, Any]:
        """One family's entry, as a dict (a copy).

        Parameters
        ----------
        name : str
            The family's name (e.g. ``"classical"``).

        Returns
        -------
        dict
            Its operators, weights, errors, latency, threshold choice, notes.

        Raises
        ------
        KeyError
            If no family of that name was fitted.

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> report = pihyst.fit(u, y, family="classical", thresholds=[0, 30]).report
        >>> report.family("classical")["thresholds"]
        [0.0, 30.0]
        """
        for f in self._data["families"]:
            if f["family"] == name:
                return copy.deepcopy(f)
        raise KeyError(name)

    def model_summary(self) -> dict[str, Any]:
        """What a saved model records about its fit (``model.metadata["fit"]``).

        Returns
        -------
        dict
            The chosen family's entry (without the per-size search), the data, the
            criterion, what was undetermined, the refit and every family's judged RMS.

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> report = pihyst.fit(u, y, family="classical", thresholds=[0, 30]).report
        >>> summary = report.model_summary()
        >>> summary["family"], sorted(summary["compared"])
        ('classical', ['classical'])
        """
        best = self.family(self.chosen)
        keep = ("family", "title", "recipe", "operator_kind", "n_operators", "thresholds",
                "kernels", "shape", "input_function_segments", "grid", "regularization",
                "errors", "held_back_by_kind", "judged_rms", "latency", "threshold_choice",
                "notes")
        summary = {k: best[k] for k in keep if k in best}
        if summary.get("threshold_choice"):
            summary["threshold_choice"] = {k: v for k, v in best["threshold_choice"].items()
                                           if k != "sizes"}
        summary["data"] = self._data["data"]
        summary["criterion"] = self._data["criterion"]
        summary["undetermined"] = self._data["undetermined"]
        summary["final"] = self._data["final"]
        summary["compared"] = {f["family"]: f["judged_rms"] for f in self._data["families"]}
        summary["threshold_frame"] = ("thresholds are measured from the bottom of the "
                                      "input range (input_range[0])")
        return summary

    # ------------------------------------------------------------------ text
    def __str__(self) -> str:
        return "\n".join(self._data_lines() + self._family_lines() + self._record_lines()
                         + self._chosen_lines())

    def _data_lines(self) -> list[str]:
        """The record: samples, ranges, start state, cycles, what was held back."""
        d = self._data["data"]
        uin, uout = d["units"].get("input", "V"), display_unit(d["units"].get("output", "um"))
        lines = [
            f"pihyst fit: {d['n_samples']} samples, input {d['input_range'][0]:.6g} .. "
            f"{d['input_range'][1]:.6g} {uin}, output {d['output_range'][0]:.6g} .. "
            f"{d['output_range'][1]:.6g} {uout} (range {d['measured_range']:.4g} {uout})",
            f"initial state: {_STATE_TEXT.get(d['initial_state'], d['initial_state'])}"
            + (f" ({d['settle_samples']} samples)" if d["settle_samples"] else "")
            + _state_choice_text(d.get("initial_state_choice")),
            f"{d['cycles']} cycles ({d['minor_cycles']} not spanning the whole range: minor); "
            f"fitted: {d['fit_cycles']} cycles, {d['fit_samples']} samples; held back: "
            + (f"{d['held_back_cycles']} cycles, {d['held_back_samples']} samples "
               f"({d['holdout']})" if d["held_back_samples"] else "none") +
            f"; offset {d['offset']}",
        ]
        if d.get("fitted_on_samples", d["n_samples"]) < d["n_samples"]:
            lines.append(f"fitted and judged on {d['fitted_on_samples']} of the "
                         f"{d['n_samples']} samples (evenly spaced, and every input extremum: "
                         f"the operators' outputs there are exactly the whole record's)")
        return lines + [""]

    def _family_lines(self) -> list[str]:
        """The table of families: errors, latency, skipped and excluded ones."""
        d = self._data["data"]
        uout = display_unit(d["units"].get("output", "um"))
        lines = []
        held = d["held_back_samples"] > 0
        fams = self._data["families"]
        kinds = [k for k in ("held-back minor cycles", "validation record")
                 if any(k in f["held_back_by_kind"] for f in fams)]
        short = {"held-back minor cycles": "minor", "validation record": "validation"}
        head = (f"  {'family':<24}{'ops':>5}{'fit RMS':>10}"
                + (f"{'held-back RMS':>15}" if held else "")
                + "".join(f"{short[k]:>12}" for k in kinds)
                + f"{'max |e|':>10}{'% range':>9}{'latency µs':>16}")
        judged = ("judged on held-back data" if held or kinds else "on the fitted data")
        lines += [f"errors in {uout} ({judged}; RMS unless stated), compensator latency "
                  f"per sample (typical / worst case):", head]
        for f in fams:
            e = f["errors"]
            j = e["held_back"] if held else e["fit"]
            mark = "*" if f["chosen"] else ("x" if f["excluded"] else " ")
            row = f"{mark} {f['family']:<24}{f['n_operators']:>5}{e['fit']['rms']:>10.4g}"
            if held:
                row += f"{j['rms']:>15.4g}"
            for k in kinds:
                v = f["held_back_by_kind"].get(k)
                row += f"{v['rms']:>12.4g}" if v else f"{'-':>12}"
            row += f"{j['max_abs']:>10.4g}{j['rms_pct']:>8.3g}%"
            lat = f["latency"]
            row += (f"{lat['typical_us']:>8.3g} /{lat['worst_us']:>6.3g}" if lat
                    else f"{'-':>16}")
            lines.append(row)
        for s in self._data["skipped"]:
            lines.append(f"  {s['family']:<24} skipped: {s['reason']}")
        for f in fams:
            if f["excluded"]:
                lines.append(f"x {f['family']}: not chosen, {f['excluded']}")
        return lines

    def _record_lines(self) -> list[str]:
        """The validation record, the delay, creep and what the data could not tell."""
        d = self._data["data"]
        lines = []
        val = d.get("validation")
        if val:
            lines.append(f"validation record: {val['samples']} samples, judged from sample "
                         f"{val['judged_from']} (once its input had swept its range), "
                         f"{val['interior_reversals']} reversals inside the range; mean "
                         f"error removed")
        delay = d.get("delay")
        if delay and delay["samples"]:
            lines.append(f"delay: the output follows the input by {delay['samples']} samples "
                         f"({delay['rule']}); the model maps u[k] to y[k + {delay['samples']}] "
                         f"and carries it (model.delay)")
        elif delay and delay.get("auto"):
            lines.append(f"delay: none ({delay['rule']})")
        creep = self._data.get("creep")
        if creep:
            lines.append(f"creep: {'kept' if creep['kept'] else 'not kept'}, "
                         f"{creep['reason']}")
            for e in creep.get("creep_estimated_with", []):
                lines.append(f"  creep estimated with {e['family']}: {e['family_with']} "
                             f"holds back {e['held_back_rms_with']:.4g} with creep")
            if creep.get("other_kind_not_tried"):
                lines.append(f"  other kind not tried: {creep['other_kind_not_tried']}")
            start = creep.get("record_start")
            if start:
                lines.append(f"  record start: {'at rest' if start['settled'] else 'NOT at rest'}"
                             f" ({start['note']})")
        if self._data["undetermined"]:
            lines.append("what the data could not determine:")
            lines += [f"  - {t}" for t in self._data["undetermined"]]
        return lines

    def _chosen_lines(self) -> list[str]:
        """The chosen family: the criterion, the refit, its structure and why."""
        d = self._data["data"]
        uin, uout = d["units"].get("input", "V"), display_unit(d["units"].get("output", "um"))
        lines = []
        best = self.family(self.chosen)
        lines += ["", f"chosen: {best['family']} ({best['title']}), {self._data['criterion']}"]
        fin = self._data["final"]
        if fin["refit"]:
            ef = fin["errors"]
            lines.append(f"weights refitted on all used cycles: RMS {ef['fit']['rms']:.4g} "
                         f"(fitted cycles), {ef['held_back']['rms']:.4g} (held-back cycles)"
                         + (f", {ef['validation']['rms']:.4g} (validation record)"
                            if ef.get("validation") else "") + f" {uout}")
        if "shape" in best:
            s = best["shape"]
            lines.append(f"shape: U = {s['U']:.6g} {uin}, a = {s['a']:.4g}, b = {s['b']:.4g}, "
                         f"h = {s['h']:.4g}")
        if best.get("thresholds"):
            lines.append(f"thresholds ({uin}, from the bottom of the range): "
                         + ", ".join(f"{t:.4g}" for t in best["thresholds"]))
        if "regularization" in best:
            reg = best["regularization"]
            towards = {"separable": "a separable density with a smooth reversible part",
                       "width": "a density of the loop width"}.get(reg.get("penalty_shape"),
                                                                   "its penalty")
            lines.append(f"{reg['kernels']} kernels on a grid, {best['n_operators']} with "
                         f"non-zero weight; regularized towards {towards}, lambda = "
                         f"{reg['lambda']:.3g} ({reg['rule']})")
            product = reg.get("product_density")
            if product:
                lines.append(product["rule"])
            cut = reg.get("pruning")
            if cut and cut["kernels"] < cut["kernels_before"]:
                lines.append(f"{cut['kernels_before']} -> {cut['kernels']} kernels: the same "
                             f"model to {cut['tolerance']:.3g} {uout} RMS on the fitted cycles "
                             f"({cut['record_rms']:.3g}) and on reversal curves over the "
                             f"Preisach plane ({cut['probe_rms']:.3g})")
        ch = best.get("threshold_choice")
        if ch:
            where = "held-back" if ch["judged_on"] == "held_back" else "fitted"
            lines.append(f"chosen from {len(ch['candidates'])} candidates "
                         f"({ch['candidates'][0]:.4g} .. {ch['candidates'][-1]:.4g}), "
                         f"{ch['search']} ({ch['subsets_evaluated']} subsets fitted and "
                         f"judged on the {where} data); size: {ch['size_rule']}")
            if len(ch["sizes"]) > 1:
                n_best = len(ch["chosen"])
                lines.append(f"{where} RMS of the best set of each size: " + ", ".join(
                    f"{s['n_operators']}: {s['rms']:.4g}" + ("*" if s["n_operators"] == n_best
                                                             else "")
                    for s in ch["sizes"]))
            lines.append("why each threshold:")
            lines += [f"  {r['text']}" for r in ch["reasons"]]
            if ch.get("note"):
                lines.append(f"  ({ch['note']})")
        for n in best["notes"]:
            lines.append(f"note: {n}")
        for w in best["warnings"]:
            lines.append(f"warning: {w}")
        return lines
