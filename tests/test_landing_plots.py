"""Landing figures and animation: each draws the result's own data, limits and phases.

The landing is made by hand here (a descent onto a pad that drives a curve,
heaves, rolls and pitches), so these tests need no simulator.
"""

import sys

import numpy as np
import pytest
from matplotlib import animation
from matplotlib.figure import Figure
from PIL import Image
from scipy.spatial.transform import Rotation

from quadland.exceptions import QuadlandError
from quadland.plots import (
    LANDING_FIGURES,
    landing_animation,
    landing_figures,
    landing_ground_track_plot,
    landing_limits,
    relative_position_plot,
    rotor_forces_plot,
    trajectory_3d_plot,
)
from quadland.plots.animation import frame_rows
from quadland.plots.landing import LIMIT_NAMES, PAD_SIZE
from quadland.scenario import Scenario
from quadland_symbolic.landing.guidance import PHASES

RATE = 50.0        # rows per second
TOUCHDOWN = 3.0    # s
MASS, GRAVITY, THRUST_TO_WEIGHT = 1.5, 9.81, 2.0
F_MAX = THRUST_TO_WEIGHT * MASS * GRAVITY / 4
#: (phase, start, end) of the hand-made landing, s
RUNS = [(0, 0.0, 1.0), (1, 1.0, 1.5), (2, 1.5, 3.0), (3, 3.0, 3.5), (4, 3.5, 4.0)]


class _Landing(dict):
    """Columns by name and a scenario: all the figures read."""

    def __init__(self, columns, scenario):
        super().__init__(columns)
        self.scenario = scenario


def _deck_rotation(psi, theta, phi):
    """Rz(psi) Ry(theta) Rx(phi): scipy's intrinsic ZYX."""
    return Rotation.from_euler("ZYX", np.column_stack([psi, theta, phi])).as_matrix()


def _landing(duration=4.0, landing=None, quadrotor=True, touchdown=TOUCHDOWN):
    t = np.arange(round(duration * RATE) + 1) / RATE
    psi2 = 0.3 + 0.05 * t                                 # a turn at 3 m/s
    x2, y2 = 60 * (np.sin(psi2) - np.sin(0.3)), -60 * (np.cos(psi2) - np.cos(0.3))
    z2 = 1.0 + 0.3 * np.sin(1.1 * t)                      # heave
    phi2, theta2 = 0.05 * np.sin(0.7 * t), 0.04 * np.sin(0.9 * t + 0.4)
    shape = (1 - np.clip(t / touchdown, 0, 1)) ** 2       # 1 at the start, 0 from touchdown
    dshape = np.where(t < touchdown, -2 * (1 - t / touchdown) / touchdown, 0.0)
    p_e = np.column_stack([-3 * shape, shape, 0.15 + 2.85 * shape])
    v_e = np.column_stack([-3 * dshape, dshape, 2.85 * dshape])
    p1 = (np.column_stack([x2, y2, z2])
          + np.einsum("nij,nj->ni", _deck_rotation(psi2, theta2, phi2), p_e))
    phase = np.select([t < 1, t < 1.5, t < touchdown, t < touchdown + 0.5], [0, 1, 2, 3], 4)
    F = np.column_stack([MASS * GRAVITY / 4 * (1 + 0.1 * np.sin(2 * t + k)) for k in range(4)])
    phi1, theta1, psi1 = phi2 + 0.1 * shape * np.sin(3 * t), theta2 - 0.08 * shape, \
        psi2 + 0.2 * shape
    n1 = _deck_rotation(psi1, theta1, phi1)[:, :, 2]
    n2 = _deck_rotation(psi2, theta2, phi2)[:, :, 2]
    tilt = np.degrees(np.arccos(np.clip(np.sum(n1 * n2, axis=1), -1, 1)))
    columns = dict(
        t=t, phase=phase, x1=p1[:, 0], y1=p1[:, 1], z1=p1[:, 2],
        phi1=phi1, theta1=theta1, psi1=psi1, x2=x2, y2=y2, z2=z2, phi2=phi2,
        theta2=theta2, psi2=psi2, x_e=p_e[:, 0], y_e=p_e[:, 1], z_e=p_e[:, 2],
        dx_e=v_e[:, 0], dy_e=v_e[:, 1], dz_e=v_e[:, 2], tilt_deg=tilt, F_total=F.sum(axis=1),
        M_x=0.2 * (F[:, 1] - F[:, 3]), M_y=0.2 * (F[:, 2] - F[:, 0]),
        M_z=0.01 * (F[:, 0] - F[:, 1] + F[:, 2] - F[:, 3]),
        F_1=F[:, 0], F_2=F[:, 1], F_3=F[:, 2], F_4=F[:, 3],
        d_Fx=0 * t, d_Fy=0 * t, d_Fz=0 * t)
    data = {}
    if quadrotor:
        data["quadrotor"] = {"mass": MASS, "gravity": GRAVITY,
                             "thrust_to_weight": THRUST_TO_WEIGHT, "arm_length": 0.2}
    if landing is not None:
        data["landing"] = landing
    return _Landing(columns, Scenario(name="synthetic", source="<test>", data=data))


