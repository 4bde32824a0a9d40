"""The exact compensator of any model: :class:`pihyst.Compensator` for a PI model, the
family's own for the others (Bouc-Wen: :class:`pihyst.inverse.BoucWenCompensator`), with
the same options, so that callers (the CLI, the rig, control) need not know the family."""

from typing import Any

from numpy.typing import ArrayLike

from pihyst.inverse._compensator import OTHER_COMPENSATORS, Compensator


def compensator_for(model: Any, *, u_min: float | None = None, u_max: float | None = None,
                    slew_rate: float | None = None, initial_voltage: float | None = None,
                    initial_state: ArrayLike | None = None,
                    creep_state: ArrayLike | None = None,
                    sample_period: float | None = None) -> Any:
    """A compensator of ``model``, of the class its family needs.

    Parameters
    ----------
    model : PIModel or BoucWenModel
        The model to invert.
    u_min, u_max, slew_rate, initial_voltage, initial_state, creep_state, sample_period
        As for :class:`pihyst.Compensator` (``slew_rate`` in V/s, converted to a step per
        sample at ``sample_period``).

    Returns
    -------
    Compensator or BoucWenCompensator
        The compensator, at its initial state.

    Raises
    ------
    InvalidModelError
        If the model cannot be inverted.
    InvalidArgumentError
        If an argument is not valid.

    Examples
    --------
    >>> from pihyst.model import BoucWenModel
    >>> comp = compensator_for(BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0,
    ...                                     linear=40.0), u_max=100.0)
    >>> type(comp).__name__, comp.limits
    ('BoucWenCompensator', (0.0, 100.0))
    """
    cls = OTHER_COMPENSATORS.get(getattr(model, "family", None), Compensator)
    return cls(model, u_min=u_min, u_max=u_max, slew_rate=slew_rate,
               initial_voltage=initial_voltage, initial_state=initial_state,
               creep_state=creep_state, sample_period=sample_period)
