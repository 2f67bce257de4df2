"""The margin review: typed report, its JSON form and its table, on a small network."""

import dataclasses
import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq
from threadpoolctl import threadpool_limits

from quadland.analysis import DiskMargin, Margins, freqresp
from quadland.cli import main
from quadland.exceptions import MarginsError
from quadland.margins import (
    LoopMargins,
    LoopReport,
    MarginReport,
    MultiloopDiskMargin,
    PoleSummary,
    Requirement,
    format_report,
    margin_report,
)
from quadland.scenario import load_scenario

SMALL = ["rbf.nodes=5"]
LOOPS = ["altitude", "roll", "pitch", "yaw"]


def _report(*overrides, **kwargs) -> MarginReport:
    with threadpool_limits(1):
        return margin_report(load_scenario("paper", [*SMALL, *overrides]), **kwargs)


@pytest.fixture(scope="module")
def report():
    return _report()


@pytest.fixture(scope="module")
def sampled():
    """50 Hz with the plain hold, and with the shipped hold compensation, commanded at
    the sample (no computation delay)."""
    return {hold: _report("controller.rate_hz=50", f"controller.hold_compensation={hold}",
                          delay_periods=0)
            for hold in (0.0, 0.5)}


@pytest.fixture(scope="module")
def delayed():
    """50 Hz, plain hold, with the default one period of computation delay."""
    return _report("controller.rate_hz=50", "controller.hold_compensation=0")


def test_report_is_typed(report):
    assert isinstance(report.requirement, Requirement)
    assert report.requirement == Requirement(6.0, 45.0)
    cont = report.continuous
    assert isinstance(cont, LoopReport) and cont.rate_hz is None
    assert report.sampled is None and report.sampled_models is None
    assert [m.name for m in cont.loops] == LOOPS
    for m in cont.loops:
        assert isinstance(m, LoopMargins)
        assert isinstance(m.crossings, Margins) and isinstance(m.disk, DiskMargin)
        assert cont.loop(m.name) is m
    assert isinstance(cont.multiloop_disk, MultiloopDiskMargin)
    assert isinstance(cont.poles, PoleSummary) and cont.poles.spectral_radius is None
    assert cont.poles.count == report.poles.size == report.models.loop_input.nstates
    assert cont.stable and cont.passed and report.passed and cont.failed == ()
    assert report.point.kind == "equilibrium"
    with pytest.raises(dataclasses.FrozenInstanceError):
        report.continuous = None
    with pytest.raises(KeyError):
        cont.loop("thrust")


def test_margins_agree_with_each_other(report):
    cont = report.continuous
    for m in cont.loops:
        # delay margin = phase margin (rad) / crossover frequency
        assert m.delay_margin_s == pytest.approx(
            math.radians(m.phase_margin_deg) / m.crossover_frequency, rel=1e-9)
        assert m.delay_margin_frequency == m.crossover_frequency
        # the summary values are the extremes of every crossing
        assert m.phase_margin_deg == min(m.crossings.phase_margin)
        gms = np.array(m.crossings.gain_margin)
        up, down = gms[gms >= 1], gms[gms < 1]
        assert m.gain_margin_up_db == (20 * math.log10(up.min()) if up.size else math.inf)
        assert m.gain_margin_down_db == (20 * math.log10(down.max()) if down.size else -math.inf)
        assert m.disk.phase_margin == pytest.approx(
            math.degrees(2 * math.atan(m.disk.disk_margin / 2)), rel=1e-9)
        # the disk margin never promises more than the loop-at-a-time classical phase margin
        assert m.disk.phase_margin <= m.phase_margin_deg + 1e-9
    # the multiloop disk cannot exceed any single loop's disk
    alphas = [m.disk.disk_margin for m in cont.loops]
    assert cont.multiloop_disk.disk.disk_margin <= min(alphas) + 1e-9
    # every pole of the summary is a closed-loop pole
    for p in cont.poles.slowest + cont.poles.least_damped:
        assert np.min(np.abs(report.poles - complex(p.real, p.imag))) < 1e-12
        assert p.damping == pytest.approx(-p.real / abs(complex(p.real, p.imag)))


