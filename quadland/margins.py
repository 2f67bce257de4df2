"""The ``quadland margins`` command: a flight-control margin review.

Linearizes the closed loop at an operating point (the equilibrium, or the
simulated state at ``--at T``), breaks it at the plant input u, and reports
per loop (altitude, roll, pitch, yaw) the classical margins with the other
loops closed, the loop-at-a-time and multiloop disk margins, the closed-loop
poles, and pass or fail against a gain and phase requirement. With
``controller.rate_hz > 0`` the sampled-data loop is reported beside the
continuous one.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
import time
from pathlib import Path

import numpy as np

from quadland.analysis import (FrequencyResponse, allmargin, closed_loop_poles, diskmargin,
                               frequency_grid, loop_at_a_time)
from quadland.exceptions import MarginsError
from quadland.linearize import (LOOP_NAMES, LinearModels, OperatingPoint, equilibrium,
                                frozen_point, linear_models, sampled_models)
from quadland.output import write_bytes_atomic, write_text_atomic
from quadland.scenario import Scenario, load_scenario

__all__ = ["Requirement", "MarginReport", "margin_report", "format_report", "render_figures",
           "FIGURES", "main"]

#: Figures written by the command.
FIGURES = ("bode.png", "nyquist.png", "sigma.png", "poles.png")


@dataclasses.dataclass(frozen=True)
class Requirement:
    """Margin requirement of the review.

    Attributes
    ----------
    gain_margin_db : float
        dB, required gain margin in both directions.
    phase_margin_deg : float
        deg, required phase margin.
    """

    gain_margin_db: float = 6.0
    phase_margin_deg: float = 45.0

    def __post_init__(self):
        if not (math.isfinite(self.gain_margin_db) and self.gain_margin_db >= 0):
            raise MarginsError(f"--gain-margin-db must be a finite number >= 0, "
                               f"got {self.gain_margin_db}")
        if not (math.isfinite(self.phase_margin_deg) and 0 <= self.phase_margin_deg < 180):
            raise MarginsError(f"--phase-margin-deg must lie in [0, 180), "
                               f"got {self.phase_margin_deg}")


@dataclasses.dataclass(frozen=True)
class MarginReport:
    """Everything the command prints, writes and plots.

    Attributes
    ----------
    scenario : Scenario
    point : OperatingPoint
    models : LinearModels
        Continuous-time models.
    sampled : LinearModels or None
        Zero-order-hold models at ``controller.rate_hz``, if > 0.
    poles : ndarray
        Poles of the continuous closed loop, 1/s.
    data : dict
        The JSON-ready results (see :func:`margin_report`).
    """

    scenario: Scenario
    point: OperatingPoint
    models: LinearModels
    sampled: LinearModels | None
    poles: np.ndarray
    data: dict


def _db(ratio: float) -> float:
    return 20.0 * math.log10(ratio) if ratio > 0 else -math.inf


def _finite(x):
    """JSON value: infinities become None (no crossing, margin unbounded)."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def _pole_summary(poles: np.ndarray, dt: float, count: int = 3) -> dict:
    s = np.log(poles.astype(complex)) / dt if dt else poles.astype(complex)
    upper = s[s.imag >= -1e-12]
    slow = upper[np.argsort(-upper.real)][:count]
    osc = upper[upper.imag > 1e-9]
    zeta = -osc.real / np.abs(osc)
    least = osc[np.argsort(zeta)][:count]

    def row(p):
        wn = abs(p)
        return dict(real=float(p.real), imag=float(p.imag), natural_frequency=float(wn),
                    damping=float(-p.real / wn) if wn > 0 else 1.0,
                    time_constant=float(-1.0 / p.real) if p.real < 0 else math.inf)

    out = dict(count=int(poles.size), slowest=[row(p) for p in slow],
               least_damped=[row(p) for p in least])
    if dt:
        out["spectral_radius"] = float(np.max(np.abs(poles)))
    return out


