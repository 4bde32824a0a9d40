"""Errors and warnings of pihyst's identification (``pihyst.fit``).

Model construction errors live in :mod:`pihyst.model` (``InvalidModelError``,
``InputRangeError``); this module holds what fitting adds.
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