def test_to_dict_is_the_json_of_the_command(report, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["margins", "--set", *SMALL, "--no-plots", "--out", str(out)]) == 0
    data = json.loads((out / "margins.json").read_text())
    assert data.pop("runtime_s") > 0
    assert data.pop("versions")["control"]
    assert data == report.to_dict()
    assert list(data) == ["scenario", "overrides", "operating_point", "requirement",
                          "loop_break", "continuous", "verdict_from"]
    assert data["verdict_from"] == ["continuous"]        # no sampled loop, no filter
    cont = data["continuous"]
    assert list(cont) == ["stable", "loops", "multiloop_disk", "passed", "poles", "sensitivity"]
    ms = report.continuous.sensitivity.multiloop.ms
    assert cont["sensitivity"]["multiloop"]["ms"] == ms.value
    assert list(cont["loops"]) == LOOPS
    assert data["requirement"] == {"gain_margin_db": 6.0, "phase_margin_deg": 45.0}
    assert data["overrides"] == SMALL
    roll = report.continuous.loop("roll")
    entry = cont["loops"]["roll"]
    assert entry["phase_margin_deg"] == roll.phase_margin_deg
    assert entry["crossover_frequency"] == roll.crossover_frequency
    assert entry["all_crossings"]["pm_frequency"] == list(roll.crossings.pm_frequency)
    assert entry["disk"]["disk_margin"] == roll.disk.disk_margin
    assert cont["multiloop_disk"]["passed"] is report.continuous.multiloop_disk.passed
    assert cont["poles"]["count"] == report.continuous.poles.count
    # what it is doing, then the table
    printed = capsys.readouterr().out
    assert printed.startswith("quadland: margins of paper: linearizing, then the loops' "
                              "frequency responses...\n" + format_report(report))


def test_infinities_become_null(report):
    roll = report.continuous.loop("roll")
    assert roll.gain_margin_up_db == math.inf and roll.gain_margin_up_frequency is None
    entry = report.to_dict()["continuous"]["loops"]["roll"]
    assert entry["gain_margin_up_db"] is None and entry["gain_margin_up_frequency"] is None
    json.dumps(report.to_dict(), allow_nan=False)


def test_requirement_decides_the_verdict():
    strict = _report(requirement=Requirement(phase_margin_deg=89))
    assert not strict.passed and not strict.continuous.passed
    # the multiloop disk margin's phase (64 deg on the paper's loop) is short of 89 too
    assert strict.continuous.failed == (*LOOPS, "multiloop disk")
    assert strict.to_dict()["continuous"]["passed"] is False
    table = format_report(strict)
    assert ("requirement 6 dB / 89 deg, each loop with the others closed and the multiloop "
            "disk margin: FAIL") in table
    assert table.count("  FAIL") >= len(LOOPS)


def test_table_shows_the_report(report):
    table = format_report(report)
    for word in ("altitude", "roll", "pitch", "yaw", "multiloop disk margin", "least damped",
                 "slowest", "equilibrium"):
        assert word in table
    for m in report.continuous.loops:
        row = next(line for line in table.splitlines() if line.startswith(f"  {m.name} "))
        assert f"{m.phase_margin_deg:.1f}" in row and f"{m.disk.disk_margin:.3f}" in row
        assert row.endswith("pass")
    assert ("requirement 6 dB / 45 deg, each loop with the others closed and the multiloop "
            "disk margin: PASS") in table
    assert table.endswith("\n") and "sampled" not in table


@pytest.mark.parametrize("call, parameter", [
    (lambda: margin_report(load_scenario("paper", SMALL), at=-1.0), "at"),
    (lambda: margin_report(load_scenario("paper", SMALL), at=math.nan), "at"),
    (lambda: Requirement(gain_margin_db=-3.0), "gain_margin_db"),
    (lambda: Requirement(gain_margin_db=math.inf), "gain_margin_db"),
    (lambda: Requirement(phase_margin_deg=200.0), "phase_margin_deg"),
])
def test_errors_name_the_parameter_not_a_flag(call, parameter):
    with pytest.raises(MarginsError) as info:
        call()
    assert str(info.value).startswith(f"{parameter}: ")
    assert "--" not in str(info.value)
    assert isinstance(info.value, ValueError)