@pytest.fixture(scope="module")
def result():
    return _landing()


@pytest.fixture(autouse=True)
def _no_pyplot_figure():
    yield
    if "matplotlib.pyplot" in sys.modules:
        assert sys.modules["matplotlib.pyplot"].get_fignums() == []


def _data(line):
    return np.asarray(line.get_xdata(), dtype=float), np.asarray(line.get_ydata(), dtype=float)


def _by_label(ax, label):
    (line,) = [ln for ln in ax.lines if ln.get_label() == label]
    return line


def _limit_values(ax):
    """y of every dotted or dashed horizontal line (axhline) of an axis."""
    return sorted(float(ln.get_ydata()[0]) for ln in ax.lines
                  if ln.get_linestyle() in (":", "--") and ln.get_xdata()[0] == 0
                  and ln.get_xdata()[1] == 1)


def test_landing_figures(result):
    figs = landing_figures(result)
    assert list(figs) == list(LANDING_FIGURES) == [
        "landing_3d.png", "relative_position.png", "ground_tracks.png", "rotor_forces.png"]
    for name, fig in figs.items():
        assert isinstance(fig, Figure)
        assert (fig.get_suptitle() or fig.axes[0].get_title()) == LANDING_FIGURES[name]
        assert any(t.get_text() == "scenario synthetic" for t in fig.texts)


def test_trajectory_3d_draws_the_approach_from_the_pad_centre(result):
    (a,) = trajectory_3d_plot(result).axes
    xyz = _by_label(a, "quadrotor").get_data_3d()
    for got, name in zip(xyz, "xyz", strict=True):
        np.testing.assert_array_equal(got, result[f"{name}1"] - result[f"{name}2"])
    start = np.ravel(_by_label(a, "quadrotor start").get_data_3d())
    np.testing.assert_array_equal(start, [result[f"{n}1"][0] - result[f"{n}2"][0]
                                          for n in "xyz"])
    np.testing.assert_array_equal(np.ravel(_by_label(a, "pad centre").get_data_3d()), 0.0)


@pytest.mark.parametrize("landing, pad_size, side", [
    (None, None, PAD_SIZE),
    ({"pad_size": 2.5}, None, 2.5),
    ({"pad_size": 2.5}, 0.8, 0.8),
])
def test_pad_square_lies_at_touchdown_in_the_deck_plane(landing, pad_size, side):
    res = _landing(landing=landing)
    (a,) = trajectory_3d_plot(res, pad_size=pad_size).axes
    square = np.column_stack(_by_label(a, "pad at touchdown").get_data_3d())
    row = round(TOUCHDOWN * RATE)                 # the first row with phase 3
    assert res["phase"][row] == 3 and res["phase"][row - 1] == 2
    # by hand, from the pad centre: R_deck [+-s/2, +-s/2, 0]
    R = _deck_rotation([res["psi2"][row]], [res["theta2"][row]], [res["phi2"][row]])[0]
    h = side / 2
    expected = [R @ np.array([sx * h, sy * h, 0.0]) for sx in (1, -1) for sy in (1, -1)]
    assert square.shape == (5, 3)
    np.testing.assert_array_equal(square[0], square[-1])          # closed
    for corner in expected:
        assert np.min(np.linalg.norm(square[:4] - corner, axis=1)) < 1e-12
    # the corners are in the deck plane and the sides are a square's
    np.testing.assert_allclose(square[:4] @ R[:, 2], 0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(np.diff(square, axis=0), axis=1), side,
                               rtol=1e-12)


