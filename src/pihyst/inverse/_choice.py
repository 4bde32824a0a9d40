"""The exact compensator of any model: :class:`pihyst.Compensator` for a PI model, the
family's own for the others (Bouc-Wen: :class:`pihyst.inverse.BoucWenCompensator`), with
the same options, so that callers (the CLI, the rig, control) need not know the family."""

from pihyst.inverse._compensator import OTHER_COMPENSATORS, Compensator


def compensator_for(model, *, creep_state=None, **options):
    """A compensator of ``model``; ``options`` as for :class:`pihyst.Compensator`
    (``u_min``, ``u_max``, ``slew_rate`` in V/s, ``sample_period``, ``initial_voltage``,
    ``initial_state``);
    ``creep_state`` for a model with creep.

    Examples
    --------
    >>> from pihyst.model import BoucWenModel
    >>> comp = compensator_for(BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0,
    ...                                     linear=40.0), u_max=100.0)
    >>> type(comp).__name__, comp.limits
    ('BoucWenCompensator', (0.0, 100.0))
    """
    cls = OTHER_COMPENSATORS.get(getattr(model, "family", None), Compensator)
    return cls(model, creep_state=creep_state, **options)
