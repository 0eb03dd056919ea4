"""Table exports of the results: columns as arrays, pandas data frames, MATLAB files.

Every result that has CSV rows (``rows()``) exports them as a table of columns
(:func:`columns_of`): a number column becomes a float array (a blank cell NaN),
any other a text array.  :func:`to_pandas` turns a table into a
:class:`pandas.DataFrame` when pandas is installed (it is optional), and
:func:`mat_variables` into variables :func:`scipy.io.savemat` writes (names
made valid MATLAB identifiers).

The time series of one move (:meth:`harness.results.ScenarioResult.to_table`)
use the column names of ``<scenario>-signals.csv``: :data:`SIGNAL_COLUMNS`.

>>> cols = columns_of([{"profile": "AL", "residual_m": 1e-3}, {"profile": "JL",
...                     "residual_m": ""}])
>>> cols["profile"].tolist(), cols["residual_m"].tolist()
(['AL', 'JL'], [0.001, nan])
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["SIGNAL_COLUMNS", "TableMixin", "columns_of", "mat_name", "mat_variables",
           "rows_of", "to_pandas"]

SIGNAL_COLUMNS: tuple[tuple[str, str], ...] = (
    ("x", "x_m"), ("v", "v_m_s"), ("a", "a_m_s2"), ("j", "j_m_s3"), ("eps", "eps_m"),
    ("z", "z_m"), ("f", "f_Hz"))
"""(attribute of :class:`~harness.simulation.master.CoSimResult`, column suffix) of one
profile's time series: reference x/v/a/j of the excited axis, deflection ε of the load,
Z position and frequency of the tuned mode (``f`` is the tuned mode's row)."""


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def columns_of(rows: Sequence[Mapping[str, Any]]) -> dict[str, np.ndarray]:
    """Turn CSV rows into columns.

    Parameters
    ----------
    rows : sequence of mapping
        The rows, e.g. ``result.rows()``; the columns are the keys of the first row.

    Returns
    -------
    dict of str to ndarray
        A column of numbers (blank cells allowed: NaN) as float64, one of booleans as
        bool, any other as an object array of str.
    """
    if not rows:
        return {}
    out: dict[str, np.ndarray] = {}
    for k in rows[0]:
        vals = [r.get(k, "") for r in rows]
        if all(isinstance(v, (bool, np.bool_)) for v in vals):
            out[k] = np.array(vals, dtype=bool)
        elif all(_is_number(v) or v == "" or v is None for v in vals) and any(
                _is_number(v) for v in vals):
            out[k] = np.array([math.nan if v == "" or v is None else float(v) for v in vals])
        else:
            out[k] = np.array(["" if v is None else str(v) for v in vals], dtype=object)
    return out


def rows_of(columns: Mapping[str, np.ndarray]) -> list[dict[str, Any]]:
    """Turn columns of equal length back into rows (for :func:`harness.files.write_csv`)."""
    names = list(columns)
    if not names:
        return []
    data = [np.asarray(columns[k]) for k in names]
    n = len(data[0])
    if any(len(d) != n for d in data):
        raise ValueError("columns of different lengths")
    lists = [d.tolist() for d in data]
    return [dict(zip(names, vals, strict=True)) for vals in zip(*lists, strict=True)]


def to_pandas(columns: Mapping[str, np.ndarray]) -> Any:
    """Return the columns as a :class:`pandas.DataFrame`.

    Raises
    ------
    ImportError
        When pandas is not installed (it is optional: ``pip install pandas``).
    """
    try:
        import pandas as pd  # deferred: optional, and heavy to import
    except ImportError:
        raise ImportError("to_pandas() needs pandas, which is optional: pip install pandas "
                          "(to_table() gives the same columns as numpy arrays)") from None
    return pd.DataFrame({k: np.asarray(v) for k, v in columns.items()})


def mat_name(name: str) -> str:
    """Return a valid MATLAB variable or field name for a column name.

    ``DJL-optimal_x_m`` -> ``DJL_optimal_x_m``; a name not starting with a letter gets
    an ``x`` before it.
    """
    s = re.sub(r"\W", "_", name)
    return s if re.match(r"[A-Za-z]", s) else "x" + s


def mat_variables(columns: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """Columns as a MATLAB struct's fields: valid names, text as cell arrays.

    Raises
    ------
    ValueError
        If two column names map to the same MATLAB name.
    """
    out: dict[str, Any] = {}
    for k, v in columns.items():
        m = mat_name(k)
        if m in out:
            raise ValueError(f"columns {k!r} and another both become {m!r} in MATLAB")
        a = np.asarray(v)
        out[m] = a.astype(object) if a.dtype.kind in "OUS" else a
    return out


class TableMixin:
    """``to_table()`` and ``to_pandas()`` for a result with CSV rows (``rows()``)."""

    def rows(self) -> list[dict[str, Any]]:  # pragma: no cover - provided by the result
        """Return the CSV rows (each result defines them)."""
        raise NotImplementedError

    def to_table(self) -> dict[str, np.ndarray]:
        """Return the CSV's columns as arrays (numbers float, text str); see :func:`columns_of`."""
        return columns_of(self.rows())

    def to_pandas(self) -> Any:
        """Return the CSV's table as a :class:`pandas.DataFrame` (pandas is optional).

        Raises
        ------
        ImportError
            When pandas is not installed.
        """
        return to_pandas(self.to_table())