def test_sampled_loop_beside_the_continuous(delayed):
    plain = delayed
    assert plain.sampled.rate_hz == 50.0 and plain.sampled_models.dt == pytest.approx(0.02)
    assert plain.sampled.poles.spectral_radius < 1
    data = plain.to_dict()
    assert data["sampled"]["rate_hz"] == 50.0
    assert data["sampled"]["poles"]["spectral_radius"] == plain.sampled.poles.spectral_radius
    assert data["sampled"]["computation_delay_periods"] == 1
    assert data["sampled"]["computation_delay_s"] == pytest.approx(0.02)
    assert "computation_delay_periods" not in data["continuous"]
    assert plain.continuous.computation_delay_s is None
    # a zero-order hold adds phase lag: the sampled loop has less phase margin
    for m in plain.sampled.loops:
        assert m.phase_margin_deg < plain.continuous.loop(m.name).phase_margin_deg
    table = format_report(plain)
    assert "zero-order hold at 50 Hz, computation delay 1 period (20 ms)" in table


def test_computation_delay_is_one_period_on_the_command(sampled, delayed):
    """Commanding one period late multiplies the loop by z^-1 = exp(-j w dt): the same
    gain, w dt less phase; the controller carries the four held commands."""
    prompt, late = sampled[0.0].sampled_models, delayed.sampled_models
    assert late.delay_periods == 1 and prompt.delay_periods == 0
    assert late.controller.nstates == prompt.controller.nstates + 4
    assert not late.controller.D.any() and prompt.controller.D.any()
    w = np.array([0.1, 3.0, 20.0, 150.0])
    want = np.exp(-1j * w * 0.02)[:, None, None] * freqresp(prompt.loop_input, w)
    np.testing.assert_allclose(freqresp(late.loop_input, w), want, rtol=1e-9,
                               atol=1e-9 * np.abs(want).max())
    # the delay costs phase: w_c dt at each crossover of the decoupled loops
    for m in delayed.sampled.loops:
        m0 = sampled[0.0].sampled.loop(m.name)
        assert m.phase_margin_deg < m0.phase_margin_deg


def test_delay_periods_must_be_a_count():
    for bad in (-1, 0.5, True):
        with pytest.raises(MarginsError, match=r"^delay_periods: must be an integer >= 0"):
            margin_report(load_scenario("paper", SMALL), delay_periods=bad)


@pytest.mark.parametrize("name, overrides", [
    ("paper", [*SMALL, "controller.rate_hz=50"]),
    ("paper", [*SMALL, "controller.rate_hz=50", "controller.hold_compensation=0.5"]),
    ("highway", []),
])
def test_loop_states_bound_the_linearized_loop(name, overrides):
    """The budget's count is at least the linearized loop's states, and each period of
    delay adds exactly what the linearization adds."""
    from quadland.linearization import equilibrium, sampled_models
    from quadland.margins import loop_states

    sc = load_scenario(name, overrides)
    base, per_period = loop_states(sc)
    point, rate = equilibrium(sc), float(sc.data["controller"]["rate_hz"])
    sizes = [sampled_models(sc, point, rate, d).loop_input.nstates for d in (0, 1, 3)]
    assert sizes[0] <= base
    assert sizes[1] - sizes[0] == per_period == 4 and sizes[2] - sizes[0] == 3 * per_period


def test_delay_periods_are_bounded_by_the_loop_s_size():
    """A delay line of a million periods ran out of memory after the folder was claimed;
    the bound leaves the delayed loop within MAX_LOOP_STATES."""
    from quadland.margins import MAX_LOOP_STATES, check_request, loop_states

    sc = load_scenario("highway")
    base, per_period = loop_states(sc)
    most = (MAX_LOOP_STATES - base) // per_period
    check_request(sc, None, most)
    assert base + most * per_period <= MAX_LOOP_STATES < base + (most + 1) * per_period
    for bad in (most + 1, 2_000, 1_000_000, 10**400):
        with pytest.raises(MarginsError, match=rf"^delay_periods: must be at most {most} for "
                                               rf"this loop .*, got {bad}$"):
            check_request(sc, None, bad)
    # a continuous-time loop has no delay line: the count is not used
    check_request(load_scenario("paper", SMALL), None, 1_000_000)
    with pytest.raises(MarginsError, match=r"^rbf\.nodes: the loop of 1000 nodes has 4,0"):
        check_request(load_scenario("paper", ["rbf.nodes=1000"]), None, 1)


