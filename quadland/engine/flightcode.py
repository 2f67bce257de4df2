"""Generated flight C loaded with ``ctypes``: the tools every loop kind's flight code uses.

The C a loop kind flies or exposes (its ``flight`` module in
:mod:`quadland.kinds`) is generated from ``quadland_symbolic``, compiled into the
disk cache by :func:`quadland.engine.build.build_library` and loaded with
``ctypes``; the source tree's ``generated/`` is never read, so an installed
quadland works the same as a checkout. This module holds what the kinds
share: ``ctypes`` mirrors of the C structs from the same layouts as the C
(:func:`ctypes_struct`), the library spelled ``ql_`` in either precision
(:class:`Library`), and the real type of a precision (:func:`real_type`).
"""

from __future__ import annotations

import ctypes
import functools
import re

from quadland_symbolic.layout import Layout

__all__ = ["ctypes_struct", "Library", "real_type", "pointer_array", "label"]


def real_type(precision: str):
    """``ctypes.c_double`` for ``"double"``, ``ctypes.c_float`` for ``"float"``."""
    return ctypes.c_double if precision == "double" else ctypes.c_float


@functools.cache
def ctypes_struct(layout: Layout, real) -> type:
    """The ``ctypes.Structure`` of a layout, as ``quadland_symbolic.codegen`` declares it in C.

    Real fields in order (a matrix ``shape = (rows, cols)`` as
    ``real[cols][rows]``), nested layouts as nested structures, ``int``
    fields as ``c_int``.

    Parameters
    ----------
    layout : Layout
        The struct's layout (``quadland_symbolic.codegen.structs``).
    real : type
        ``ctypes.c_double`` or ``ctypes.c_float``.
    """
    fields = []
    for f in layout.fields:
        if f.ctype == "int":
            fields.append((f.name, ctypes.c_int))
        elif f.layout is not None:
            fields.append((f.name, ctypes_struct(f.layout, real)))
        elif f.shape is not None:
            fields.append((f.name, (real * f.shape[0]) * f.shape[1]))
        else:
            fields.append((f.name, real if f.size == 1 else real * f.size))
    return type(layout.name, (ctypes.Structure,), {"_fields_": fields})


def pointer_array(arrays, ctype):
    """A C array of pointers to the NumPy ``arrays``' data."""
    return (ctypes.POINTER(ctype) * len(arrays))(
        *[a.ctypes.data_as(ctypes.POINTER(ctype)) for a in arrays])


class Library:
    """A build's library, its API spelled ``ql_`` whatever the build's prefix.

    ``lib.ql_control_step`` is ``qlf_control_step`` in the float build;
    every other name is looked up as it is.
    """

    def __init__(self, cdll: ctypes.CDLL, prefix: str):
        self._cdll, self.prefix = cdll, prefix

    def __getattr__(self, name: str):
        if name.startswith("ql_"):
            name = self.prefix + name[3:]
        return getattr(self._cdll, name)


#: Characters the scenario label keeps in generated C (comments, a string literal).
C_UNSAFE = re.compile(r"[^A-Za-z0-9_.,:=+\-\[\] ]")

def label(sc) -> str:
    """The scenario's name and overrides; it goes into C comments and a string
    literal: only safe characters."""
    return C_UNSAFE.sub("?", sc.name + "".join(f" --set {o}" for o in sc.overrides))