def _loop_rows(L, req: Requirement) -> tuple[dict, np.ndarray]:
    classical = allmargin(L)
    per_loop, multi = diskmargin(L)
    loops = {}
    for name, cm, dm in zip(LOOP_NAMES, classical, per_loop):
        gms = np.asarray(cm.gain_margin, dtype=float)
        up, down = gms[gms >= 1.0], gms[gms < 1.0]
        gm_up = float(up.min()) if up.size else math.inf
        gm_down = float(down.max()) if down.size else 0.0
        w_up = cm.gm_frequency[int(np.flatnonzero(gms == gm_up)[0])] if up.size else None
        w_down = cm.gm_frequency[int(np.flatnonzero(gms == gm_down)[0])] if down.size else None
        if cm.phase_margin:
            k = int(np.argmin(cm.phase_margin))
            pm, w_pm = cm.phase_margin[k], cm.pm_frequency[k]
            j = int(np.argmin(cm.delay_margin))
            dmg, w_dm = cm.delay_margin[j], cm.dm_frequency[j]
        else:
            pm, w_pm, dmg, w_dm = math.inf, None, math.inf, None
        ok = (cm.stable and _db(gm_up) >= req.gain_margin_db
              and -_db(gm_down) >= req.gain_margin_db and pm >= req.phase_margin_deg)
        loops[name] = dict(
            gain_margin_up_db=_db(gm_up), gain_margin_up_frequency=w_up,
            gain_margin_down_db=_db(gm_down), gain_margin_down_frequency=w_down,
            phase_margin_deg=pm, crossover_frequency=w_pm,
            delay_margin_s=dmg, delay_margin_frequency=w_dm,
            all_crossings=dict(gain_margin=list(cm.gain_margin),
                               gm_frequency=list(cm.gm_frequency),
                               phase_margin=list(cm.phase_margin),
                               pm_frequency=list(cm.pm_frequency),
                               delay_margin=list(cm.delay_margin),
                               dm_frequency=list(cm.dm_frequency)),
            disk=dataclasses.asdict(dm), stable=cm.stable, passed=bool(ok))
    multi_ok = (_db(multi.gain_margin[1]) >= req.gain_margin_db
                and multi.phase_margin >= req.phase_margin_deg)
    stable = bool(classical[0].stable)
    poles = closed_loop_poles(L)
    return dict(stable=stable, loops=loops,
                multiloop_disk=dict(dataclasses.asdict(multi), passed=bool(multi_ok)),
                passed=bool(stable and all(v["passed"] for v in loops.values())),
                poles=_pole_summary(poles, float(L.dt) if L.dt else 0.0)), poles


def margin_report(scenario: Scenario, at: float | None = None,
                  requirement: Requirement = Requirement()) -> MarginReport:
    """Linearize a scenario's loop and compute the margin review.

    Parameters
    ----------
    scenario : Scenario
    at : float, optional
        s: linearize about the simulated state at this time instead of
        the equilibrium.
    requirement : Requirement

    Returns
    -------
    MarginReport
        ``data`` holds ``operating_point``, ``requirement``, ``continuous``
        and (with ``controller.rate_hz > 0``) ``sampled``, each with per-loop
        classical and disk margins, the multiloop disk margin, the
        closed-loop poles and the verdicts.
    """
    if at is not None and not (math.isfinite(at) and at >= 0):
        raise MarginsError(f"--at must be a finite time >= 0 s, got {at}")
    point = equilibrium(scenario) if at is None else frozen_point(scenario, at)
    models = linear_models(scenario, point)
    cont, poles = _loop_rows(models.loop_input, requirement)
    data = dict(scenario=scenario.name, overrides=list(scenario.overrides),
                operating_point=point.to_dict(),
                requirement=dataclasses.asdict(requirement),
                loop_break="plant input u (eq. 6), L = -K P, negative feedback",
                continuous=cont)
    rate = float(scenario.data["controller"]["rate_hz"])
    sampled = None
    if rate > 0:
        sampled = sampled_models(scenario, point, rate)
        data["sampled"], _ = _loop_rows(sampled.loop_input, requirement)
        data["sampled"]["rate_hz"] = rate
    return MarginReport(scenario, point, models, sampled, poles, data)


def _fmt(x, spec=".3g", none="-"):
    if x is None:
        return none
    if isinstance(x, float) and math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return format(x, spec)


