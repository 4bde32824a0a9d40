"""Errors a command reports as one line with exit status 2."""

from pihyst.io import RecordError
from pihyst.model import InputRangeError, InvalidModelError


class UsageError(ValueError):
    """Bad input detected by a command; the message is shown as is."""


USER_ERRORS = (RecordError, InvalidModelError, InputRangeError, UsageError)
