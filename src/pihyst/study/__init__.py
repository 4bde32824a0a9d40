"""The paper's study end to end, and the same fit-and-compare study on a user's record:
computation (``_paper_study``), figures (``_plot``) and the report folder (``_report``).

The top layer with :mod:`pihyst.rig` and :mod:`pihyst.cli`: it uses identification,
inversion and the simulated beams; nothing below imports it. The paper's numbers come
from :mod:`pihyst.paper` (docs/paper.md).
"""

from pihyst.study._paper_study import (
    CLASSICAL_THRESHOLDS,
    MULTISLOPE_THRESHOLDS,
    PAPER,
    FittedModel,
    Recording,
    Study,
    fit_paper_models,
    loop_study,
    paper_study,
    signed_extremes,
)
from pihyst.study._report import write_report

__all__ = ["CLASSICAL_THRESHOLDS", "MULTISLOPE_THRESHOLDS", "PAPER", "FittedModel",
           "Recording", "Study", "fit_paper_models", "loop_study", "paper_study",
           "signed_extremes", "write_report"]
