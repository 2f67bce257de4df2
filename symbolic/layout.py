"""Named layouts of vectors: one description per vector.

Every vector that crosses a boundary (a state, an input, an output, a
parameter vector, a function's arguments) is described once, as a
:class:`Layout` of named :class:`Field` blocks with sizes, units and docs.
Everything that needs the vector's shape is derived from that description:

* slices and named blocks in Python (:meth:`Layout.slice`,
  :meth:`Layout.unpack`, :meth:`Layout.pack`), symbolic or numeric;
* the scalar entries' names and units (:meth:`Layout.element_names`,
  :meth:`Layout.element_units`): CSV columns and their sidecar;
* C structs, their offsets and the ``ctypes`` mirrors (``quadland_symbolic.codegen``
  and ``quadland.engine.flightcode`` read the same fields).

A field may nest another layout (its size is the nested layout's), hold a
matrix (``shape``, column-major as CasADi stores it) or, in C structs only,
an ``int`` (``ctype="int"``).
"""

from __future__ import annotations

import dataclasses
import functools

import casadi as ca
import numpy as np

__all__ = ["Field", "Layout"]


@dataclasses.dataclass(frozen=True)
class Field:
    """One named block of a vector.

    Attributes
    ----------
    name : str
        Identifier (a valid C and Python name).
    size : int
        Number of scalar entries.
    unit : str or tuple of str
        Unit of every entry, or one unit per entry.
    doc : str
        One line saying what the block is.
    shape : tuple of int, optional
        ``(rows, cols)`` when the block is a matrix, stored column-major.
    elements : tuple of str, optional
        Names of the scalar entries (default ``name`` for a scalar and
        ``name_1 .. name_n`` otherwise).
    layout : Layout, optional
        A nested layout; ``size`` is then its size.
    ctype : str
        ``"real"`` (every numeric vector) or ``"int"`` (C struct members
        that are counts or flags; such fields are not part of a real vector).
    """

    name: str
    size: int
    unit: str | tuple[str, ...]
    doc: str
    shape: tuple[int, int] | None = None
    elements: tuple[str, ...] | None = None
    layout: Layout | None = None
    ctype: str = "real"

    def __post_init__(self):
        if not self.name.isidentifier():
            raise ValueError(f"field name {self.name!r} is not an identifier")
        if self.layout is not None and self.size != self.layout.size:
            raise ValueError(f"{self.name}: size {self.size} != nested layout's "
                             f"{self.layout.size}")
        if self.shape is not None and self.shape[0] * self.shape[1] != self.size:
            raise ValueError(f"{self.name}: shape {self.shape} does not hold {self.size}")
        if self.elements is not None and len(self.elements) != self.size:
            raise ValueError(f"{self.name}: {len(self.elements)} element names for "
                             f"{self.size} entries")
        if isinstance(self.unit, tuple) and len(self.unit) != self.size:
            raise ValueError(f"{self.name}: {len(self.unit)} units for {self.size} entries")
        if self.ctype not in ("real", "int"):
            raise ValueError(f"{self.name}: ctype must be 'real' or 'int'")

    @classmethod
    def nested(cls, name: str, layout: Layout, doc: str) -> Field:
        """A field that holds a whole other layout."""
        return cls(name, layout.size, "", doc, layout=layout)

    def element_names(self) -> tuple[str, ...]:
        """Names of the scalar entries."""
        if self.layout is not None:
            return self.layout.element_names()
        if self.elements is not None:
            return self.elements
        if self.size == 1:
            return (self.name,)
        if self.shape is not None:
            rows, cols = self.shape
            return tuple(f"{self.name}_{i + 1}_{j + 1}" for j in range(cols) for i in range(rows))
        return tuple(f"{self.name}_{i + 1}" for i in range(self.size))

    def element_units(self) -> tuple[str, ...]:
        """Unit of each scalar entry."""
        if self.layout is not None:
            return self.layout.element_units()
        if isinstance(self.unit, tuple):
            return self.unit
        return (self.unit,) * self.size


