"""The paper's Figures 2-5 and the ground track of a simulation."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from quadland.engine.result import SimulationResult
from quadland.plots.finite import drawable
from quadland.plots.style import finish

__all__ = ["SIMULATION_FIGURES", "CHANNEL_UNITS", "relative_errors_plot", "velocity_errors_plot",
           "control_inputs_plot", "uncertainty_plot", "ground_track_plot", "simulation_figures"]

#: File name and title of each figure, in the order of :func:`simulation_figures`.
SIMULATION_FIGURES = {
    "fig2_relative_altitude_attitude.png": "Relative altitude and attitude (Fig. 2)",
    "fig3_velocity_errors.png": "Velocity errors e2 (Fig. 3)",
    "fig4_control_inputs.png": "Control inputs (Fig. 4)",
    "fig5_uncertainty_estimation.png": "Uncertainty and its RBFNN estimate (Fig. 5)",
    "ground_track.png": "Ground track of the quadrotor and the vehicle",
}


#: Units of the channels of u, Delta and its estimate: the altitude channel's and
#: the three attitude channels' accelerations.
CHANNEL_UNITS = ("m/s^2", "rad/s^2", "rad/s^2", "rad/s^2")


def _grid(title: str, ax=None, rows: int = 4):
    """A new figure of ``rows`` time axes, or the figure of the axes ``ax`` given."""
    if ax is not None:
        axes = list(np.ravel(np.asarray(ax, dtype=object)))
        if len(axes) != rows:
            raise ValueError(f"ax: {rows} axes expected, got {len(axes)}")
        return axes[0].figure, axes
    fig = Figure(figsize=(7, 1.9 * rows + 0.6))
    axes = fig.subplots(rows, 1, sharex=True)
    fig.suptitle(title)
    return fig, axes


def _done(fig: Figure, result, axes, own: bool) -> Figure:
    """A new figure finished (:func:`quadland.plots.style.finish`); an overlay as it is."""
    if own:
        return finish(fig, result, axes)
    for a in axes:
        a.legend(fontsize="small")
    return fig


def _run_label(result, label: str | None) -> str:
    """The name of a run in an overlay's legend: ``label``, else its scenario's name."""
    return result.scenario.name if label is None else str(label)


def _four_panel(result, fig_name, first, first_unit, rest, rest_unit, ax,
                label=None) -> Figure:
    """One linear signal and three angular ones (shown in degrees)."""
    fig, axes = _grid(SIMULATION_FIGURES[fig_name], ax)
    t = result["t"]
    label = _run_label(result, label)
    axes[0].plot(t, result[first], label=label)
    axes[0].set_ylabel(f"{first} [{first_unit}]")
    for a, name in zip(axes[1:], rest, strict=True):
        a.plot(t, np.rad2deg(result[name]), label=label)
        a.set_ylabel(f"{name} [{rest_unit}]")
    return _done(fig, result, axes, ax is None)


def relative_errors_plot(result: SimulationResult, ax=None,
                         label: str | None = None) -> Figure:
    """Relative altitude and attitude errors against time (the paper's Fig. 2).

    Parameters
    ----------
    result : SimulationResult
    ax : sequence of four matplotlib Axes, optional
        Where to draw, to overlay runs (each line labelled with ``label``);
        a new figure if None.
    label : str, optional
        The run's name in the legend; by default its scenario's name (two
        runs of one scenario, say with different gains, need their own).

    Returns
    -------
    matplotlib.figure.Figure
        Four axes: ``z_e`` (m), then ``phi_e``, ``theta_e``, ``psi_e`` (deg).
    """
    return _four_panel(result, "fig2_relative_altitude_attitude.png", "z_e", "m",
                       ("phi_e", "theta_e", "psi_e"), "deg", ax, label)


def velocity_errors_plot(result: SimulationResult, ax=None,
                         label: str | None = None) -> Figure:
    """Velocity errors e2 against time (the paper's Fig. 3).

    Parameters
    ----------
    result : SimulationResult
    ax : sequence of four matplotlib Axes, optional
        Where to draw, to overlay runs (each line labelled with ``label``);
        a new figure if None.
    label : str, optional
        The run's name in the legend; by default its scenario's name (two
        runs of one scenario, say with different gains, need their own).

    Returns
    -------
    matplotlib.figure.Figure
        Four axes: ``dz_e`` (m/s), then ``p_e``, ``q_e``, ``r_e`` (deg/s).
    """
    return _four_panel(result, "fig3_velocity_errors.png", "dz_e", "m/s",
                       ("p_e", "q_e", "r_e"), "deg/s", ax, label)


def control_inputs_plot(result: SimulationResult, ax=None,
                        label: str | None = None) -> Figure:
    """Virtual control inputs u_1..u_4 against time (the paper's Fig. 4).

    Parameters
    ----------
    result : SimulationResult
    ax : sequence of four matplotlib Axes, optional
        Where to draw, to overlay runs (each line labelled with ``label``);
        a new figure if None.
    label : str, optional
        The run's name in the legend; by default its scenario's name (two
        runs of one scenario, say with different gains, need their own).

    Returns
    -------
    matplotlib.figure.Figure
        Four axes, ``u_1`` (m/s^2) and ``u_2..u_4`` (rad/s^2).
    """
    fig, axes = _grid(SIMULATION_FIGURES["fig4_control_inputs.png"], ax)
    t = result["t"]
    for i, a in enumerate(axes):
        a.plot(t, result[f"u_{i + 1}"], label=_run_label(result, label))
        a.set_ylabel(f"u_{i + 1} [{CHANNEL_UNITS[i]}]")
    return _done(fig, result, axes, ax is None)


def uncertainty_plot(result: SimulationResult, ax=None,
                     label: str | None = None) -> Figure:
    """Uncertainty and its RBFNN estimate against time (the paper's Fig. 5).

    Parameters
    ----------
    result : SimulationResult
    ax : sequence of four matplotlib Axes, optional
        Where to draw, to overlay runs (each line labelled with ``label``);
        a new figure if None.
    label : str, optional
        The run's name in the legend; by default its scenario's name (two
        runs of one scenario, say with different gains, need their own).

    Returns
    -------
    matplotlib.figure.Figure
        One axis per channel k, in the channel's unit (``m/s^2`` for
        altitude, ``rad/s^2`` for the attitude channels, those of ``u_k``):
        ``Delta_k`` (``f + d``), with
        ``controller.nominal_model`` also the network's target
        ``Delta_target_k``, and the estimate ``Delta_hat_k`` (dashed).
    """
    own = ax is None
    fig, axes = _grid(SIMULATION_FIGURES["fig5_uncertainty_estimation.png"], ax)
    t = result["t"]
    nominal = result.scenario.data["controller"]["nominal_model"]
    tag = "" if own and label is None else f" ({_run_label(result, label)})"
    for i, a in enumerate(axes):
        k = i + 1
        a.plot(t, result[f"Delta_{k}"], label="Delta = f + d" + tag)
        if nominal:
            a.plot(t, result[f"Delta_target_{k}"], label="Delta - fed-forward part" + tag)
        a.plot(t, result[f"Delta_hat_{k}"], "--", label="W_hat^T Psi" + tag)
        a.set_ylabel(f"Delta_{k} [{CHANNEL_UNITS[i]}]")
    axes[0].legend(loc="best", fontsize="small")
    return finish(fig, result, axes) if own else fig


def ground_track_plot(result: SimulationResult, ax=None,
                      label: str | None = None) -> Figure:
    """Planar tracks of the vehicle and the quadrotor.

    Parameters
    ----------
    result : SimulationResult
    ax : matplotlib Axes, optional
        Where to draw, to overlay runs (each line labelled with ``label``);
        a new figure if None.
    label : str, optional
        The run's name in the legend; by default its scenario's name (two
        runs of one scenario, say with different gains, need their own).

    Returns
    -------
    matplotlib.figure.Figure
        One axis, equal scales: ``(x2, y2)``, ``(x1, y1)`` (dashed) and the
        vehicle's start, m.
    """
    own = ax is None
    if own:
        fig = Figure(figsize=(6, 6))
        ax = fig.subplots()
    fig, a = ax.figure, ax
    tag = "" if own and label is None else f" ({_run_label(result, label)})"
    a.plot(result["x2"], result["y2"], label="vehicle" + tag)
    a.plot(result["x1"], result["y1"], "--", label="quadrotor" + tag)
    a.plot(result["x2"][0], result["y2"][0], "ko", label="start")
    a.set_xlabel("x [m]")
    a.set_ylabel("y [m]")
    a.set_aspect("equal", adjustable="datalim")
    a.set_title(SIMULATION_FIGURES["ground_track.png"])
    a.legend(loc="best")
    a.grid(True)
    return finish(fig, result) if own else fig


def simulation_figures(result: SimulationResult) -> dict[str, Figure]:
    """Every figure of a simulation, by the file name it is saved under.

    Parameters
    ----------
    result : SimulationResult

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        Keys are those of :data:`SIMULATION_FIGURES`, in that order.

    Examples
    --------
    >>> import quadland
    >>> from quadland.plots import simulation_figures
    >>> res = quadland.simulate(quadland.load_scenario("paper", ["simulation.duration=0.1"]))
    >>> list(simulation_figures(res))[0]
    'fig2_relative_altitude_attitude.png'
    """
    draw = (relative_errors_plot, velocity_errors_plot, control_inputs_plot, uncertainty_plot,
            ground_track_plot)
    result = drawable(result)                 # a failed flight's last rows may diverge
    return {name: plot(result) for name, plot in zip(SIMULATION_FIGURES, draw, strict=True)}
