"""The paper's Figures 2-5 and the ground track, as PNG bytes."""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import numpy as np  # noqa: E402

from quadland.simulate import SimulationResult  # noqa: E402

__all__ = ["FIGURES", "render_figures"]

#: File name and title of each figure.
FIGURES = {
    "fig2_relative_altitude_attitude.png": "Relative altitude and attitude (Fig. 2)",
    "fig3_velocity_errors.png": "Velocity errors e2 (Fig. 3)",
    "fig4_control_inputs.png": "Control inputs (Fig. 4)",
    "fig5_uncertainty_estimation.png": "Uncertainty and its RBFNN estimate (Fig. 5)",
    "ground_track.png": "Ground track of the quadrotor and the vehicle",
}


def _grid(title, rows=4):
    fig, axes = plt.subplots(rows, 1, sharex=True, figsize=(7, 1.9 * rows + 0.6))
    fig.suptitle(title)
    return fig, axes


def _four_panel(r, fig_name, first, first_unit, rest, rest_unit):
    """One linear signal and three angular ones (shown in degrees)."""
    fig, ax = _grid(FIGURES[fig_name])
    t = r["t"]
    ax[0].plot(t, r[first])
    ax[0].set_ylabel(f"{first} [{first_unit}]")
    for a, name in zip(ax[1:], rest):
        a.plot(t, np.rad2deg(r[name]))
        a.set_ylabel(f"{name} [{rest_unit}]")
    return fig, ax


def _fig2(r):
    return _four_panel(r, "fig2_relative_altitude_attitude.png", "z_e", "m",
                       ("phi_e", "theta_e", "psi_e"), "deg")


def _fig3(r):
    return _four_panel(r, "fig3_velocity_errors.png", "dz_e", "m/s", ("p_e", "q_e", "r_e"),
                       "deg/s")


def _fig4(r):
    fig, ax = _grid(FIGURES["fig4_control_inputs.png"])
    t = r["t"]
    units = ("m/s^2", "rad/s^2", "rad/s^2", "rad/s^2")
    for i, a in enumerate(ax):
        a.plot(t, r[f"u_{i + 1}"])
        a.set_ylabel(f"u_{i + 1} [{units[i]}]")
    return fig, ax


def _fig5(r):
    fig, ax = _grid(FIGURES["fig5_uncertainty_estimation.png"])
    t = r["t"]
    nominal = r.scenario.data["controller"]["nominal_model"]
    for i, a in enumerate(ax):
        k = i + 1
        a.plot(t, r[f"Delta_{k}"], label="Delta = f + d")
        if nominal:
            a.plot(t, r[f"Delta_target_{k}"], label="Delta - fed-forward part")
        a.plot(t, r[f"Delta_hat_{k}"], "--", label="W_hat^T Psi")
        a.set_ylabel(f"channel {k}")
    ax[0].legend(loc="best", fontsize="small")
    return fig, ax


def _track(r):
    fig, a = plt.subplots(figsize=(6, 6))
    a.plot(r["x2"], r["y2"], label="vehicle")
    a.plot(r["x1"], r["y1"], "--", label="quadrotor")
    a.plot(r["x2"][0], r["y2"][0], "ko", label="start")
    a.set_xlabel("x [m]")
    a.set_ylabel("y [m]")
    a.set_aspect("equal", adjustable="datalim")
    a.set_title(FIGURES["ground_track.png"])
    a.legend(loc="best")
    a.grid(True)
    return fig, None


def render_figures(result: SimulationResult) -> dict[str, bytes]:
    """Render every figure of ``FIGURES`` to PNG bytes, by file name."""
    out = {}
    stamp = f"scenario {result.scenario.name}"
    for (name, _), draw in zip(FIGURES.items(), (_fig2, _fig3, _fig4, _fig5, _track)):
        fig, axes = draw(result)
        if axes is not None:
            for a in axes:
                a.grid(True)
            axes[-1].set_xlabel("t [s]")
        fig.text(0.99, 0.005, stamp, ha="right", va="bottom", fontsize="x-small", color="0.4")
        fig.tight_layout()
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110, metadata={"Software": None})
        plt.close(fig)
        out[name] = buf.getvalue()
    return out