@dataclasses.dataclass(frozen=True)
class Layout:
    """Ordered fields of one vector.

    Examples
    --------
    >>> lay = Layout("xq", (Field("z1", 1, "m", "altitude"),
    ...                     Field("eta1", 3, "rad", "attitude",
    ...                           elements=("phi1", "theta1", "psi1"))))
    >>> lay.size, lay.slice("eta1")
    (4, slice(1, 4, None))
    >>> lay.element_names()
    ('z1', 'phi1', 'theta1', 'psi1')
    >>> lay.unpack(np.arange(4.0))["eta1"]
    array([1., 2., 3.])
    """

    name: str
    fields: tuple[Field, ...]
    doc: str = ""

    def __post_init__(self):
        names = [f.name for f in self.fields]
        if len(set(names)) != len(names):
            raise ValueError(f"{self.name}: duplicate field names in {names}")

    @functools.cached_property
    def size(self) -> int:
        """Total number of real scalar entries (``int`` fields excluded)."""
        return sum(f.size for f in self.fields if f.ctype == "real")

    @functools.cached_property
    def _offsets(self) -> dict[str, tuple[int, int]]:
        out, start = {}, 0
        for f in self.fields:
            if f.ctype != "real":
                continue
            out[f.name] = (start, start + f.size)
            start += f.size
        return out

    def offsets(self) -> dict[str, tuple[int, int]]:
        """Map each real field's name to its ``(start, stop)``."""
        return dict(self._offsets)

    def __getitem__(self, name: str) -> Field:
        for f in self.fields:
            if f.name == name:
                return f
        raise KeyError(f"{self.name} has no field {name!r}")

    def __contains__(self, name: str) -> bool:
        return any(f.name == name for f in self.fields)

    def names(self) -> tuple[str, ...]:
        """Field names in order."""
        return tuple(f.name for f in self.fields)

    def slice(self, name: str) -> slice:
        """Slice of field ``name``; a dotted name reaches into nested layouts."""
        head, _, rest = name.partition(".")
        if head not in self._offsets:
            raise KeyError(f"{self.name} has no real field {head!r}")
        a, b = self._offsets[head]
        if not rest:
            return slice(a, b)
        inner = self[head].layout
        if inner is None:
            raise KeyError(f"{self.name}.{head} is not a nested layout")
        s = inner.slice(rest)
        return slice(a + s.start, a + s.stop)

    def index(self, element: str) -> int:
        """Position of the scalar entry named ``element``."""
        try:
            return self.element_names().index(element)
        except ValueError:
            raise KeyError(f"{self.name} has no entry {element!r}") from None

    def element_names(self) -> tuple[str, ...]:
        """Names of every real scalar entry, in order."""
        return tuple(n for f in self.fields if f.ctype == "real" for n in f.element_names())

    def element_units(self) -> tuple[str, ...]:
        """Unit of every real scalar entry, in order."""
        return tuple(u for f in self.fields if f.ctype == "real" for u in f.element_units())

    def element_docs(self) -> tuple[str, ...]:
        """What each real scalar entry is: its field's doc (nested: the innermost)."""
        out = []
        for f in self.fields:
            if f.ctype != "real":
                continue
            out.extend(f.layout.element_docs() if f.layout is not None else (f.doc,) * f.size)
        return tuple(out)

    def sym(self, name: str | None = None) -> ca.SX:
        """A fresh symbolic column vector of the layout's length."""
        return ca.SX.sym(name or self.name, self.size)

    def syms(self) -> list[ca.SX]:
        """One fresh symbol per field, shaped as the field (a signature's arguments)."""
        return [ca.SX.sym(f.name, *(f.shape or (f.size, 1))) for f in self.fields]

    def unpack(self, v) -> dict:
        """Split a symbolic or numeric vector into named blocks.

        Matrix blocks are reshaped column-major to their ``shape``; a
        trailing axis of a NumPy array (samples) is kept.
        """
        n = v.shape[0]
        if n != self.size:
            raise ValueError(f"{self.name}: expected {self.size} entries, got {n}")
        symbolic = isinstance(v, ca.SX | ca.MX | ca.DM)
        out = {}
        for f in self.fields:
            if f.ctype != "real":
                continue
            a, b = self._offsets[f.name]
            block = v[a:b]
            if f.shape is not None:
                if symbolic:
                    block = ca.reshape(block, *f.shape)
                else:
                    block = np.reshape(block, f.shape + block.shape[1:], order="F")
            out[f.name] = block
        return out

    def pack(self, values: dict) -> np.ndarray:
        """Assemble a numeric vector from a dict of named blocks."""
        missing = [f.name for f in self.fields if f.ctype == "real" and f.name not in values]
        if missing:
            raise KeyError(f"{self.name}: missing {missing}")
        chunks = []
        for f in self.fields:
            if f.ctype != "real":
                continue
            v = values[f.name]
            if f.layout is not None and isinstance(v, dict):
                v = f.layout.pack(v)
            flat = np.asarray(v, dtype=float).reshape(-1, order="F")   # column-major
            if flat.size != f.size:
                raise ValueError(f"{self.name}.{f.name}: expected {f.size} values, "
                                 f"got {flat.size}")
            chunks.append(flat)
        return np.concatenate(chunks) if chunks else np.zeros(0)

    def zeros(self) -> np.ndarray:
        """A numeric vector of zeros of the layout's length."""
        return np.zeros(self.size)
