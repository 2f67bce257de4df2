"""The ``quadland`` command line: parses arguments and calls the library.

Known errors (``QuadlandError``) are reported as one line
``quadland: error: ...`` with exit status 2 (1 for ``codegen --check``
differences); nothing is written before the inputs are validated.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from quadland.exceptions import QuadlandError

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    from quadland import __version__

    parser = argparse.ArgumentParser(
        prog="quadland",
        description="Adaptive RBFNN backstepping landing of a quadrotor on a moving vehicle.")
    parser.add_argument("--version", action="version", version=f"quadland {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    def scenario_args(p):
        p.add_argument("--scenario", default="paper", metavar="NAME|PATH",
                       help="a shipped scenario's name or a TOML file (default: paper)")
        p.add_argument("--set", dest="overrides", action="append", default=[],
                       metavar="SECTION.KEY=VALUE",
                       help="override one scenario value (repeatable); the value is TOML")

    sim = sub.add_parser("simulate", help="simulate a scenario and write its outputs",
                         description="Simulate a scenario's closed loop; write trajectory.csv, "
                                     "summary.json and the figures.")
    scenario_args(sim)
    sim.add_argument("--out", type=Path, metavar="DIR",
                     help="output folder (default: a new folder named after the scenario "
                          "and the time)")
    sim.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    sim.set_defaults(handler=_run_simulate)

    cg = sub.add_parser("codegen", help="regenerate the C code of generated/",
                        description="Write the generated C code, byte for byte reproducible.")
    cg.add_argument("--out", type=Path, metavar="DIR",
                    help="output folder (default: the project's generated/)")
    cg.add_argument("--check", action="store_true",
                    help="regenerate into a temporary folder, print a unified diff and "
                         "exit 1 where DIR differs")
    cg.set_defaults(handler=_run_codegen)

    mg = sub.add_parser("margins", help="linearize the closed loop and report its margins",
                        description="Stability margins of the linearized closed loop.")
    scenario_args(mg)
    mg.add_argument("--at", type=float, metavar="T", default=None,
                    help="linearize about the simulated state at time T (s) instead of the "
                         "closed loop's equilibrium")
    mg.add_argument("--out", type=Path, metavar="DIR",
                    help="output folder (default: a new folder named after the scenario "
                         "and the time)")
    mg.add_argument("--gain-margin-db", type=float, default=6.0, metavar="DB",
                    help="required gain margin (default: 6 dB)")
    mg.add_argument("--phase-margin-deg", type=float, default=45.0, metavar="DEG",
                    help="required phase margin (default: 45 deg)")
    mg.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    mg.set_defaults(handler=_run_margins)
    return parser


def _run_simulate(args) -> int:
    from quadland.run import run_simulation

    out = run_simulation(args.scenario, args.overrides, args.out, plots=not args.no_plots)
    print(f"quadland: wrote {out}")
    return 0


def _run_codegen(args) -> int:
    from quadland.codegen import main as codegen_main

    return codegen_main(out=args.out, check=args.check)


def _run_margins(args) -> int:
    from quadland.margins import main as margins_main

    return margins_main(args)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``quadland`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.handler(args)
    except QuadlandError as exc:
        print(f"quadland: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("quadland: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
