"""Files in and out: model files (JSON) and records, plus readers for the measured data
sets kept beside the repository (:mod:`pihyst.io.datasets`).

Records (docs/records.md): :func:`read_record` reads delimited text (any separator,
header or not, decimal comma), NumPy, MATLAB, HDF5 and Parquet files, or what a Python
function returns, with the columns, units, lag and start the user names;
:func:`open_record` reads them block by block. Formats: docs/interfaces.md. Every
writer leaves no partial file on error; every reader reports a bad file as one line
naming the file, line and column.
"""

from pihyst.exceptions import CSVError, RecordError
from pihyst.io._csv import ColumnWriter, column_number, read_columns, write_columns
from pihyst.io._model_files import load_model, read_model_dict, save_model
from pihyst.io._records import Record, RecordReader, open_record, read_record
from pihyst.io._validation import Validation, validate_model

__all__ = ["CSVError", "ColumnWriter", "Record", "RecordError", "RecordReader",
           "column_number", "load_model", "open_record", "read_columns", "read_model_dict",
           "read_record",
           "save_model", "validate_model", "Validation", "write_columns"]
