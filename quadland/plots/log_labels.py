"""A log axis's tick labels as plain text: ``10⁻²`` instead of mathtext's ``10^{-2}``.

matplotlib labels a log axis with mathtext (``$\\mathdefault{10^{-2}}$``): every
distinct label is parsed by its pyparsing grammar, about 3 ms each and the
grammar built once per process, and laid out glyph by glyph. The same labels as
plain text, the exponent in Unicode superscripts (which the default font,
DejaVu Sans, has), read the same and cost what any text costs.
:class:`PlainLogFormatter` formats as matplotlib's ``LogFormatterSciNotation``
and rewrites what it returns; a label it cannot write plainly (an exponent with
a decimal point, say) is left as mathtext.
"""

from __future__ import annotations

import re

from matplotlib.ticker import LogFormatterSciNotation

__all__ = ["PlainLogFormatter", "plain_log_labels", "plain_math"]

_SUPERSCRIPT = str.maketrans("-\u22120123456789",
                             "\u207b\u207b\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077"
                             "\u2078\u2079")
_MATH = re.compile(r"\$\\mathdefault\{(.*)\}\$")
_PLAIN = re.compile(r"(?P<head>[^\\^{}$]*?)(?:\\times\s*)?(?P<base>[0-9.]+)"
                    r"\^\{(?P<exp>[-\u2212]?[0-9]+)\}")


def plain_math(label: str) -> str:
    """``label`` without mathtext if it is a power of matplotlib's log formatters.

    Parameters
    ----------
    label : str
        A label of ``LogFormatterSciNotation``: ``$\\mathdefault{10^{-2}}$``,
        ``$\\mathdefault{-10^{3}}$``, ``$\\mathdefault{2\\times10^{-1}}$``, or
        anything else.

    Returns
    -------
    str
        ``10⁻²``, ``−10³`` (a minus sign), ``2×10⁻¹``; any other label as it was.
    """
    inner = _MATH.fullmatch(label)
    if inner is None:
        return label
    power = _PLAIN.fullmatch(inner.group(1))
    if power is None:
        return label
    head = power.group("head").replace("-", "\u2212")      # as mathtext draws it
    times = "\u00d7" if "\\times" in inner.group(1) else ""
    return f"{head}{times}{power.group('base')}{power.group('exp').translate(_SUPERSCRIPT)}"


class PlainLogFormatter(LogFormatterSciNotation):
    """``LogFormatterSciNotation`` whose powers are plain text (:func:`plain_math`)."""

    def __call__(self, x, pos=None):
        return plain_math(super().__call__(x, pos))


def plain_log_labels(ax) -> None:
    """Label the log x axis of ``ax`` with :class:`PlainLogFormatter` (major ticks).

    Axes whose x axis is not logarithmic are left alone.
    """
    if ax.get_xscale() == "log":
        ax.xaxis.set_major_formatter(PlainLogFormatter())
