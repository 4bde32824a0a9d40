"""pyvisa-sim YAML files of the rig's ASCII dialects, so that PyVISA code (a user's own,
or PyMeasure's VISAAdapter) can be tried without the instruments or pihyst's emulators:
``keyence.yaml`` (LK-G5000 on ``ASRL1::INSTR``, LK-G3000 on ``ASRL2::INSTR``) and
``supplies.yaml`` (SCPI-like supply on ``ASRL1::INSTR``, MDT693B-like on ``ASRL2::INSTR``);
each file's comments say what it answers. Needs ``pip install pyvisa-sim``.

Examples
--------
>>> library("keyence.yaml").endswith("keyence.yaml@sim")
True
"""

from importlib.resources import files

from pihyst.exceptions import InvalidArgumentError

FILES = ("keyence.yaml", "supplies.yaml")


def path(name):
    """The file ``name`` (one of :data:`FILES`) of this package."""
    if name not in FILES:
        raise InvalidArgumentError(f"no pyvisa-sim file {name!r}; there are {', '.join(FILES)}")
    return str(files(__name__) / name)


def library(name):
    """The visa_library string that opens ``name`` with pyvisa-sim:
    ``pyvisa.ResourceManager(library("keyence.yaml"))``."""
    return f"{path(name)}@sim"
