"""Analytic inverse of the classical Prandtl-Ishlinskii model (docs/theory/inverse.md).

The model ``y = offset + sum_i w_i F_{r_i}[u]`` with classical play operators F_r,
thresholds ``0 = r_0 < r_1 < ... < r_{n-1}`` and partial sums ``S_i = sum_{j<=i} w_j``
all positive has the inverse (paper eqs. 21-25, correctly indexed: sums from j = 0)

    u = offset' + sum_i w'_i F_{r'_i}[y]
    r'_i    = sum_{j<=i} w_j (r_i - r_j)
    w'_0    = 1 / w_0,      w'_i = -w_i / (S_i S_{i-1})   (i >= 1)
    offset' = -offset / S_{n-1}                            (sum_i w'_i = 1 / S_{n-1})

another classical PI model, with negative weights. Its operators track the model's:

    F_{r'_i}[y] = offset + S_i F_{r_i}[u] + sum_{j>i} w_j F_{r_j}[u],

which gives the inverse's initial state from the model's, and, substituted above,
u = F_{r_0}[u] (the coefficient of F_{r_m}[u], m >= 1, is w'_m S_m + w_m / S_{m-1} = 0).

The inverse's input is the displacement: its input range is the model's reachable
output range (every output the model can produce from its initial state with inputs
in its input range), widened by 1e-12 of its scale for rounding.

For models with multislope or polyline operators (or any w >= 0) the exact inverse is
the compensator of :mod:`pihyst.inverse`.
"""

from typing import TYPE_CHECKING

import numpy as np

from pihyst.exceptions import InvalidModelError

if TYPE_CHECKING:   # _models imports this module
    from pihyst.model._models import ClassicalPI, PIModel

__all__ = ["classical_inverse", "reachable_output_range"]


def reachable_output_range(model: "PIModel") -> tuple[float, float]:
    """An interval holding every output ``model`` can produce from its initial state.

    Each operator output f_k stays within [min(f_k[-1], F_k(u_min)), max(f_k[-1],
    R_k(u_max))]: it can only be pushed down by F_k and up by R_k. The output bound is
    the weighted sum of those ends (by the sign of each weight).

    Parameters
    ----------
    model : PIModel
        Any PI model.

    Returns
    -------
    (float, float)
        The lowest and highest output it can reach (µm).

    Examples
    --------
    >>> from pihyst.model import ClassicalPI
    >>> m = ClassicalPI([0, 10, 30, 150], [0.008, 0.252, 0.019, 0.582])
    >>> lo, hi = reachable_output_range(m)
    >>> float(lo), round(float(hi), 2)
    (0.0, 38.76)
    """
    lo_u, hi_u = model.input_range
    _, fall_lo = model.envelopes(lo_u)
    rise_hi, _ = model.envelopes(hi_u)
    f0 = model.initial_state
    f_min = np.minimum(f0, fall_lo)
    f_max = np.maximum(f0, rise_hi)
    w = model.weights
    y_min = model.offset + np.sum(np.where(w >= 0, w * f_min, w * f_max))
    y_max = model.offset + np.sum(np.where(w >= 0, w * f_max, w * f_min))
    return float(y_min), float(y_max)


def classical_inverse(model: "ClassicalPI") -> "ClassicalPI":
    """The classical PI model of the inverse of a classical PI ``model``.

    Parameters
    ----------
    model : ClassicalPI
        Needs ``thresholds[0] == 0`` and every partial sum of weights
        ``S_i = w_0 + ... + w_i`` positive (true for w_0 > 0 and w >= 0; also true
        for an inverse, so ``classical_inverse(classical_inverse(m))`` gives ``m``
        back).

    Returns
    -------
    ClassicalPI
        Input: displacement (input range: the model's reachable output range);
        output: voltage. Its initial state corresponds to the model's.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.model import ClassicalPI
    >>> m = ClassicalPI([0, 10, 30, 150], [0.008, 0.252, 0.019, 0.582])
    >>> inv = classical_inverse(m)
    >>> u = np.r_[np.arange(0, 151), np.arange(149, -1, -1)].astype(float)
    >>> bool(np.allclose(inv.predict(m.predict(u)), u, atol=1e-9))
    True
    """
    if model.family != "classical":
        raise InvalidModelError(f"the analytic inverse is for classical PI models, not "
                                f"{type(model).__name__}; use pihyst.compensate for others")
    r = model.thresholds
    w = model.weights
    if r[0] != 0:
        raise InvalidModelError(f"the analytic inverse needs a first threshold of 0 (a "
                                f"linear part), got {r[0]:g}")
    s = np.cumsum(w)  # S_i = sum_{j<=i} w_j
    bad = np.flatnonzero(s <= 0)
    if bad.size:
        raise InvalidModelError(f"the analytic inverse needs positive partial sums of the "
                                f"weights; w_0 + ... + w_{bad[0]} = {s[bad[0]]:g}")

    # r'_i = sum_{j<=i} w_j (r_i - r_j) = S_i r_i - sum_{j<=i} w_j r_j
    r_inv = s * r - np.cumsum(w * r)
    r_inv[0] = 0.0
    # w'_0 = 1/w_0,  w'_i = -w_i / (S_i S_{i-1})
    w_inv = np.empty_like(w)
    w_inv[0] = 1.0 / w[0]
    w_inv[1:] = -w[1:] / (s[1:] * s[:-1])
    offset_inv = -model.offset / s[-1]
    # q_i = offset + S_i f_i + sum_{j>i} w_j f_j
    f = model.initial_state
    tail = np.concatenate([np.cumsum((w * f)[::-1])[::-1][1:], [0.0]])
    state_inv = model.offset + s * f + tail

    y_lo, y_hi = reachable_output_range(model)
    pad = 1e-12 * (abs(y_lo) + abs(y_hi) + 1.0)
    units = {"input": model.units.get("output", "um"), "output": model.units.get("input", "V")}
    return model.replace(thresholds=r_inv, weights=w_inv, offset=offset_inv,
                         input_range=(y_lo - pad, y_hi + pad), initial_state=state_inv,
                         units=units,
                         metadata={"inverse_of": {"family": "classical",
                                                  "thresholds": r.tolist(),
                                                  "weights": w.tolist(),
                                                  "offset": model.offset}})
