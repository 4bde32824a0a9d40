"""pyvisa-sim YAML files of the rig's ASCII dialects, so that PyVISA code (a user's own,
or PyMeasure's VISAAdapter) can be tried without the instruments or pihyst's emulators:
``keyence.yaml`` (LK-G5000 on ``ASRL1::INSTR``, LK-G3000 on ``ASRL2::INSTR``) and
``supplies.yaml`` (SCPI-like supply on ``ASRL1::INSTR``, MDT693B-like on ``ASRL2::INSTR``);
each file's comments say what it answers. Needs ``pip install pyvisa-sim``.

Examples
--------
>>> from pihyst.rig.sim import library
>>> library("keyence.yaml").endswith("keyence.yaml@sim")
True
"""

from importlib.resources import files

from pihyst.exceptions import InvalidArgumentError

__all__ = ["FILES", "library", "path"]

FILES = ("keyence.yaml", "supplies.yaml")


def path(name: str) -> str:
    """The file ``name`` (one of :data:`FILES`) of this package.

    Parameters
    ----------
    name : str
        ``"keyence.yaml"`` or ``"supplies.yaml"``.

    Returns
    -------
    str
        Its path.

    Raises
    ------
    InvalidArgumentError
        A name that is not one of :data:`FILES`.

    Examples
    --------
    >>> import os
    >>> from pihyst.rig.sim import path
    >>> os.path.isfile(path("supplies.yaml"))
    True
    """
    if name not in FILES:
        raise InvalidArgumentError(f"no pyvisa-sim file {name!r}; there are {', '.join(FILES)}")
    return str(files(__name__) / name)


def library(name: str) -> str:
    """The visa_library string that opens ``name`` with pyvisa-sim:
    ``pyvisa.ResourceManager(library("keyence.yaml"))``.

    Parameters
    ----------
    name : str
        ``"keyence.yaml"`` or ``"supplies.yaml"``.

    Returns
    -------
    str
        ``PATH@sim``.

    Raises
    ------
    InvalidArgumentError
        A name that is not one of :data:`FILES`.

    Examples
    --------
    >>> import pyvisa
    >>> from pihyst.rig.sim import library
    >>> manager = pyvisa.ResourceManager(library("keyence.yaml"))
    >>> sensor = manager.open_resource("ASRL1::INSTR", read_termination="\\r",
    ...                                write_termination="\\r")
    >>> sensor.query("MS,01")
    'MS,01,+0012.3456'
    >>> manager.close()
    """
    return f"{path(name)}@sim"
