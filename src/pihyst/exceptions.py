"""Every exception and warning pihyst raises, in one place (the lowest layer).

- :class:`InvalidModelError`: parameters that do not describe a valid model;
- :class:`InputRangeError`: an input sample outside a model's input range;
- :class:`RecordError`: a record (data file) that cannot be used, and its subclass
  :class:`CSVError` for delimited text (file, line and column named);
- :class:`FitError`, :class:`InfeasibleConstraintsError`: data that cannot be fitted as asked;
- :class:`InvalidArgumentError`, :class:`ResourceLimitError`: any other invalid argument of
  a pihyst function (wrong type, out of range, too large to process);
- :class:`PihystWarning`, :class:`IllConditionedWarning`, :class:`InsufficientDataWarning`:
  warnings.

Each is a ``ValueError`` (or a ``UserWarning``), so ``except ValueError`` still catches them;
:class:`InvalidArgumentError` is also a ``TypeError``, for arguments of the wrong type.
The rules (and the command line's exit statuses) are in docs/errors.md.
"""

import os


class PihystWarning(UserWarning):
    """Base class of every warning pihyst issues.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", PihystWarning)   # silences all of pihyst's
    ...     warnings.warn("weights not determined", IllConditionedWarning)
    """


class IllConditionedWarning(PihystWarning):
    """The least-squares problem is ill-conditioned: some weights are not determined by
    the data. The solution returned is still the best admissible one (with a tiny
    regularization that picks the smallest such weights), but those weights mean little.

    Examples
    --------
    >>> issubclass(IllConditionedWarning, PihystWarning)
    True
    """


class InsufficientDataWarning(PihystWarning):
    """The record supports the fitted model only weakly: it shows no hysteresis, or the
    model explains the displacement poorly. The model is still the best fit of the data."""


class InvalidArgumentError(ValueError, TypeError):
    """An argument of a pihyst function has the wrong type or an invalid value; the
    message names the argument. Both a ``ValueError`` and a ``TypeError``."""


class ResourceLimitError(InvalidArgumentError):
    """The arguments ask for more than pihyst will allocate (e.g. a signal of billions of
    samples); checked before anything is allocated. The message says the limit."""


class FitError(ValueError):
    """The data cannot be fitted as asked; the message says why.

    ``index`` is the 0-based sample the problem is at, and ``column`` is ``"input"`` or
    ``"output"``, when they are known (the command line turns them into file:line:column).

    Parameters
    ----------
    message : str
        What is wrong.
    index : int, optional
        The 0-based sample the problem is at.
    column : str, optional
        ``"input"`` or ``"output"``.

    Examples
    --------
    >>> err = FitError("the output does not vary", column="output")
    >>> str(err), err.column, isinstance(err, ValueError)
    ('the output does not vary', 'output', True)
    """

    def __init__(self, message: str, *, index: int | None = None,
                 column: str | None = None) -> None:
        super().__init__(message)
        self.index = index
        self.column = column


class InfeasibleConstraintsError(FitError):
    """No weights satisfy the constraints (bounds and equality constraints together).

    Parameters
    ----------
    message : str
        What is wrong.
    index : int, optional
        The 0-based sample the problem is at.
    column : str, optional
        ``"input"`` or ``"output"``.

    Examples
    --------
    >>> isinstance(InfeasibleConstraintsError("no weights satisfy them"), FitError)
    True
    """


class InvalidModelError(ValueError):
    """The parameters do not describe a valid model; the message says which and why.

    Examples
    --------
    >>> import pihyst
    >>> try:
    ...     pihyst.ClassicalPI([0, 10], [1.0])
    ... except InvalidModelError as err:
    ...     print(err)
    2 thresholds but 1 weights
    """


class InputRangeError(ValueError):
    """An input sample lies outside the model's input range.

    Parameters
    ----------
    index : int
        The 0-based sample.
    value : float
        Its value.
    input_range : (float, float)
        The model's input range.

    Examples
    --------
    >>> str(InputRangeError(3, 151.0, (0.0, 150.0)))
    "sample 3: input 151 is outside the model's input range [0, 150]"
    """

    def __init__(self, index: int, value: float, input_range: tuple[float, float]) -> None:
        self.index = index
        self.value = value
        super().__init__(f"sample {index}: input {value:g} is outside the model's input range "
                         f"[{input_range[0]:g}, {input_range[1]:g}]")


class RecordError(ValueError):
    """A record could not be used: ``FILE: where: what is wrong`` (``where`` names the
    variable and sample of an array file).

    Parameters
    ----------
    path : str or os.PathLike
        The record's file.
    message : str
        Where and what is wrong.

    Examples
    --------
    >>> str(RecordError("loop.mat", "variable 'u': sample 4 is NaN"))
    "loop.mat: variable 'u': sample 4 is NaN"
    """

    def __init__(self, path: "str | os.PathLike[str]", message: str) -> None:
        self.path, self.message = path, message
        super().__init__(f"{path}: {message}")


class CSVError(RecordError):
    """A CSV file could not be used; the message names file, line and column.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    line : int
        The 1-based line (0: the file as a whole, e.g. it cannot be opened).
    column : int or None
        The 1-based column (None: the whole line).
    message : str
        What is wrong.

    Examples
    --------
    >>> str(CSVError("loop.csv", 7, 2, "'abc' is not a number"))
    "loop.csv:7:2: 'abc' is not a number"
    >>> str(CSVError("gone.csv", 0, None, "cannot read file: No such file or directory"))
    'gone.csv: cannot read file: No such file or directory'
    """

    def __init__(self, path: "str | os.PathLike[str]", line: int, column: int | None,
                 message: str) -> None:
        self.line, self.column = line, column
        where = (f"{path}:{line}:{column}" if line and column else
                 f"{path}:{line}" if line else f"{path}")
        ValueError.__init__(self, f"{where}: {message}")
        self.path, self.message = path, message
