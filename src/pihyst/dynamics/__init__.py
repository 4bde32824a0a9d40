"""Rate-dependent models: pihyst's static hysteresis followed by identified discrete
linear dynamics (Hammerstein), and the linear-only reference of the same order
(docs/theory/hammerstein.md).

- :func:`fit_hammerstein` / :class:`HammersteinModel`: classical PI per input, then
  A_j(q) y_j = sum_i B_ji(q) h_i per output;
- :func:`fit_linear` / :func:`predict_linear`: the same linear structure on the input
  itself;
- :func:`compensate_hammerstein`: zero-phase error tracking inverse of the dynamics,
  then the exact hysteresis inverse with voltage and slew limits (SISO).
"""

from pihyst.dynamics._compensate import compensate_hammerstein, zpetc
from pihyst.dynamics._hammerstein import (
    HammersteinModel,
    default_thresholds,
    fit_hammerstein,
    fit_linear,
    predict_linear,
)

__all__ = ["HammersteinModel", "compensate_hammerstein", "default_thresholds",
           "fit_hammerstein", "fit_linear", "predict_linear", "zpetc"]
