"""The summary of a fleet as files: JSON (everything) and CSV (one row per record)."""

import csv
import io
import json
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from pihyst._atomic import write_atomically
from pihyst.io._csv import write_sidecar

if TYPE_CHECKING:
    from pihyst.fleet._fit_many import FleetResult

__all__ = ["SUMMARY_COLUMNS", "summary_csv", "summary_json"]

#: Columns of the CSV summary, in order.
SUMMARY_COLUMNS = ("record", "status", "error", "family", "n_operators", "held_back_rms_um",
                   "fit_time_s", "model_file")


def _rows(result, model_files):
    for o in result:
        row = o.summary()
        yield {"record": row["record"], "status": row["status"], "error": row["error"],
               "family": row["family"], "n_operators": row["n_operators"],
               "held_back_rms_um": row["held_back_rms"], "fit_time_s": row["seconds"],
               "model_file": model_files.get(o.record), "warnings": row["warnings"]}


def summary_json(result: "FleetResult", path: "str | os.PathLike[str]", *,
                 model_files: Mapping[str, str] | None = None, **extra: Any) -> None:
    """Write the fleet's summary as JSON: ``extra`` keys, the counts, then one object per
    record (the CSV's columns and the warnings).

    Parameters
    ----------
    result : FleetResult
        What :func:`pihyst.fit_many` returned.
    path : str or os.PathLike
        The file to write (it appears only once complete).
    model_files : dict, optional
        Record name -> the model file written for it.
    **extra
        Keys written first (e.g. the command and its options).

    Raises
    ------
    OSError
        If the file cannot be written.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from pihyst.fleet import FleetResult, RecordOutcome
    >>> result = FleetResult((RecordOutcome("a.csv", "failed", error="unreadable"),))
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> summary_json(result, folder / "summary.json", command="fit-many")
    >>> import json; json.loads((folder / "summary.json").read_text())["failed"]
    1
    """
    rows = list(_rows(result, model_files or {}))
    data = {**extra, "records": len(rows), "fitted": len(result.fitted),
            "failed": len(result.failed), "scheduler": result.scheduler,
            "wall_time_s": result.seconds, "rows": rows}
    write_atomically(path, json.dumps(data, indent=2) + "\n")


def summary_csv(result: "FleetResult", path: "str | os.PathLike[str]", *,
                model_files: Mapping[str, str] | None = None,
                comments: Sequence[str] = ()) -> None:
    """Write the fleet's summary as plain CSV (:data:`SUMMARY_COLUMNS`; ``comments`` in
    its sidecar ``PATH.json``); numbers with 17 significant digits, empty fields where a
    value does not apply.

    Parameters
    ----------
    result : FleetResult
        What :func:`pihyst.fit_many` returned.
    path : str or os.PathLike
        The file to write (it appears only once complete).
    model_files : dict, optional
        Record name -> the model file written for it.
    comments : sequence of str
        Lines for the sidecar's comments.

    Raises
    ------
    OSError
        If the file cannot be written.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from pihyst.fleet import FleetResult, RecordOutcome
    >>> result = FleetResult((RecordOutcome("a.csv", "failed", error="unreadable"),))
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> summary_csv(result, folder / "summary.csv")
    >>> (folder / "summary.csv").read_text().splitlines()[1]
    'a.csv,failed,unreadable,,,,0,'
    """
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(SUMMARY_COLUMNS)
    for row in _rows(result, model_files or {}):
        writer.writerow([_field(row[c]) for c in SUMMARY_COLUMNS])
    write_atomically(path, out.getvalue())
    write_sidecar(path, SUMMARY_COLUMNS, len(result), list(comments))


def _field(value):
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.17g}"
    return str(value)
