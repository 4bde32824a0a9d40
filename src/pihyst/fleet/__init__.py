"""Fleets: many records (one per actuator) fitted at once, serially or on a Dask cluster.

:func:`fit_many` fits every record exactly as :func:`pihyst.fit` fits it alone; a record
that cannot be read or fitted is reported in its :class:`RecordOutcome` and never stops
the others. With a ``dask.distributed`` client (``pip install 'pihyst[dask]'``) the
records are fitted in parallel on its cluster; without one, in this process. Dask is
imported only when a client is used. Usage: docs/fleets.md.
"""

from pihyst.fleet._fit_many import (
    INPUT_COLUMN,
    OUTPUT_COLUMN,
    FleetResult,
    RecordOutcome,
    fit_many,
)
from pihyst.fleet._summary import SUMMARY_COLUMNS, summary_csv, summary_json

__all__ = ["INPUT_COLUMN", "OUTPUT_COLUMN", "SUMMARY_COLUMNS", "FleetResult", "RecordOutcome",
           "fit_many", "summary_csv", "summary_json"]