def _table(section: dict, title: str, req: dict) -> list[str]:
    lines = [title,
             f"  {'loop':<9}{'GM up':>8}{'GM down':>9}{'PM':>8}{'w_c':>9}{'DM':>9}"
             f"{'w_180':>9}{'disk a':>8}{'disk GM':>9}{'disk PM':>9}  verdict",
             f"  {'':<9}{'dB':>8}{'dB':>9}{'deg':>8}{'rad/s':>9}{'s':>9}"
             f"{'rad/s':>9}{'':>8}{'+-dB':>9}{'deg':>9}"]
    for name, r in section["loops"].items():
        d = r["disk"]
        tighter_up = r["gain_margin_up_db"] <= -r["gain_margin_down_db"]
        w180 = r["gain_margin_up_frequency" if tighter_up else "gain_margin_down_frequency"]
        lines.append(
            f"  {name:<9}{_fmt(r['gain_margin_up_db'], '.1f'):>8}"
            f"{_fmt(r['gain_margin_down_db'], '.1f'):>9}{_fmt(r['phase_margin_deg'], '.1f'):>8}"
            f"{_fmt(r['crossover_frequency'], '.3g'):>9}{_fmt(r['delay_margin_s'], '.3g'):>9}"
            f"{_fmt(w180, '.3g'):>9}{d['disk_margin']:>8.3f}"
            f"{_fmt(_db(d['gain_margin'][1]), '.1f'):>9}{d['phase_margin']:>9.1f}"
            f"  {'pass' if r['passed'] else 'FAIL'}")
    m = section["multiloop_disk"]
    lines.append(f"  multiloop disk margin: alpha = {m['disk_margin']:.3f}, gain "
                 f"[{m['gain_margin'][0]:.3f}, {_fmt(m['gain_margin'][1], '.3f')}] "
                 f"(+-{_fmt(_db(m['gain_margin'][1]), '.1f')} dB), phase +-"
                 f"{m['phase_margin']:.1f} deg, at {m['frequency']:.3g} rad/s: "
                 f"{'pass' if m['passed'] else 'FAIL'}")
    p = section["poles"]
    slow = ", ".join(f"{q['real']:.4g}{q['imag']:+.4g}j" for q in p["slowest"])
    least = ", ".join(f"{q['real']:.4g}{q['imag']:+.4g}j (zeta {q['damping']:.3f})"
                      for q in p["least_damped"]) or "none (all real)"
    lines.append(f"  closed loop ({p['count']} states): "
                 f"{'stable' if section['stable'] else 'UNSTABLE'}")
    lines.append(f"  slowest poles (s-plane): {slow}")
    lines.append(f"  least damped poles:      {least}")
    verdict = "PASS" if section["passed"] else "FAIL"
    lines.append(f"  requirement {req['gain_margin_db']:g} dB / {req['phase_margin_deg']:g} deg "
                 f"on every loop: {verdict}")
    return lines


def format_report(report: MarginReport) -> str:
    """The readable table the command prints."""
    d = report.data
    op = d["operating_point"]
    where = ("equilibrium (steady motion, constant disturbance)" if op["kind"] == "equilibrium"
             else f"frozen simulated state at t = {op['time_s']:g} s")
    s = op["state"]
    lines = [f"quadland margins: scenario {d['scenario']}, {where}",
             f"  z_e = {s['z1'] - op['vehicle']['z2']:.4g} m, phi = {s['phi1']:.3g} rad, "
             f"theta = {s['theta1']:.3g} rad, psi_e = {s['psi_e']:.3g} rad, "
             f"vehicle r2 = {op['vehicle']['r2']:.4g} rad/s, residual {op['residual']:.2g}",
             "  loop broken at the plant input u (eq. 6), L = -K P; each loop with the "
             "others closed", ""]
    lines += _table(d["continuous"], "continuous-time controller", d["requirement"])
    if "sampled" in d:
        lines += [""] + _table(d["sampled"], f"sampled-data controller, zero-order hold at "
                                             f"{d['sampled']['rate_hz']:g} Hz",
                               d["requirement"])
    return "\n".join(lines) + "\n"


