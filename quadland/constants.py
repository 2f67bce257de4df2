"""Constants shared by several of quadland's modules, each defined once here."""

__all__ = ["TILT_MIN"]

#: Smallest accepted ``|cos(theta1) cos(phi1)|``: the thrust map of eq. (6)
#: divides by it. The simulator stops, the linearization refuses a point and
#: the generated C step returns ``QL_ERR_TILT`` below it (about 89.94 deg).
TILT_MIN = 1e-3
