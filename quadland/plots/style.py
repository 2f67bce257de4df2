"""What every figure of a run shares: the time axes' grid and label, the scenario's name."""

from __future__ import annotations

from matplotlib.figure import Figure

__all__ = ["finish"]


def finish(fig: Figure, result, axes=None) -> Figure:
    """Time-axis grid and label, the scenario's name in a corner, tight layout."""
    if axes is not None:
        for a in axes:
            a.grid(True)
        axes[-1].set_xlabel("t [s]")
    fig.text(0.99, 0.005, f"scenario {result.scenario.name}", ha="right", va="bottom",
             fontsize="x-small", color="0.4")
    fig.tight_layout()
    return fig
