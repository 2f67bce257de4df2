"""Stand-ins for a campaign's flights, shared by the journal's tests."""

from __future__ import annotations

from quadland.campaign import local


def ctrl_c_at_run(monkeypatch, index: int):
    """Make the campaign's run ``index`` end in a Ctrl-C (a ``KeyboardInterrupt`` where it
    would have flown), the others fly as before; returns the real ``fly``."""
    real_fly = local.fly

    def fly(base, draw, limits, *keep):
        if draw.index == index:
            raise KeyboardInterrupt
        return real_fly(base, draw, limits, *keep)

    monkeypatch.setattr(local, "fly", fly)
    return real_fly