def render_figures(report: MarginReport) -> dict[str, bytes]:
    """PNG bytes of ``FIGURES``: Bode and Nyquist per loop, sigma of S and T, pole map."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    L = report.models.loop_input
    resp = FrequencyResponse(L)
    omega = frequency_grid(resp, points_per_decade=30, extra_poles=report.poles)
    G = resp(omega)
    lc = loop_at_a_time(G)
    ld = wd = None
    if report.sampled is not None:
        rd = FrequencyResponse(report.sampled.loop_input)
        wd = omega[omega < math.pi * report.sampled.dt ** -1]
        ld = loop_at_a_time(rd(wd))
    out = {}

    def png(fig):
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110)
        plt.close(fig)
        return buf.getvalue()

    fig, ax = plt.subplots(2, 4, figsize=(15, 6.5), sharex=True)
    for i, name in enumerate(LOOP_NAMES):
        ax[0, i].semilogx(omega, 20 * np.log10(np.abs(lc[:, i])), label="continuous")
        ax[1, i].semilogx(omega, np.degrees(np.unwrap(np.angle(lc[:, i]))))
        if ld is not None:
            ax[0, i].semilogx(wd, 20 * np.log10(np.abs(ld[:, i])), "--", label="sampled")
            ax[1, i].semilogx(wd, np.degrees(np.unwrap(np.angle(ld[:, i]))), "--")
        ax[0, i].axhline(0, color="k", lw=0.6)
        ax[0, i].set_title(f"{name} loop (others closed)")
        ax[1, i].set_xlabel("frequency [rad/s]")
        ax[0, i].grid(True, which="both", alpha=0.3)
        ax[1, i].grid(True, which="both", alpha=0.3)
    ax[0, 0].set_ylabel("|L| [dB]")
    ax[1, 0].set_ylabel("arg L [deg]")
    ax[0, 0].legend()
    fig.tight_layout()
    out["bode.png"] = png(fig)

    fig, ax = plt.subplots(2, 2, figsize=(10, 9))
    t = np.linspace(0, 2 * np.pi, 200)
    for i, (name, a) in enumerate(zip(LOOP_NAMES, ax.ravel())):
        for vals, style in ((lc[:, i], "-"), (None if ld is None else ld[:, i], "--")):
            if vals is None:
                continue
            a.plot(vals.real, vals.imag, style, color="C0" if style == "-" else "C1")
            a.plot(vals.real, -vals.imag, style, color="C0" if style == "-" else "C1", alpha=0.35)
        a.plot(np.cos(t), np.sin(t), "k:", lw=0.6)
        a.plot([-1], [0], "r+", ms=12)
        a.set_xlim(-3, 2)
        a.set_ylim(-2.5, 2.5)
        a.set_aspect("equal")
        a.set_title(f"{name} loop: Nyquist (zoom on -1)")
        a.grid(True, alpha=0.3)
    fig.tight_layout()
    out["nyquist.png"] = png(fig)

    S = np.linalg.inv(np.eye(G.shape[-1]) + G)
    sS = np.linalg.svd(S, compute_uv=False)
    sT = np.linalg.svd(np.eye(G.shape[-1]) - S, compute_uv=False)
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
    for a, sv, name in ((ax[0], sS, "S = (I + L)^-1"), (ax[1], sT, "T = I - S")):
        a.semilogx(omega, 20 * np.log10(sv))
        a.set_title(f"singular values of {name} at the plant input")
        a.set_xlabel("frequency [rad/s]")
        a.grid(True, which="both", alpha=0.3)
    ax[0].set_ylabel("sigma [dB]")
    fig.tight_layout()
    out["sigma.png"] = png(fig)

    p = report.poles
    fig, ax = plt.subplots(1, 2, figsize=(12, 5))
    for a, zoom in zip(ax, (False, True)):
        a.plot(p.real, p.imag, "x")
        a.axvline(0, color="k", lw=0.6)
        a.set_xlabel("Re [1/s]")
        a.set_ylabel("Im [rad/s]")
        a.grid(True, alpha=0.3)
        if zoom:
            a.set_xlim(-0.5, 0.05)
            a.set_ylim(-0.3, 0.3)
            a.set_title("zoom: the slow adaptive and translational poles")
        else:
            a.set_title(f"closed-loop poles ({p.size})")
    fig.tight_layout()
    out["poles.png"] = png(fig)
    return out


def _default_out(scenario: Scenario) -> Path:
    return Path(f"{scenario.name}-margins-{time.strftime('%Y%m%d-%H%M%S')}")


def main(args) -> int:
    """Run ``quadland margins`` from parsed arguments; returns the exit status."""
    start = time.perf_counter()
    requirement = Requirement(args.gain_margin_db, args.phase_margin_deg)
    scenario = load_scenario(args.scenario, args.overrides)
    out = Path(args.out) if args.out is not None else _default_out(scenario)
    if out.exists() and not out.is_dir():
        raise MarginsError(f"--out {out}: exists and is not a folder")
    report = margin_report(scenario, args.at, requirement)
    figures = {} if args.no_plots else render_figures(report)
    data = dict(report.data, runtime_s=time.perf_counter() - start)
    text = json.dumps(_finite(data), indent=2) + "\n"
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "margins.json", text)
    for name, blob in figures.items():
        write_bytes_atomic(out / name, blob)
    print(format_report(report), end="")
    print(f"quadland: wrote {out} ({time.perf_counter() - start:.1f} s)")
    return 0
