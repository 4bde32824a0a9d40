"""Fitting a fleet: one record per actuator, each fitted by :func:`pihyst.identify.fit`,
serially in this process or in parallel on a Dask cluster.

Each record is fitted by one call of the same function, :func:`_fit_one`, wherever it
runs; it takes the arrays and the options and returns plain data (the models as their
JSON dicts, the report as its dict), which the client turns back into objects. A model
rebuilt from its dict equals the fitted one bit for bit (the dict holds every parameter
as a Python float), so a fleet's results are those of fitting each record alone.

A record that cannot be read or fitted becomes a failed :class:`RecordOutcome` with its
error message; the other records go on.
"""

import inspect
import os
import time
import traceback
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pihyst.exceptions import CSVError, FitError, InvalidArgumentError
from pihyst.identify import FitReport, FitResult, fit
from pihyst.io import Record, column_number, read_columns
from pihyst.model import PIModel

__all__ = ["FleetResult", "RecordOutcome", "fit_many", "INPUT_COLUMN", "OUTPUT_COLUMN"]

INPUT_COLUMN = "voltage_V"
OUTPUT_COLUMN = "displacement_um"
TIME_COLUMN = "time_s"
_COLUMN_OF = {"input": INPUT_COLUMN, "output": OUTPUT_COLUMN}
_FIT_PARAMETERS = inspect.signature(fit).parameters
# the keyword options fit() names (None: it takes any keyword, so fit() checks them)
_FIT_OPTIONS = None if any(p.kind is p.VAR_KEYWORD for p in _FIT_PARAMETERS.values()) \
    else frozenset(p for p in _FIT_PARAMETERS if p not in ("u", "y"))


@dataclass(frozen=True)
class RecordOutcome:
    """What became of one record of a fleet.

    Parameters
    ----------
    record : str
        The record's name (the file name for a file).
    status : str
        ``"fitted"`` or ``"failed"``.
    error : str or None
        Why it failed, one line (``FILE:LINE:COLUMN: ...`` when a file line is at fault).
    result : FitResult or None
        What :func:`pihyst.fit` returned for the record (``model``, ``report``,
        ``models``), when fitted.
    warnings : tuple of str
        Warnings the fit issued (e.g. ill-conditioned weights).
    seconds : float
        Time spent reading and fitting the record, where it ran.
    source : str or None
        The file the record was read from.
    traceback : str or None
        The traceback of an unexpected error (not a bad record but a fault), for a bug
        report.

    Examples
    --------
    >>> o = RecordOutcome("a.csv", "failed", error="a.csv:3:2: 'x' is not a number")
    >>> o.ok, o.model
    (False, None)
    """

    record: str
    status: str
    error: str | None = None
    result: FitResult | None = None
    warnings: tuple = ()
    seconds: float = 0.0
    source: str | None = None
    traceback: str | None = None

    @property
    def ok(self):
        return self.status == "fitted"

    @property
    def model(self):
        """The chosen model, or None."""
        return None if self.result is None else self.result.model

    @property
    def family(self):
        """The chosen family's name, or None."""
        return None if self.result is None else self.result.report.chosen

    @property
    def held_back_rms(self):
        """RMS error of the chosen family on the held-back cycles (output units), or None
        when nothing was held back."""
        if self.result is None:
            return None
        held = self.result.report.family(self.family)["errors"]["held_back"]
        return None if held is None else held["rms"]

    def summary(self) -> dict[str, Any]:
        """One row of the fleet's summary, as a dict.

        Returns
        -------
        dict
            ``record``, ``status``, ``error``, ``family``, ``n_operators``,
            ``held_back_rms``, ``seconds`` and ``warnings``.

        Examples
        --------
        >>> RecordOutcome("a.csv", "failed", error="unreadable").summary()["error"]
        'unreadable'
        """
        return {"record": self.record, "status": self.status, "error": self.error,
                "family": self.family,
                "n_operators": None if self.model is None else int(self.model.n_operators),
                "held_back_rms": self.held_back_rms, "seconds": self.seconds,
                "warnings": list(self.warnings)}


