"""Every exception and warning pihyst raises, in one place (the lowest layer).

- :class:`InvalidModelError`: parameters that do not describe a valid model;
- :class:`InputRangeError`: an input sample outside a model's input range;
- :class:`RecordError`: a record (data file) that cannot be used, and its subclass
  :class:`CSVError` for delimited text (file, line and column named);
- :class:`FitError`, :class:`InfeasibleConstraintsError`: data that cannot be fitted as asked;
- :class:`PihystWarning`, :class:`IllConditionedWarning`: warnings.

Each is a ``ValueError`` (or a ``UserWarning``), so ``except ValueError`` still catches them.
"""


class PihystWarning(UserWarning):
    """Base class of every warning pihyst issues."""


class IllConditionedWarning(PihystWarning):
    """The least-squares problem is ill-conditioned: some weights are not determined by
    the data. The solution returned is still the best admissible one (with a tiny
    regularization that picks the smallest such weights), but those weights mean little."""


class FitError(ValueError):
    """The data cannot be fitted as asked; the message says why.

    ``index`` is the 0-based sample the problem is at, and ``column`` is ``"input"`` or
    ``"output"``, when they are known (the command line turns them into file:line:column).
    """

    def __init__(self, message, *, index=None, column=None):
        super().__init__(message)
        self.index = index
        self.column = column


class InfeasibleConstraintsError(FitError):
    """No weights satisfy the constraints (bounds and equality constraints together)."""


class InvalidModelError(ValueError):
    """The parameters do not describe a valid model; the message says which and why."""


class InputRangeError(ValueError):
    """An input sample lies outside the model's input range."""

    def __init__(self, index, value, input_range):
        self.index = index
        self.value = value
        super().__init__(f"sample {index}: input {value:g} is outside the model's input range "
                         f"[{input_range[0]:g}, {input_range[1]:g}]")


class RecordError(ValueError):
    """A record could not be used: ``FILE: where: what is wrong`` (``where`` names the
    variable and sample of an array file)."""

    def __init__(self, path, message):
        self.path, self.message = path, message
        super().__init__(f"{path}: {message}")


class CSVError(RecordError):
    """A CSV file could not be used; the message names file, line and column."""

    def __init__(self, path, line, column, message):
        self.line, self.column = line, column
        where = f"{path}:{line}:{column}" if column else f"{path}:{line}"
        ValueError.__init__(self, f"{where}: {message}")
        self.path, self.message = path, message
