"""The decisions of one fit, as frozen values: what each step of :func:`pihyst.fit`
decided, why, and the figures it decided on (docs/theory/identification.md, "The
procedure"). The report and ``model.metadata["fit"]`` are built from them.
"""

from dataclasses import dataclass, field
from typing import Optional


@dataclass(frozen=True)
class StartState:
    """Step "start state": the operator state before the first sample.

    ``mode`` is one of ``_family_fit.INITIAL_STATES`` resolved ("cycled", "settle",
    "zero", "rise", "fall") or "explicit"; ``compared`` the probe's fitted RMS per state
    and the rule, when "auto" compared states (else None).
    """

    mode: str
    compared: Optional[dict] = None


@dataclass(frozen=True)
class Delay:
    """Step "delay": the samples by which the output follows the input.

    ``samples`` is the delay the models are fitted with; ``rule`` why; ``best`` the
    probe's best delay and ``tried`` its scan ({"samples", "rms"} per delay);
    ``confirmation`` the fitted structure's check (identify/_delay.py); ``auto``
    whether the delay was decided from the data; ``refused`` the delay the scan adopted
    but the chosen family did not hold back better with (then ``samples`` is 0).
    ``decided_before``: the decision was made by an earlier fit of the same record (the
    creep step's fit of the record with its creep removed), and is not made again.
    """

    samples: int
    rule: str
    best: Optional[int]
    tried: tuple
    confirmation: Optional[dict]
    auto: bool
    probe: str
    refused: Optional[int] = None
    decided_before: bool = field(default=False, compare=False)

    def refusing(self, family, judged_with, judged_without):
        """This decision with its delay refused: ``family``, the family chosen with it,
        holds back ``judged_with`` with the delay and ``judged_without`` without."""
        d = self.samples
        rule = (f"{d} samples lowered the probes' held-back RMS, but the family chosen, "
                f"{family}, holds back {judged_with:.4g} with them against "
                f"{judged_without:.4g} without: a shape the probes cannot fit, not a dead "
                f"time")
        return Delay(samples=0, rule=rule, best=self.best, tried=self.tried,
                     confirmation=self.confirmation, auto=True, probe=self.probe, refused=d)

    def given(self):
        """This decision as one already made (for a later fit of the same record)."""
        return Delay(**{**self.to_report_fields(), "decided_before": True})

    def to_report_fields(self):
        return dict(samples=self.samples, rule=self.rule, best=self.best, tried=self.tried,
                    confirmation=self.confirmation, auto=self.auto, probe=self.probe,
                    refused=self.refused)

    def to_report(self):
        """The report's ``data.delay`` entry."""
        out = {"samples": self.samples, "rule": self.rule, "best": self.best,
               "tried": [dict(t) for t in self.tried], "confirmation": self.confirmation,
               "auto": self.auto, "probe": self.probe}
        if self.refused is not None:
            out["refused"] = self.refused
        return out


@dataclass(frozen=True)
class FamiliesFitted:
    """Steps "candidate operators", "weights" and "structure", for every family: the
    families fitted (``FamilyFit``, in the order given), those skipped with why
    ({"family", "reason"}), and the warnings each family's fit gave."""

    results: tuple
    skipped: tuple
    warnings: dict


@dataclass(frozen=True)
class Choice:
    """Step "choice": the family returned, the candidates it was chosen among (each
    ``_choice.Candidate`` with why it was excluded, if it was) and the criterion."""

    chosen: object
    candidates: tuple
    criterion: str

    @property
    def excluded(self):
        """{family: why it could not be chosen} for the candidates excluded."""
        return {c.name: c.excluded for c in self.candidates if c.excluded}
