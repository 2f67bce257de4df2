"""A lock-down device's face on a ball joint in a foot: where it lies flush, where on its edge.

The face of a magnet in a foot (:data:`~quadland_symbolic.landing.contact.LOCK`'s
``at_feet``) swivels on a ball joint within ``swivel`` of the joint's neutral axis; past it
the face meets the deck on its edge and its centre stands off, which the device's gap law
then sees (docs/contact.md, "The lock-down device").
"""

from __future__ import annotations

import casadi as ca

__all__ = ["swivel_edge"]


def swivel_edge(R1, n2, lk):
    """How far a foot device's face centre stands off the deck past its swivel (m).

    The face swivels flush with the deck while the angle ``A`` between the deck's normal
    and the device's neutral axis ``a = (-sin b, 0, cos b)`` (body axes, ``b`` =
    ``swivel_pitch``: the deck's normal as seen from a body pitched ``b`` nose down) is
    within ``swivel`` (0 to 90 deg); past it by ``e = A - swivel`` the face rests on its
    edge, and its centre stands ``face_width / 2 sin e`` off (``e`` capped at 90 deg).
    ``sin e`` comes from ``cos A = a . n`` and ``sin A = sqrt(1 - cos^2 A + 1e-12)``
    without an inverse cosine, whose slope is infinite where the two align (the
    linearizations); the floor moves ``sin A`` by at most 1e-6."""
    n_b = R1.T @ n2
    b, al = lk["swivel_pitch"], lk["swivel"]
    cos_a = -ca.sin(b) * n_b[0] + ca.cos(b) * n_b[2]
    sin_a = ca.sqrt(ca.fmax(1 - cos_a ** 2, 0) + 1e-12)
    sin_e = sin_a * ca.cos(al) - cos_a * ca.sin(al)
    cos_e = cos_a * ca.cos(al) + sin_a * ca.sin(al)
    return lk["face_width"] / 2 * ca.if_else(cos_e < 0, 1, ca.fmax(sin_e, 0))
