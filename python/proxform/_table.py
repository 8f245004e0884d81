"""A table of named numpy columns (column-major, no copies), with pandas on request."""

from __future__ import annotations

from typing import Any, ItemsView, Iterator, KeysView, Mapping, ValuesView

import numpy as np


class Table:
    """Named columns of equal length: ``table["x_m"]`` is a numpy array. As in pandas,
    ``len(table)`` is the number of rows and iterating gives the column names;
    ``table.columns`` the names; ``table.to_pandas()`` a DataFrame (pandas
    installed); ``table.to_numpy()`` a 2-D float array of the numeric columns."""

    def __init__(self, columns: Mapping[str, Any]):
        self._columns = {k: np.asarray(v) for k, v in columns.items()}

    def __getitem__(self, name: str) -> np.ndarray:
        return self._columns[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._columns)

    def __len__(self) -> int:
        first = next(iter(self._columns.values()), None)
        return 0 if first is None else len(first)

    def __contains__(self, name: object) -> bool:
        return name in self._columns

    def keys(self) -> KeysView[str]:
        """The column names."""
        return self._columns.keys()

    def values(self) -> ValuesView[np.ndarray]:
        """The columns."""
        return self._columns.values()

    def items(self) -> ItemsView[str, np.ndarray]:
        """(name, column) pairs."""
        return self._columns.items()

    @property
    def columns(self) -> list[str]:
        """The column names, in order."""
        return list(self._columns)

    def to_pandas(self) -> Any:
        """The table as a pandas DataFrame (requires pandas)."""
        import pandas as pd

        return pd.DataFrame(self._columns)

    def to_numpy(self) -> np.ndarray:
        """The numeric columns as one (rows, columns) float64 array."""
        cols = [c for c in self._columns.values() if c.dtype.kind in "biuf"]
        return np.column_stack([c.astype(np.float64) for c in cols]) if cols else np.empty((len(self), 0))

    def __repr__(self) -> str:
        return f"Table({len(self)} rows × {len(self._columns)} columns: {', '.join(self._columns)})"
