"""What a simulation gives: every signal by name, the states, the CSV's layout."""

from __future__ import annotations

import csv
import dataclasses
import io
from collections.abc import Iterable, Mapping
from types import MappingProxyType
from typing import Any, NoReturn

import numpy as np

from quadland.output import write_text_atomic
from quadland_symbolic.layout import Layout

__all__ = ["SimulationResult", "columns_sidecar"]


@dataclasses.dataclass(frozen=True)
class SimulationResult(dict):
    """The outputs of one simulation, each a NumPy array by name.

    ``result["t"]``, ``result["z_e"]``, ...; ``states`` is the loop's state at
    each row, ``(len(t), nx)``, its columns named by :attr:`state_labels`.
    ``layout`` names the columns of ``trajectory.csv`` (the loop kind's: the
    paper's loop writes all its signals, a landing a selection of the many it
    records). Every array is read-only, and so is the mapping: a result is a
    record of a run.

    A result is a read-only ``dict`` of its signals (a subclass: ``dict``'s
    methods that would change it raise ``TypeError``), so that what takes a
    ``dict`` of columns takes it as one: ``pd.DataFrame(result)`` is a
    ``pandas.DataFrame`` with one column per signal (every one of
    ``list(result)``, in that order; copies, so the frame is writable), and
    ``pd.DataFrame(result, columns=[...])`` picks some. :meth:`to_pandas`
    gives ``trajectory.csv``'s columns with their units in ``attrs``.
    """

    scenario: Any
    columns: Mapping[str, np.ndarray]
    states: np.ndarray
    layout: Layout
    state_layout: Layout | None = None

    def __post_init__(self):
        for array in (*self.columns.values(), self.states):
            if isinstance(array, np.ndarray):
                array.flags.writeable = False
        object.__setattr__(self, "columns", MappingProxyType(dict(self.columns)))
        dict.update(self, self.columns)

    def _read_only(self, *args, **kwargs) -> NoReturn:
        raise TypeError("a SimulationResult is read-only (a record of a run): "
                        "dict(result) or result.to_pandas() gives a copy to change")

    __setitem__ = __delitem__ = __ior__ = _read_only
    clear = pop = popitem = setdefault = update = _read_only

    def __reduce__(self):
        """Pickled by its fields (``dict``'s own way would set its items one by one)."""
        return (type(self), (self.scenario, dict(self.columns), self.states, self.layout,
                             self.state_layout))

    def __repr__(self) -> str:
        """One line: the scenario, the rows and their time span, the columns and states
        (a notebook shows this, not every array)."""
        t = self.columns.get("t")
        span = "" if t is None or not len(t) else f" over {float(t[0]):g}..{float(t[-1]):g} s"
        return (f"<SimulationResult of {getattr(self.scenario, 'name', '?')!r}: "
                f"{self.states.shape[0]} rows{span}, {len(self.columns)} columns "
                f"(list(result)), {self.states.shape[1]} states; .to_pandas()>")

    def to_csv(self, path=None) -> str:
        """The trajectory as CSV text with a header of plain names; written to ``path`` if given.

        Units are in :func:`columns_sidecar` (``columns.json``) and ``docs/simulation.md``.
        """
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        names = self.layout.element_names()
        writer.writerow(names)
        data = np.column_stack([self.columns[n] for n in names])
        for row in data:
            writer.writerow([f"{v:.12g}" for v in row])
        text = buf.getvalue()
        if path is not None:
            write_text_atomic(path, text)
        return text

    @property
    def state_labels(self) -> tuple[str, ...]:
        """The name of each column of :attr:`states` (the loop's state layout's)."""
        if self.state_layout is None:
            return tuple(f"x[{i}]" for i in range(self.states.shape[1]))
        return tuple(self.state_layout.element_names())

    def to_pandas(self, columns: Iterable[str] | None = None):
        """The trajectory as a ``pandas.DataFrame``, one column per signal.

        Parameters
        ----------
        columns : iterable of str, optional
            Which signals, in order; by default those of ``trajectory.csv``
            (:attr:`layout`). ``list(result)`` names all of them (and
            ``pd.DataFrame(result)`` gives all of them).

        Returns
        -------
        pandas.DataFrame
            Copies of the arrays (writable); ``attrs["units"]`` maps each
            column of the layout to its unit, ``attrs["scenario"]`` is the
            scenario's name.

        Raises
        ------
        ImportError
            Without pandas (``pip install 'quadland[pandas]'``).
        KeyError
            For a name the result does not have.
        """
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("SimulationResult.to_pandas needs pandas "
                              "(pip install 'quadland[pandas]')") from None
        names = list(self.layout.element_names() if columns is None else columns)
        missing = [n for n in names if n not in self.columns]
        if missing:
            raise KeyError(f"no signal {missing[0]!r} in this result (list(result) names them)")
        frame = pd.DataFrame({n: np.array(self.columns[n]) for n in names})
        frame.attrs["units"] = dict(zip(self.layout.element_names(),
                                        self.layout.element_units(), strict=True))
        frame.attrs["scenario"] = getattr(self.scenario, "name", None)
        return frame

    def truncated(self, n: int) -> SimulationResult:
        """The first ``n`` rows."""
        return SimulationResult(self.scenario, {k: v[:n] for k, v in self.columns.items()},
                                self.states[:n], self.layout, self.state_layout)


def columns_sidecar(layout: Layout) -> dict:
    """``columns.json``: each CSV column's unit and meaning, in column order.

    ``layout`` is the result's (``SimulationResult.layout``).
    """
    return {"columns": [dict(name=n, unit=u, doc=d) for n, u, d in
                        zip(layout.element_names(), layout.element_units(),
                            layout.element_docs(), strict=True)]}
