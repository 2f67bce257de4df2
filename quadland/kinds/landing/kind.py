"""The 6-DOF landing on a moving deck as a loop kind."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from quadland.engine.envelope import Envelope
from quadland.engine.plan import SimulationPlan
from quadland.engine.result import SimulationResult
from quadland.exceptions import MarginsError, ScenarioError
from quadland.kinds.base import LoopKind
from quadland.kinds.landing import flight, report, simulate
from quadland.scenario import Scenario
from quadland.schema import LANDING_SCHEMA
from quadland_symbolic.codegen import LandingDefaults
from quadland_symbolic.landing.loop import landing_loop, landing_loop_state
from quadland_symbolic.landing.quadrotor import COMMAND
from quadland_symbolic.landing.signals import LANDING_TRAJECTORY
from quadland_symbolic.loop import LoopModel

if TYPE_CHECKING:  # python-control (and matplotlib with it) loads on first analysis
    from quadland.linear import LinearModels, OperatingPoint

__all__ = ["LandingKind", "LANDING"]


class LandingKind(LoopKind):
    """A quadrotor landing on a moving deck (``scenario.model = "landing"``).

    The 6-DOF plant with motor lag, a vehicle and its deck, the guidance and the
    landing step at ``controller.rate_hz``, until touchdown and the ride on the
    deck; broken at the wrench into the mixer for its margins, hovering over the
    pad.
    """

    name = "landing"
    summary_line = "a 6-DOF quadrotor landing on a moving deck (car, ship)"
    schema = LANDING_SCHEMA
    default_scenario = flight.LANDING_SCENARIO
    codegen_part = "landing"
    metrics = report.LANDING_METRICS
    trajectory = LANDING_TRAJECTORY
    loop_break = ("plant input: the wrench [T, M_x, M_y, M_z] into the mixer, L = -K P, "
                  "negative feedback")
    can_animate = True

    def loop_model(self, l: int) -> LoopModel:
        return landing_loop(l)

    def loop_sizes(self, l: int) -> tuple[int, int]:
        # the layouts landing_loop(l) is built on, without building its functions (0.1 s)
        return landing_loop_state(l).size, COMMAND.size

    def plan(self, scenario: Scenario) -> SimulationPlan:
        return simulate.landing_plan(scenario)

    def check(self, scenario: Scenario) -> None:
        simulate.check_landing_plan(scenario)

    def envelope(self, scenario: Scenario) -> Envelope:
        return simulate.landing_envelope(scenario)

    def simulate(self, scenario: Scenario) -> SimulationResult:
        return simulate.simulate_landing(scenario)

    def summary(self, result: SimulationResult) -> dict:
        return report.landing_summary(result)

    def io_values(self, scenario: Scenario) -> dict[str, Any]:
        from quadland.kinds.landing.sensed import sensors_enabled
        from quadland.kinds.landing.values import landing_values
        from quadland_symbolic.landing.plant import LANDING_PLANT_STATE
        from quadland_symbolic.landing.quadrotor import QUAD6_STATE

        lv = landing_values(scenario)
        d = scenario.data
        hover = QUAD6_STATE.unpack(LANDING_PLANT_STATE.unpack(lv.xp0)["x1q"])["F"]
        # the sampled loop on perfect sensors, as simulate_landing flies it without them
        sampled = {"xc0": lv.xc0, "pc": lv.pc, "uh0": hover,
                   "dt": 1.0 / d["controller"]["rate_hz"],
                   "delay": d["controller"]["delay_periods"],
                   "substeps": d["simulation"]["rk_steps_per_interval"],
                   "break_rates": (d["simulation"]["output_rate_hz"],
                                   d["disturbance"]["sample_rate_hz"]),
                   "sensed": sensors_enabled(scenario)}
        return {"x0": None, "p": None, "xp0": lv.xp0, "pp": lv.pp, "sampled": sampled}

    def result_lines(self, summary: Mapping[str, Any]) -> list[str]:
        return report.landing_result_lines(summary)

    def run_metrics(self, result: SimulationResult) -> dict[str, float | None]:
        return report.landing_run_metrics(result)

    def judge(self, result: SimulationResult, metrics: Mapping[str, float | None],
              limits: Mapping[str, float]) -> list[str]:
        if metrics["touchdown_time"] is None:
            return [f"no touchdown by t = {result['t'][-1]:.4g} s"]
        if metrics.get("secured") is None:              # welded: no gear contact to judge
            limits = {k: v for k, v in limits.items() if k not in report.GEAR_METRICS}
        return super().judge(result, metrics, limits) + report.gear_violations(result, metrics)

    def figures(self, result: SimulationResult) -> dict[str, Any]:
        from quadland.plots.landing import landing_figures

        return landing_figures(result, report.touchdown_limits(result.scenario))

    def animation(self, result: SimulationResult, path: Path) -> Path:
        from quadland.plots.animation import landing_animation

        return landing_animation(result, path, limits=report.touchdown_limits(result.scenario))

    def operating_point(self, scenario: Scenario, at: float | None = None) -> OperatingPoint:
        if at is not None:
            self.check_operating_time(scenario, at)
        from quadland.kinds.landing import linearize

        return linearize.hover_equilibrium(scenario)

    def check_operating_time(self, scenario: Scenario, at: float) -> None:
        raise MarginsError("at: the landing loop is analysed at its hover equilibrium only; "
                           "a frozen state applies to the paper's loop")

    def linear_models(self, scenario: Scenario, point: OperatingPoint) -> LinearModels:
        from quadland.kinds.landing import linearize

        return linearize.hover_linear_models(scenario, point)

    def sampled_models(self, scenario: Scenario, point: OperatingPoint, rate_hz: float,
                       delay_periods: int = 1) -> LinearModels:
        from quadland.kinds.landing import linearize

        return linearize.hover_sampled_models(scenario, point, rate_hz, delay_periods)

    def filtered_models(self, scenario: Scenario, point: OperatingPoint, rate_hz: float,
                        delay_periods: int = 1) -> LinearModels | None:
        """The sampled loop with the navigation filter in it; None unless the scenario
        flies its sensors (``sensors.enabled``)."""
        from quadland.kinds.landing.sensed import sensors_enabled

        if not sensors_enabled(scenario):
            return None
        from quadland.kinds.landing import filter_loop

        return filter_loop.hover_filter_models(scenario, point, rate_hz, delay_periods)

    def describe_point(self, scenario: Scenario, point: OperatingPoint
                       ) -> tuple[list[str], str]:
        op = point.to_dict()
        s, v = op["state"], op["vehicle"]
        hover = scenario.data["landing"]["hover_height"]
        lines = [f"quadland margins: scenario {scenario.name}, hover {hover:g} m above "
                 "the pad (steady motion in the deck frame; deck still, mean wind, constant "
                 "disturbance)",
                 f"  x_e = {s['x_e']:.3g} m, y_e = {s['y_e']:.3g} m, z_e = {s['z_e']:.4g} m, "
                 f"phi = {s['phi1']:.3g} rad, theta = {s['theta1']:.3g} rad, "
                 f"psi_e = {s['psi_e']:.3g} rad, T = {point.u[0]:.4g} N",
                 f"  vehicle u2 = {v['u2']:.4g} m/s, r2 = {v['r2']:.4g} rad/s; residual "
                 f"{op['residual']:.2g}",
                 "  loop broken at the wrench [T, M_x, M_y, M_z] into the mixer, L = -K P; "
                 "each loop with the others closed", ""]
        return lines, "continuous-time limit of the landing step (dt -> 0)"

    def sensor_channels(self, scenario: Scenario) -> dict[str, tuple[tuple[str, ...], float]]:
        from quadland.kinds.landing.sensor_break import sensor_channels

        return sensor_channels(scenario)

    def computation_delay(self, scenario: Scenario) -> int:
        return int(scenario.data["controller"]["delay_periods"])

    def codegen_defaults(self, scenario: Scenario) -> LandingDefaults:
        if scenario.data["gear"]["welded"]:
            raise ScenarioError("gear.welded: the pure-C example flies the gear's contact; "
                                "generate it from a scenario with gear.welded = false")
        if scenario.data["estimator"]["handover_lockout_gnss"]:
            raise ScenarioError("estimator.handover_lockout_gnss: the pure-C example's "
                                "estimator_init leaves the refusal streaks at 0; generate it "
                                "from a scenario with handover_lockout_gnss = 0")
        return flight.landing_defaults(scenario)


#: The landing loop kind.
LANDING = LandingKind()