def test_pad_square_without_touchdown_is_at_the_end():
    res = _landing(duration=2.0, touchdown=10.0)
    assert res["phase"].max() < 3
    (a,) = trajectory_3d_plot(res).axes
    square = np.column_stack(_by_label(a, "pad at the end (no touchdown)").get_data_3d())
    np.testing.assert_allclose(square[:4].mean(axis=0), 0.0, atol=1e-12)   # on the pad centre


def test_relative_position_plots_the_columns_and_rates(result):
    fig = relative_position_plot(result)
    assert len(fig.axes) == 4
    t = result["t"]
    pos, height, speed, tilt = fig.axes
    for label, y in (("x_e", result["x_e"]), ("y_e", result["y_e"]),
                     ("offset", np.hypot(result["x_e"], result["y_e"]))):
        x, yy = _data(_by_label(pos, label))
        np.testing.assert_array_equal(x, t)
        np.testing.assert_array_equal(yy, y)
    np.testing.assert_array_equal(_data(_by_label(height, "z_e"))[1], result["z_e"])
    # the rates and the tilt are the result's own signals, not re-derived
    np.testing.assert_array_equal(_data(_by_label(speed, "horizontal speed"))[1],
                                  np.hypot(result["dx_e"], result["dy_e"]))
    np.testing.assert_array_equal(_data(_by_label(speed, "sink rate"))[1], -result["dz_e"])
    np.testing.assert_array_equal(_data(_by_label(tilt, "tilt from deck normal"))[1],
                                  result["tilt_deg"])
    assert fig.axes[-1].get_xlabel() == "t [s]"


LIMITS = {"max_offset": 0.3, "max_sink_rate": 0.7, "max_tilt_deg": 8.0,
          "max_relative_speed": 0.4, "F_max": 5.0}


def _touchdown_limits(ax, t_end):
    """y of every touchdown limit segment of an axis, each checked to run from the
    hand-made landing's touchdown (3 s) to its end."""
    lines = [ln for ln in ax.lines if ln.get_gid() == "limit"]
    for ln in lines:
        assert list(ln.get_xdata()) == [TOUCHDOWN, t_end]
        assert ln.get_ydata()[0] == ln.get_ydata()[1]
    return sorted(float(ln.get_ydata()[0]) for ln in lines)


@pytest.mark.parametrize("limits", [LIMITS, {"max_offset": 0.25, "max_tilt_deg": 12.0}, None])
def test_relative_position_limit_lines(limits):
    """Each limit given is drawn where it applies, from touchdown to the end; one not
    given is not drawn; none is drawn across the flight."""
    res = _landing()
    pos, height, speed, tilt = relative_position_plot(res, limits).axes
    t_end = res["t"][-1]
    lim = {k: (limits or {}).get(k) for k in LIMIT_NAMES}
    off = lim["max_offset"]
    assert _touchdown_limits(pos, t_end) == ([] if off is None else [-off, off])
    assert _touchdown_limits(height, t_end) == []
    for name in ("max_relative_speed", "max_sink_rate"):
        lines = [ln for ln in speed.lines if ln.get_label() == name]
        assert [ln.get_ydata()[0] for ln in lines] == ([] if lim[name] is None else [lim[name]])
        assert all(ln.get_gid() == "limit" for ln in lines)
    assert _touchdown_limits(tilt, t_end) == ([] if lim["max_tilt_deg"] is None
                                              else [lim["max_tilt_deg"]])
    for a in (pos, height, speed, tilt):
        assert _limit_values(a) == []             # no line across the whole flight


