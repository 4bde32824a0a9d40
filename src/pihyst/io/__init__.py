"""Files in and out: model files (JSON) and records (CSV), plus readers for the measured
data sets kept beside the repository (:mod:`pihyst.io.datasets`).

Formats: docs/interfaces.md. Every writer goes through :func:`pihyst._atomic.write_atomically`
(no partial file on error); every reader reports a bad file as one line naming the file,
line and column.
"""

from pihyst.exceptions import CSVError
from pihyst.io._csv import column_number, read_columns, write_columns
from pihyst.io._model_files import load_model, save_model

__all__ = ["CSVError", "column_number", "load_model", "read_columns", "save_model",
           "write_columns"]