def test_a_huge_delay_is_one_line_before_the_folder_is_claimed(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["margins", "--scenario", "highway", "--delay-periods", "1000000",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("quadland: error: --delay-periods: must be at most ")
    assert len(err.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_hold_compensation_trades_nyquist_gain_for_phase(sampled):
    """At z = -1 the extrapolation 1 + k - k/z is exactly 1 + 2k and real: with
    k = 1/2 the gain margin at the Nyquist frequency shrinks by 20 log10(2) dB,
    while the phase lost to the hold is recovered near crossover."""
    nyquist = math.pi * 50
    for cont in sampled[0.0].continuous.loops:
        at_nyquist = []
        for hold in (0.0, 0.5):
            crossings = sampled[hold].sampled.loop(cont.name).crossings
            k = [i for i, w in enumerate(crossings.gm_frequency)
                 if w == pytest.approx(nyquist, rel=1e-9)]
            assert len(k) == 1
            at_nyquist.append(crossings.gain_margin[k[0]])
        assert at_nyquist[0] / at_nyquist[1] == pytest.approx(2.0, rel=1e-9)
        lag = {h: abs(sampled[h].sampled.loop(cont.name).phase_margin_deg
                      - cont.phase_margin_deg) for h in sampled}
        assert lag[0.5] < 0.1 * lag[0.0]


# the landing loop

LANDING_LOOPS = ["thrust", "roll", "pitch", "yaw"]


@pytest.fixture(scope="module")
def landing():
    """highway at hover, a small network, 250 Hz with one period of computation delay."""
    with threadpool_limits(1):
        return margin_report(load_scenario("highway", ["rbf.nodes=3"]))


def test_landing_report_is_the_same_review(landing):
    assert landing.point.model == "landing" and landing.point.kind == "equilibrium"
    for section in (landing.continuous, landing.sampled):
        assert [m.name for m in section.loops] == LANDING_LOOPS
        assert section.stable
        assert isinstance(section.multiloop_disk, MultiloopDiskMargin)
    assert landing.continuous.rate_hz is None
    assert landing.sampled.rate_hz == 250.0
    assert landing.sampled.computation_delay_periods == 1
    assert landing.sampled.computation_delay_s == pytest.approx(0.004)
    # the plant has 16 states (deck frame, motors), the controller the step's memory
    # (6 l + 29, less the observer's two states of the z axis, which has none) and,
    # sampled, the four held commands of the delay
    assert landing.models.plant.nstates == 16
    assert landing.models.controller.nstates == 6 * 3 + 27
    assert landing.sampled_models.controller.nstates == 6 * 3 + 27 + 4
    assert landing.continuous.poles.count == 16 + 6 * 3 + 27
    # sampling and the delay cost phase in every loop
    for m in landing.sampled.loops:
        assert m.phase_margin_deg < landing.continuous.loop(m.name).phase_margin_deg
    data = landing.to_dict()
    assert data["loop_break"].startswith("plant input: the wrench [T, M_x, M_y, M_z]")
    op = data["operating_point"]
    assert op["model"] == "landing"
    assert list(op["state"])[:6] == ["x_e", "y_e", "z_e", "phi1", "theta1", "psi_e"]
    assert op["state"]["z_e"] == pytest.approx(3.0, abs=0.05)      # landing.hover_height
    assert list(op["wrench"]) == ["F_total", "M_x", "M_y", "M_z"]
    # the hover's thrust, by hand: flying level with the car at V = 50 km/h, tilted
    # theta by the body-x balance m g sin(theta) = Kt V c + Kq (V c)^2, the body-z
    # balance is T = m g c + Kt V s + Kq (V s)^2 (the drag of docs/landing.md, "Real drag
    # and thrust"); within 1 % (the disturbance's 0.1 N biases, the ground effect 3 m up)
    m, g, Kt, Kq, V = 2.0, 9.8, 0.3, 0.01225, 50 / 3.6
    th = brentq(lambda th: m * g * math.sin(th) - Kt * V * math.cos(th)
                - Kq * (V * math.cos(th)) ** 2, 0.0, 1.0)
    c, s = math.cos(th), math.sin(th)
    assert op["wrench"]["F_total"] == pytest.approx(m * g * c + Kt * V * s + Kq * (V * s) ** 2,
                                                    rel=0.01)
    assert list(data["sampled"]["loops"]) == LANDING_LOOPS
    assert data["sampled"]["computation_delay_s"] == pytest.approx(0.004)
    # the flown loop: the filter's horizon state (21) and its delay line (the packets'
    # 13 independent channels over the 50-period horizon) beside the step's memory; its
    # verdict is the review's
    assert landing.filtered.stable and landing.filtered.rate_hz == 250.0
    assert [m.name for m in landing.filtered.loops] == LANDING_LOOPS
    assert landing.filtered_models.controller.nstates == 6 * 3 + 27 + 21 + 13 * 50 + 4
    assert landing.passed == landing.filtered.passed
    assert data["verdict_from"] == ["sampled, filter in the loop"]
    assert list(data["filtered"]["loops"]) == LANDING_LOOPS
    json.dumps(data, allow_nan=False)


def test_landing_table(landing):
    table = format_report(landing)
    assert "scenario highway, hover 3 m above the pad" in table
    assert "wrench [T, M_x, M_y, M_z] into the mixer" in table
    assert "continuous-time limit of the landing step (dt -> 0)" in table
    assert "zero-order hold at 250 Hz, computation delay 1 period (4 ms)" in table
    assert "sampled, filter in the loop: the navigation filter at its steady state" in table
    for name in LANDING_LOOPS:
        assert sum(line.startswith(f"  {name} ") for line in table.splitlines()) == 3


def test_landing_refuses_a_frozen_point():
    with pytest.raises(MarginsError, match=r"^at: the landing loop is analysed at its hover"):
        margin_report(load_scenario("highway", ["rbf.nodes=3"]), at=1.0)


@pytest.mark.slow
def test_the_sampled_review_assumes_the_scenario_s_computation_delay():
    """Without delay_periods the review takes the loop kind's computation delay: a
    landing scenario's controller.delay_periods (the delay it flies), the paper's 1."""
    from quadland.margins import margin_report

    for delay in (0, 2):
        sc = load_scenario("highway", [f"controller.delay_periods={delay}"])
        report = margin_report(sc)
        assert report.sampled.computation_delay_periods == delay
        assert report.sampled.computation_delay_s == pytest.approx(delay / 250.0)
    paper = load_scenario("paper", ["rbf.nodes=3", "controller.rate_hz=100"])
    assert margin_report(paper).sampled.computation_delay_periods == 1


# ------------------------------------------------------------------ the report's repr

def _worst(section):
    """The smallest gain margin of any loop either way and the smallest phase margin,
    with where, from the loops' fields."""
    gains = [(m.gain_margin_up_db, f"{m.name} up") for m in section.loops] + \
        [(-m.gain_margin_down_db, f"{m.name} down") for m in section.loops]
    gm = min(gains, key=lambda g: g[0])
    pm = min(((m.phase_margin_deg, m.name) for m in section.loops), key=lambda p: p[0])
    return gm, pm


def _check_repr(rep: MarginReport):
    text = repr(rep)
    lines = text.splitlines()
    sections = [rep.continuous] + [s for s in (rep.sampled, rep.filtered) if s is not None]
    titles = [s.title() + (", filter in the loop" if s is rep.filtered else "")
              for s in sections]
    assert len(lines) == 2 + len(sections) and len(text) < 800
    req = rep.requirement
    assert lines[0] == (f"<MarginReport of {rep.scenario.name!r} ({rep.point.kind}): "
                        f"{'PASS' if rep.passed else 'FAIL'} against "
                        f"{req.gain_margin_db:g} dB / {req.phase_margin_deg:g} deg")
    for section, line in zip(sections, lines[1:], strict=False):
        (gm, gm_at), (pm, pm_at) = _worst(section)
        disk = section.multiloop_disk.disk
        assert f"GM {gm:.1f} dB ({gm_at})" in line and f"PM {pm:.1f} deg ({pm_at})" in line
        assert f"multiloop disk +-{20 * math.log10(disk.gain_margin[1]):.1f} dB / " \
               f"{disk.phase_margin:.1f} deg" in line
        assert ("stable," if section.stable else "UNSTABLE,") in line
        failed = [m.name for m in section.loops if not m.passed] + \
            ([] if section.multiloop_disk.passed else ["multiloop disk"])
        assert line.endswith(": pass" if section.passed else f": FAIL ({', '.join(failed)})")
    assert lines[-1] == ("  print(quadland.margins.format_report(report)) for every margin, "
                         "report.to_dict() for margins.json>")
    # the notebook's table: a header and a row per controller, the line's words in cells
    page = rep._repr_html_()
    assert page.count("<tr>") == 1 + len(sections)
    for section, title, line in zip(sections, titles, lines[1:], strict=False):
        (gm, gm_at), (pm, pm_at) = _worst(section)
        assert line.startswith(f"  {title}: ")
        for cell in (title, f"{gm:.1f} dB ({gm_at})", f"{pm:.1f} deg ({pm_at})"):
            assert f"<td>{cell}</td>" in page and cell in line


def test_repr_is_a_short_summary_of_the_fields(report, landing):
    """The continuous paper loop and the landing's three sections: a handful of lines
    (the dataclass's own repr was over 70,000 characters)."""
    for rep in (report, landing):
        _check_repr(rep)
    assert repr(landing).splitlines()[2].startswith("  sampled 250 Hz, delay 1 period: ")
    assert repr(landing).splitlines()[3].startswith(
        "  sampled 250 Hz, delay 1 period, filter in the loop: ")


def test_repr_of_a_failed_review_names_what_failed():
    """A requirement the paper's loop misses (its phase margins are 72-76 deg, its
    lower gain margins -25 to -48 dB): every loop fails, and the multiloop disk."""
    rep = _report(requirement=Requirement(30.0, 80.0))
    assert not rep.passed and rep.continuous.failed
    _check_repr(rep)
    assert repr(rep).splitlines()[0].endswith(": FAIL against 30 dB / 80 deg")


def test_the_text_ends_with_one_verdict_naming_what_it_judged(report, landing):
    """One verdict closes the text: the report's ``passed`` and the sections it judges (the
    paper's continuous loop and its sampled one; a landing's filter section alone), each
    section's own requirement line above it agreeing with its ``passed``."""
    from quadland.margins import format_report

    for rep, judged in ((report, [s for s in ("continuous", "sampled")
                                  if getattr(report, s) is not None]),
                        (landing, ["sampled, filter in the loop"])):
        text = format_report(rep).splitlines()
        assert [label for label, _ in rep.judged] == judged
        assert text[-1] == (f"verdict: {'PASS' if rep.passed else 'FAIL'} against 6 dB / "
                            f"45 deg, judged on the {' and '.join(judged)} section"
                            f"{'s' if len(judged) > 1 else ''}")
        verdicts = [line for line in text if line.startswith("  requirement ")]
        sections = [rep.continuous] + [s for s in (rep.sampled, rep.filtered) if s is not None]
        assert [v.endswith("PASS") for v in verdicts] == [s.passed for s in sections]
    failed = _report(requirement=Requirement(30.0, 80.0))
    assert format_report(failed).splitlines()[-1].startswith("verdict: FAIL against 30 dB")


@pytest.mark.parametrize("name, nodes", [("paper", 3), ("highway", 3), ("highway", 10)])
def test_loop_sizes_are_the_built_loop_s(name, nodes):
    """A kind's loop_sizes (the landing's from its layouts, without building the loop)
    are the sizes of the loop its loop_model builds."""
    from quadland.kinds import kind_of

    kind = kind_of(load_scenario(name, [f"rbf.nodes={nodes}"]))
    loop = kind.loop_model(nodes)
    assert kind.loop_sizes(nodes) == (loop.state.size, loop.held.size)


def test_a_review_is_the_same_whatever_the_caller_s_blas_threads():
    """The review sets its own BLAS threads: called under one thread and under two it
    reports the same numbers, bit for bit (a two-thread OpenBLAS changes the last bits of
    highway's margins, so without the review's own limit the two differ)."""
    sc = load_scenario("highway", ["rbf.nodes=3"])
    texts = []
    for threads in (1, 2):
        with threadpool_limits(threads):
            d = margin_report(sc).to_dict()
        texts.append(json.dumps(d, sort_keys=True))
    assert texts[0] == texts[1]