def test_no_legend_hides_a_touchdown_limit():
    """Drawn, each axis' legend leaves the touchdown limit segments (the end of the
    flight) in view: at "upper right" it covered highway's tilt limit (28.1 deg, near
    the approach's 30) and its offset limit (review of issue 21). Here the tilt limit
    sits near the top of its axis too, at 0.97 of the largest tilt, in the top right
    corner."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    res = _landing()
    tilt_limit = 0.97 * float(np.max(res["tilt_deg"]))
    assert tilt_limit > np.max(res["tilt_deg"][res["t"] >= TOUCHDOWN])
    fig = relative_position_plot(res, {**LIMITS, "max_tilt_deg": tilt_limit})
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    for a in fig.axes:
        box = a.get_legend().get_window_extent(renderer)
        for line in (ln for ln in a.lines if ln.get_gid() == "limit"):
            assert not box.overlaps(line.get_window_extent(renderer)), line.get_label()


def test_no_touchdown_no_touchdown_limits():
    res = _landing(duration=2.0, touchdown=10.0)
    for a in relative_position_plot(res, LIMITS).axes:
        assert [ln for ln in a.lines if ln.get_gid() == "limit"] == []


@pytest.mark.parametrize("plot", [relative_position_plot, rotor_forces_plot])
def test_phases_are_shaded_where_they_are(result, plot):
    fig = plot(result)
    for a in fig.axes:
        spans = [(p.get_x(), p.get_x() + p.get_width()) for p in a.patches]
        assert spans == [(t0, t1) for _, t0, t1 in RUNS]
        colours = [p.get_facecolor() for p in a.patches]
        assert len(set(colours)) == len(RUNS)
    (legend,) = fig.legends
    assert [t.get_text() for t in legend.get_texts()] == list(PHASES)


def test_phase_runs_repeat_after_an_abort():
    res = _landing()
    res["phase"] = np.where((res["t"] >= 2.0) & (res["t"] < 2.5), 1, res["phase"])  # abort
    a = relative_position_plot(res).axes[0]
    spans = [(p.get_x(), p.get_x() + p.get_width()) for p in a.patches]
    assert spans == [(0.0, 1.0), (1.0, 1.5), (1.5, 2.0), (2.0, 2.5), (2.5, 3.0), (3.0, 3.5),
                     (3.5, 4.0)]


def test_ground_track_plot(result):
    (a,) = landing_ground_track_plot(result).axes
    for label, body in (("pad centre", "2"), ("quadrotor", "1")):
        x, y = _data(_by_label(a, label))
        np.testing.assert_array_equal(x, result[f"x{body}"])
        np.testing.assert_array_equal(y, result[f"y{body}"])
        start = _data(_by_label(a, f"{label.split()[0]} start"))
        assert (start[0][0], start[1][0]) == (result[f"x{body}"][0], result[f"y{body}"][0])
        row = round(TOUCHDOWN * RATE)
        end = _data(_by_label(a, f"{label.split()[0]} at touchdown"))
        assert (end[0][0], end[1][0]) == (result[f"x{body}"][row], result[f"y{body}"][row])
    assert a.get_aspect() == "auto"               # the approach is not squeezed flat
    (inset,) = a.child_axes                       # true scale around the pad at touchdown
    assert inset.get_aspect() == 1.0
    row = round(TOUCHDOWN * RATE)
    cx, cy = result["x2"][row], result["y2"][row]
    assert inset.get_xlim() == (cx - 2 * PAD_SIZE, cx + 2 * PAD_SIZE)
    assert inset.get_ylim() == (cy - 2 * PAD_SIZE, cy + 2 * PAD_SIZE)
    square = np.column_stack(_data(_by_label(inset, "pad at touchdown")))
    np.testing.assert_allclose(square[:4].mean(axis=0), [cx, cy], atol=1e-12)


def test_ground_track_without_touchdown_has_no_touchdown_mark():
    (a,) = landing_ground_track_plot(_landing(duration=2.0, touchdown=10.0)).axes
    assert not [ln for ln in a.lines if "touchdown" in ln.get_label()]
    assert a.child_axes == []


def test_trajectory_3d_has_equal_scales(result):
    """A metre is as long on every axis: each axis's span over its box side is one number."""
    (a,) = trajectory_3d_plot(result).axes
    spans = np.array([np.diff(a.get_xlim())[0], np.diff(a.get_ylim())[0],
                      np.diff(a.get_zlim())[0]])
    box = np.asarray(a.get_box_aspect())
    np.testing.assert_allclose(spans / box, (spans / box)[0], rtol=1e-9)
    for name, lim in zip("xyz", (a.get_xlim(), a.get_ylim(), a.get_zlim()), strict=True):
        rel = result[f"{name}1"] - result[f"{name}2"]
        assert lim[0] <= min(rel.min(), 0.0) and max(rel.max(), 0.0) <= lim[1]


