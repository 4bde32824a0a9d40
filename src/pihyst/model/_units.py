"""Units as people read them. A model file names its units in ASCII (``"um"``, as the
column names of docs/interfaces.md do: ``displacement_um``); what pihyst prints spells
them µm and µs."""

DISPLAY = {"um": "µm", "us": "µs"}


def display_unit(unit):
    """``unit`` as printed: µm for ``"um"``, µs for ``"us"``, any other as it is."""
    return DISPLAY.get(unit, unit)


def output_unit(model):
    """The printed unit of ``model``'s output (its displacement)."""
    return display_unit(model.units.get("output", "um"))