@dataclass(frozen=True)
class FleetResult:
    """What :func:`fit_many` returns: one :class:`RecordOutcome` per record, in the
    order given.

    ``result["name"]`` is a record's outcome, ``result.models`` the fitted models by
    record, ``result.failed`` the outcomes that failed, ``result.ok`` whether all were
    fitted, ``result.summary()`` one plain dict per record.

    Parameters
    ----------
    outcomes : tuple of RecordOutcome
        One per record, in the order given.
    seconds : float
        Wall time of the whole fleet (s).
    scheduler : str
        Where it ran: ``"serial"`` or the Dask scheduler's address.

    Examples
    --------
    >>> result = FleetResult((RecordOutcome("a.csv", "failed", error="unreadable"),))
    >>> result.ok, len(result.failed), result["a.csv"].error
    (False, 1, 'unreadable')
    """

    outcomes: tuple
    seconds: float = 0.0
    scheduler: str = "serial"
    _index: dict | None = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "_index", {o.record: o for o in self.outcomes})

    def __len__(self):
        return len(self.outcomes)

    def __iter__(self):
        return iter(self.outcomes)

    def __getitem__(self, record):
        return self._index[record]

    @property
    def ok(self):
        return all(o.ok for o in self.outcomes)

    @property
    def fitted(self):
        return [o for o in self.outcomes if o.ok]

    @property
    def failed(self):
        return [o for o in self.outcomes if not o.ok]

    @property
    def models(self):
        """The chosen model of every fitted record, by record name."""
        return {o.record: o.model for o in self.outcomes if o.ok}

    def summary(self) -> list[dict[str, Any]]:
        """One plain dict per record (:meth:`RecordOutcome.summary`), in order.

        Returns
        -------
        list of dict
            The rows of the fleet's summary.

        Examples
        --------
        >>> FleetResult((RecordOutcome("a.csv", "failed"),)).summary()[0]["status"]
        'failed'
        """
        return [o.summary() for o in self.outcomes]


def fit_many(records: Any, client: Any = None, *,
             progress: "Callable[[RecordOutcome], object] | None" = None,
             **options: Any) -> "FleetResult":
    """Fit every record of a fleet, each exactly as :func:`pihyst.fit` would alone.

    Parameters
    ----------
    records : mapping or sequence
        Name -> record, or a sequence of records (named by their file name, or by
        their position ``"0"``, ``"1"``, ...). A record is a pair ``(u, y)`` of arrays
        (voltage, displacement) or the path of a CSV file with ``voltage_V`` and
        ``displacement_um`` columns (read here, in the client, so the workers need no
        access to the files), a ``ValueError`` (a record the caller could not read:
        a failed outcome with its message), or a :class:`pihyst.io.Record` (``read_record``'s: its
        voltage and displacement are fitted, its time, when it has one, is the fit's
        ``t``; errors name its file's line and column).
    client : dask.distributed.Client, optional
        Where to fit: None (default) fits one record after the other in this process
        (no Dask needed); a client sends one task per record to its cluster.
    progress : callable, optional
        Called with each :class:`RecordOutcome` as it is done (in the order they
        finish).
    **options
        Keyword options of :func:`pihyst.fit` (``family``, ``thresholds``,
        ``holdout``, ...), the same for every record.

    Returns
    -------
    FleetResult
        One :class:`RecordOutcome` per record, in the order given. A record that
        cannot be read or fitted is a failed outcome with its error; it never stops
        the others.

    Raises
    ------
    TypeError
        An option that :func:`pihyst.fit` does not take, or records that are neither a
        mapping nor a sequence.
    ValueError
        Two records with the same name (e.g. files of the same name in two folders).

    Examples
    --------
    >>> import numpy as np, pihyst
    >>> u = np.r_[np.linspace(0, 150, 151), np.linspace(150, 0, 151)[1:]]
    >>> beam = pihyst.ClassicalPI([0, 20, 40], [0.2, 0.1, 0.05])   # an actuator's loop
    >>> y1, y2 = beam.predict(u), 1.05 * beam.predict(u)
    >>> fleet = {"a1": (u, y1), "a2": (u, y2), "bad": (u[:3], u[:3])}
    >>> result = pihyst.fit_many(fleet, family="classical", holdout=None)
    >>> [(o.record, o.status) for o in result]
    [('a1', 'fitted'), ('a2', 'fitted'), ('bad', 'failed')]
    >>> result["a1"].model == pihyst.fit(u, y1, family="classical", holdout=None).model
    True
    """
    unknown = [] if _FIT_OPTIONS is None else sorted(set(options) - _FIT_OPTIONS)
    if unknown:
        raise InvalidArgumentError(f"fit_many() got options that pihyst.fit does not take: "
                                   f"{', '.join(unknown)}")
    named = _named(records)
    start = time.perf_counter()
    outcomes = {}
    jobs = []
    for name, record in named:
        t0 = time.perf_counter()
        try:
            u, y, source, lines, period = _load(record)
        except (CSVError, ValueError, TypeError) as err:
            where = os.fspath(record) if _is_path(record) else None
            outcomes[name] = RecordOutcome(name, "failed", error=str(err), source=where,
                                           seconds=time.perf_counter() - t0)
            _report(progress, outcomes[name])
            continue
        own = options
        if isinstance(record, Record) and record.time is not None and "t" not in options:
            own = {**options, "t": record.time}
        jobs.append((name, u, y, source, lines, period, time.perf_counter() - t0, own))

    if client is None:
        scheduler = "serial"
        for name, u, y, source, lines, period, read_time, own in jobs:
            outcomes[name] = _outcome(_fit_one(u, y, own), name, source, lines,
                                      read_time, period)
            _report(progress, outcomes[name])
    else:
        scheduler = _describe(client)
        _run_on(client, jobs, options, outcomes, progress)
    return FleetResult(tuple(outcomes[name] for name, _ in named),
                       seconds=time.perf_counter() - start, scheduler=scheduler)