def test_two_landings_overlay_on_one_figure(result):
    """``ax=``: a second run drawn into the first one's axes adds its lines there."""
    other = _landing(duration=3.5, touchdown=2.5)
    fig = relative_position_plot(result)
    assert relative_position_plot(other, ax=fig.axes) is fig
    # the first run alone is unlabelled, the overlay's lines carry its scenario's name
    # (tests/test_overlay.py: two real runs, each with its label= )
    assert [ln.get_label() for ln in fig.axes[1].lines] == ["z_e", "z_e (synthetic)"]
    fig = rotor_forces_plot(result)
    assert rotor_forces_plot(other, ax=fig.axes) is fig
    assert [ln.get_label() for ln in fig.axes[1].lines if "F_total" in ln.get_label()] == \
        ["F_total", "F_total (synthetic)"]
    fig = landing_ground_track_plot(result)
    assert landing_ground_track_plot(other, ax=fig.axes[0]) is fig
    assert len([ln for ln in fig.axes[0].lines if ln.get_gid() == "quadrotor"]) == 2
    fig = trajectory_3d_plot(result)
    assert trajectory_3d_plot(other, ax=fig.axes[0]) is fig
    assert len([ln for ln in fig.axes[0].lines if ln.get_gid() == "quadrotor"]) == 2


@pytest.mark.parametrize("limits, F_max", [
    ({"F_max": F_MAX}, F_MAX),
    ({"F_max": 6.0}, 6.0),
    (None, None),
])
def test_rotor_forces_plot(limits, F_max):
    res = _landing()
    rotors, total = rotor_forces_plot(res, limits).axes
    for k in range(1, 5):
        x, y = _data(_by_label(rotors, f"F_{k}"))
        np.testing.assert_array_equal(x, res["t"])
        np.testing.assert_array_equal(y, res[f"F_{k}"])
    np.testing.assert_array_equal(_data(_by_label(total, "F_total"))[1], res["F_total"])
    if F_max is None:
        assert _limit_values(rotors) == _limit_values(total) == [0.0]
    else:
        assert _limit_values(rotors) == pytest.approx([0.0, F_max], rel=1e-15)
        assert _limit_values(total) == pytest.approx([0.0, 4 * F_max], rel=1e-15)


def test_landing_limits_rejects_unknown_keys():
    with pytest.raises(ValueError, match="max_ofset"):
        landing_limits({"max_ofset": 0.3})
    assert landing_limits({"F_max": F_MAX})["F_max"] == pytest.approx(F_MAX)
    assert landing_limits()["F_max"] is None


# animation


def test_frames_of_a_long_landing():
    t = np.arange(3001) / 100.0                   # 30 s at 100 Hz
    rows = frame_rows(t, 20)
    assert len(rows) == 12 * 20 + 1               # played in 12 s
    assert rows[0] == 0 and rows[-1] == 3000
    assert set(np.diff(rows)) <= {12, 13}         # evenly spaced: 3000 / 240 = 12.5
    short = np.arange(21) / 10.0                  # 2 s at 10 Hz, at 20 fps: every row
    np.testing.assert_array_equal(frame_rows(short, 20), np.arange(21))


def test_animation_writes_a_gif(tmp_path):
    res = _landing(duration=2.0, touchdown=1.6)
    fps = 10
    path = landing_animation(res, tmp_path / "landing.gif", fps=fps)
    assert path == tmp_path / "landing.gif"
    assert path.read_bytes()[:6] == b"GIF89a"
    with Image.open(path) as im:
        assert im.format == "GIF"
        assert im.n_frames == round(2.0 * fps) + 1
        assert im.info["duration"] == 1000 // fps
        assert im.size == (800, 650)                # FRAME_SIZE at FRAME_DPI
    again = landing_animation(res, tmp_path / "again.gif", fps=fps)
    assert again.read_bytes() == path.read_bytes()


def test_animation_mp4_needs_ffmpeg(tmp_path, monkeypatch):
    monkeypatch.setattr(animation.writers, "is_available", lambda name: False)
    with pytest.raises(QuadlandError, match="ffmpeg"):
        landing_animation(_landing(duration=0.2), tmp_path / "landing.mp4")
    with pytest.raises(QuadlandError, match=r"\.gif or an \.mp4"):
        landing_animation(_landing(duration=0.2), tmp_path / "landing.avi")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not animation.writers.is_available("ffmpeg"), reason="no ffmpeg")
def test_animation_writes_an_mp4(tmp_path):
    path = landing_animation(_landing(duration=1.0), tmp_path / "landing.mp4", fps=10)
    assert path.read_bytes()[4:8] == b"ftyp"
