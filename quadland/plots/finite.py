"""What a figure of a failed flight may draw: finite values of a sane size.

A flight that fails (``quadland.exceptions.SimulationError``) leaves a
partial trajectory whose last rows may hold infinities or values near
``1e308``; matplotlib skips NaN, but axis limits computed from an infinity or
from values whose squares overflow raise (``Axis limits -inf, inf``).
:func:`drawable` hands the figures a view in which those values are NaN.
"""

from __future__ import annotations

import numpy as np

__all__ = ["DRAWABLE_MAX", "drawable"]

#: Largest magnitude a figure draws; a larger value (m, N, rad, ...) is no
#: physical result but a diverged one, and it is left out. Squares and sums of
#: such values stay finite in double precision.
DRAWABLE_MAX = 1e100


class _Drawable:
    """A result whose float columns read with non-finite and huge values as NaN."""

    def __init__(self, result):
        self.result, self.scenario = result, result.scenario

    def __getitem__(self, name: str) -> np.ndarray:
        v = np.asarray(self.result[name])
        if v.dtype.kind != "f":
            return v
        with np.errstate(invalid="ignore"):
            return np.where(np.abs(v) <= DRAWABLE_MAX, v, np.nan)


def drawable(result):
    """``result`` as a figure reads it: each float column with NaN for any value that is
    not finite or is larger in magnitude than :data:`DRAWABLE_MAX`.

    Parameters
    ----------
    result : object
        ``result[name]`` gives a column, ``result.scenario`` the scenario
        (a :class:`quadland.engine.result.SimulationResult`).

    Returns
    -------
    object
        The same interface; ``drawable(drawable(r))`` reads as ``drawable(r)``.

    Examples
    --------
    >>> import numpy as np
    >>> class Result:
    ...     scenario = None
    ...     def __getitem__(self, name):
    ...         return np.array([1.0, np.inf, 1e300])
    >>> drawable(Result())["x"]
    array([ 1., nan, nan])
    """
    return result if isinstance(result, _Drawable) else _Drawable(result)