def _run_on(client, jobs, options, outcomes, progress):
    from distributed import as_completed

    futures = {}
    for name, u, y, source, lines, period, read_time, own in jobs:
        fut = client.submit(_fit_one, u, y, own, pure=False, key=_key(name))
        futures[fut] = (name, source, lines, read_time, period)
    for fut in as_completed(list(futures)):
        name, source, lines, read_time, period = futures[fut]
        if fut.status == "finished":
            outcome = _outcome(fut.result(), name, source, lines, read_time, period)
        elif fut.status == "cancelled":   # e.g. the client or the cluster went away
            outcome = RecordOutcome(name, "failed", source=source, seconds=read_time,
                                    error="cancelled: the cluster dropped the task")
        else:  # the task itself failed: a worker died, or the record could not be sent
            err = fut.exception()
            outcome = RecordOutcome(name, "failed", source=source, seconds=read_time,
                                    error=f"{type(err).__name__}: {err}",
                                    traceback="".join(traceback.format_exception(err)))
        fut.release()
        outcomes[name] = outcome
        _report(progress, outcome)


def _fit_one(u, y, options):
    """Fit one record; runs where the work is done (a Dask worker, or here).

    Returns plain, picklable data: the models as dicts, the report as a dict, or the
    error (with the sample and column it is at, for a file:line:column message)."""
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            res = fit(u, y, **options)
        except FitError as err:
            return {"status": "failed", "error": str(err), "index": err.index,
                    "column": err.column, "seconds": time.perf_counter() - t0}
        except Exception as err:  # a fault, not a bad record: keep the traceback
            return {"status": "failed", "error": f"{type(err).__name__}: {err}",
                    "traceback": traceback.format_exc(), "seconds": time.perf_counter() - t0}
    return {"status": "fitted", "model": res.model.to_dict(),
            "models": {k: m.to_dict() for k, m in res.models.items()},
            "report": res.report.to_dict(),
            "warnings": [str(w.message) for w in caught],
            "seconds": time.perf_counter() - t0}


def _outcome(out, name, source, lines, read_time, period=None):
    seconds = read_time + out["seconds"]
    if out["status"] == "failed":
        error = out["error"]
        if source is not None and "traceback" not in out:
            error = _located(error, out.get("index"), out.get("column"), source, lines)
        return RecordOutcome(name, "failed", error=error, seconds=seconds, source=source,
                             traceback=out.get("traceback"))
    # a delay holds at the record's sample period (its time column's), as with pihyst fit
    models = {k: _at_period(PIModel.from_dict(d), period) for k, d in out["models"].items()}
    result = FitResult(model=_at_period(PIModel.from_dict(out["model"]), period),
                       report=FitReport(out["report"]), models=models)
    return RecordOutcome(name, "fitted", result=result, warnings=tuple(out["warnings"]),
                         seconds=seconds, source=source)


def _at_period(model, period):
    return model.replace(sample_period=period) if model.delay and period else model


def _located(message, index, column, path, lines):
    """A fit error of a file record as ``FILE:LINE:COLUMN: message`` (as ``pihyst fit``)."""
    if isinstance(lines, Record):       # the record locates its own samples
        quantity = {"input": "voltage", "output": "displacement"}.get(column)
        if index is not None and 0 <= index < len(lines):
            return str(lines.error(index, quantity or "voltage", message))
        return str(lines.error(0, quantity, message)) if quantity else f"{path}: {message}"
    col = column_number(path, _COLUMN_OF[column]) if column in _COLUMN_OF else 0
    if index is not None and 0 <= index < len(lines):
        return str(CSVError(path, int(lines[index]), col, message))
    if col:
        return str(CSVError(path, int(lines[0]), col, message))
    return f"{path}: {message}"


def _is_path(record):
    return isinstance(record, (str, os.PathLike))


def _load(record):
    """(u, y, source, lines, sample period) of one record: a CSV path (read here; the
    period is the median step of its time_s column, None without one) or a (u, y) pair
    (period None)."""
    if isinstance(record, ValueError):      # the client could not read it: why
        raise record
    if isinstance(record, Record):
        if record.voltage is None or record.displacement is None:
            raise InvalidArgumentError(f"{record.source}: a record to fit needs its voltage "
                                       "and its displacement")
        period = record.metadata.get("sample_period_s")
        return record.voltage, record.displacement, record.source or None, record, period
    if _is_path(record):
        path = os.fspath(record)
        columns, lines = read_columns(path, [INPUT_COLUMN, OUTPUT_COLUMN],
                                      optional=(TIME_COLUMN,))
        steps = np.diff(columns.get(TIME_COLUMN, np.empty(0)))
        steps = steps[steps > 0]
        period = float(np.median(steps)) if steps.size else None
        return columns[INPUT_COLUMN], columns[OUTPUT_COLUMN], path, lines, period
    try:
        u, y = record
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"a record is a (u, y) pair of arrays or the path of a CSV "
                                   f"file, not {type(record).__name__}") from None
    try:
        u = np.asarray(u, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidArgumentError("u and y must be arrays of numbers") from None
    return u, y, None, None, None


def _named(records):
    if isinstance(records, dict) or hasattr(records, "keys"):
        named = [(str(k), records[k]) for k in records.keys()]
    elif isinstance(records, (str, os.PathLike)) or not hasattr(records, "__iter__"):
        raise InvalidArgumentError("records must be a mapping name -> record or a sequence of "
                                   f"records, not {type(records).__name__}")
    else:
        named = [(os.path.basename(os.fspath(r)) if _is_path(r) else str(i), r)
                 for i, r in enumerate(records)]
    seen = set()
    for name, _ in named:
        if name in seen:
            raise InvalidArgumentError(f"two records are named {name!r}: names must be "
                                       f"unique")
        seen.add(name)
    return named


def _key(name):
    import uuid

    return f"pihyst-fit-{name}-{uuid.uuid4().hex[:8]}"


def _describe(client):
    try:
        n = len(client.scheduler_info().get("workers", {}))
    except Exception:  # a client that cannot say: name the address only
        n = None
    where = getattr(client.scheduler, "address", None) or "dask"
    return f"{where} ({n} workers)" if n is not None else where


def _report(progress, outcome):
    if progress is not None:
        progress(outcome)
