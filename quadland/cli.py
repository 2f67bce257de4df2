"""The ``quadland`` command line: parses arguments and calls the library.

Only this module knows flags and file names. Known errors
(``QuadlandError``) are reported as one line ``quadland: error: ...``; a
library message that starts with one of its parameter names (``"at: must
be ..."``) is shown with the flag that sets it (``"--at: must be ..."``).

Exit status: 0 success; 1 a check failed (``codegen --check`` differences,
``margins`` below the requirement); 2 bad input (scenario, override, flag,
output folder, budget), nothing written; 3 the simulated flight failed (the
trajectory up to the failure is written, marked failed); 4 a campaign or
envelope stopped before its end (its finished runs are kept; run it again
to resume); 130 interrupted (a campaign's or envelope's runs are kept too).
"""

from __future__ import annotations

import argparse
import errno
import logging
import os
import sys
import warnings
from pathlib import Path

from quadland import interrupt
from quadland.exceptions import CampaignStopped, QuadlandError, SimulationError

__all__ = ["main", "build_parser", "UsageError"]

#: Flag of each library parameter that a command passes on from one.
_FLAGS = {"at": "--at", "out": "--out", "gain_margin_db": "--gain-margin-db",
          "phase_margin_deg": "--phase-margin-deg", "animate": "--animate", "runs": "--runs",
          "workers": "--workers", "scheduler": "--scheduler", "scenario": "--scenario",
          "delay_periods": "--delay-periods", "axis": "--axis",
          "runs_per_cell": "--runs-per-cell", "hold": "--hold", "polar": "--polar"}


class UsageError(QuadlandError, ValueError):
    """A command line that does not parse: an unknown flag, a value of the wrong type."""


class _Parser(argparse.ArgumentParser):
    """An argument parser that reports a bad command line as :class:`UsageError`.

    argparse prints its usage and a second line, then exits; quadland's
    promise is one line ``quadland: error: ...`` naming the flag, which
    :func:`main` prints. Every subcommand's parser is of this class too
    (``add_subparsers`` uses the parent's class).
    """

    def error(self, message: str):
        raise UsageError(_usage_message(message, self.prog))

    def parse_args(self, args=None, namespace=None):
        """As argparse's, with an unknown argument blamed on its subcommand's help."""
        parsed, extra = self.parse_known_args(args, namespace)
        if extra:
            prog = " ".join(filter(None, (self.prog, getattr(parsed, "command", None))))
            raise UsageError(f"unrecognized arguments: {' '.join(extra)} (see {prog} --help)")
        return parsed


def _usage_message(message: str, prog: str) -> str:
    """argparse's message as quadland's one line, naming the flag first."""
    if message.startswith("the following arguments are required: COMMAND"):
        return f"a command is required: {_COMMANDS} (see quadland --help)"
    if message.startswith("argument COMMAND: invalid choice: "):
        given = message.removeprefix("argument COMMAND: invalid choice: ").split(" (")[0]
        return f"unknown command {given}: the commands are {_COMMANDS} (see quadland --help)"
    if message.startswith("argument "):             # "argument --runs: ..."
        return message.removeprefix("argument ")
    if message.startswith("unrecognized arguments: "):
        return f"{message} (see {prog} --help)"
    return message


#: The subcommands, as the messages list them.
_COMMANDS = "simulate, codegen, margins, campaign or envelope"


def _integer(text: str) -> int:
    """An integer flag's value (argparse shows the message after the flag)."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None


def _number(text: str) -> float:
    """A number flag's value."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand.

    A command line that does not parse raises :class:`UsageError` (one
    line naming the flag) instead of printing argparse's usage and exiting;
    ``--help`` and ``--version`` print and exit as usual.
    """
    from quadland import __version__
    from quadland.scenario import scenario_names

    parser = _Parser(
        prog="quadland",
        description="Adaptive RBFNN backstepping landing of a quadrotor on a moving vehicle.",
        epilog=f"shipped scenarios: {', '.join(scenario_names())} (quadland scenarios "
               "describes them)")
    parser.add_argument("--version", action="version", version=f"quadland {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for add in (_simulate_parser, _codegen_parser, _margins_parser, _campaign_parser,
                _envelope_parser, _scenarios_parser):
        add(sub)
    return parser


def _scenarios_parser(sub) -> None:
    sc = sub.add_parser("scenarios", help="list the shipped scenarios",
                        description="The shipped scenarios: name, model and description, "
                                    "one line each.")
    sc.set_defaults(handler=_run_scenarios)


def _run_scenarios(args) -> int:
    from quadland.scenario import load_scenario, scenario_names

    rows = []
    for name in scenario_names():
        sc = load_scenario(name)
        rows.append((name, sc.model, sc.data["scenario"].get("description", "")))
    width = max(len(r[0]) for r in rows)
    for name, model, text in rows:
        print(f"{name:<{width}}  {model:<8} {text}")
    return 0


def _scenario_args(p) -> None:
    p.add_argument("--scenario", default="paper", metavar="NAME|PATH",
                   help="a shipped scenario's name (quadland scenarios lists them) or a TOML "
                        "file (default: paper)")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="SECTION.KEY=VALUE",
                   help="override one scenario value (repeatable); the value is TOML")


def _out_arg(p, what: str = "output folder") -> None:
    p.add_argument("--out", type=Path, metavar="DIR",
                   help=f"{what} (default: a new folder named after the scenario and the time)")


def _simulate_parser(sub) -> None:
    sim = sub.add_parser("simulate", help="simulate a scenario and write its outputs",
                         description="Simulate a scenario's closed loop; write trajectory.csv, "
                                     "summary.json and the figures.")
    _scenario_args(sim)
    _out_arg(sim)
    sim.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    sim.add_argument("--animate", action="store_true",
                     help="also write landing.gif, an animation of the landing (landing "
                          "scenarios)")
    sim.set_defaults(handler=_run_simulate)


def _codegen_parser(sub) -> None:
    cg = sub.add_parser("codegen", help="regenerate the C code of generated/",
                        description="Write the generated C code for a scenario, byte for byte "
                                    "reproducible.")
    _scenario_args(cg)
    cg.add_argument("--out", type=Path, metavar="DIR",
                    help="output folder (default: the source checkout's generated/, which "
                         "holds the paper and highway scenarios' code only)")
    cg.add_argument("--check", action="store_true",
                    help="regenerate into a temporary folder, print a unified diff and "
                         "exit 1 where DIR differs")
    cg.set_defaults(handler=_run_codegen)


def _margins_parser(sub) -> None:
    from quadland.margins import Requirement

    mg = sub.add_parser("margins", help="linearize the closed loop and report its margins",
                        description="Stability margins of the linearized closed loop.")
    _scenario_args(mg)
    mg.add_argument("--at", type=_number, metavar="T", default=None,
                    help="linearize about the simulated state at time T (s) instead of the "
                         "closed loop's equilibrium (paper scenarios)")
    _out_arg(mg)
    mg.add_argument("--gain-margin-db", type=_number, default=Requirement.gain_margin_db,
                    metavar="DB", help="required gain margin (default: %(default)g dB)")
    mg.add_argument("--phase-margin-deg", type=_number, default=Requirement.phase_margin_deg,
                    metavar="DEG", help="required phase margin (default: %(default)g deg)")
    mg.add_argument("--delay-periods", type=_integer, default=None, metavar="N",
                    help="control periods from sampling to commanding in the sampled loop "
                         "(default: a landing scenario's controller.delay_periods; "
                         "1 for the paper's loop)")
    mg.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    mg.add_argument("--campaign", action="store_true",
                    help="review every draw of the scenario's [campaign] table, as "
                         "quadland campaign flies them: the distribution and the worst draws")
    mg.add_argument("--runs", type=_integer, metavar="N",
                    help="with --campaign: draws 0 .. N-1 (default: the table's campaign.runs)")
    mg.set_defaults(handler=_run_margins)


def _campaign_parser(sub) -> None:
    cp = sub.add_parser("campaign", help="fly a scenario's Monte Carlo campaign",
                        description="Fly the dispersed runs of a scenario's [campaign] table "
                                    "on every core or a Dask cluster; write runs.csv, "
                                    "summary.json and the figures. Running again into the same "
                                    "folder flies only the missing runs.")
    _scenario_args(cp)
    cp.add_argument("--runs", type=_integer, metavar="N",
                    help="number of runs (default: the table's campaign.runs)")
    _campaign_args(cp, "campaign folder")
    cp.set_defaults(handler=_run_campaign)


def _campaign_args(p, what: str) -> None:
    _out_arg(p, what)
    p.add_argument("--workers", type=_integer, metavar="K",
                   help="local processes (default: one per core; 1: in this process)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run on the dask.distributed scheduler at ADDRESS (tcp://HOST:PORT) "
                        "instead of local processes")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG figures")


def _envelope_parser(sub) -> None:
    ev = sub.add_parser("envelope", help="map the success probability over two scenario keys",
                        description="Fly a grid of two keys, each cell a campaign of the "
                                    "scenario's [campaign] dispersions; write runs.csv, "
                                    "envelope.json and envelope.png (resumable as a campaign).")
    _scenario_args(ev)
    ev.add_argument("--axis", action="append", default=[], metavar="KEY=LO:HI:N",
                    help="N values of a key (section.key, section.key[i], "
                         "wind.over_deck_speed or _direction_deg) from LO to HI; twice")
    ev.add_argument("--runs-per-cell", type=_integer, metavar="K",
                    help="runs in each cell (default: the table's campaign.runs)")
    ev.add_argument("--seed", type=_integer, help="the campaign seed (campaign.seed)")
    ev.add_argument("--hold", action="append", default=[], metavar="KEY",
                    help="hold a dispersed key at the scenario's value (repeatable)")
    ev.add_argument("--polar", action="store_true", help="a polar map: the axis in degrees "
                                                         "as the angle")
    _campaign_args(ev, "envelope folder")
    ev.set_defaults(handler=_run_envelope)


def _run_simulate(args) -> int:
    from quadland.run import result_lines, run_simulation

    out = run_simulation(args.scenario, args.overrides, args.out, plots=not args.no_plots,
                         animate=args.animate)
    print(f"quadland: wrote {out}")
    for line in result_lines(out):
        print(line)
    return 0


def _run_codegen(args) -> int:
    from quadland.codegen import main as codegen_main

    return codegen_main(out=args.out, check=args.check, scenario=args.scenario,
                        overrides=args.overrides)


def _run_margins(args) -> int:
    from quadland.margins import Requirement, format_report
    from quadland.margins.command import review_scenario

    requirement = Requirement(args.gain_margin_db, args.phase_margin_deg)
    if args.campaign or args.runs is not None:
        return _run_margins_campaign(args, requirement)
    report, path, elapsed = review_scenario(
        args.scenario, args.overrides, args.out, args.at, requirement, args.delay_periods,
        plots=not args.no_plots, say=lambda line: print(line, flush=True))
    print(format_report(report), end="")
    print(f"quadland: wrote {path} ({elapsed:.1f} s)")
    if report.passed:
        return 0
    failed = [f"{label}{'' if section.stable else ' (closed loop unstable)'}: "
              f"{', '.join(section.failed)}"
              for label, section in report.judged if not section.passed]
    print(f"quadland: margins below the requirement {requirement.gain_margin_db:g} dB / "
          f"{requirement.phase_margin_deg:g} deg: {'; '.join(failed)}", file=sys.stderr)
    return 1


def _run_margins_campaign(args, requirement) -> int:
    from quadland.margins.campaign_run import run_campaign_margins
    from quadland.margins.campaign_text import format_campaign

    if not args.campaign:
        raise UsageError("--runs: counts the draws of --campaign; add --campaign")
    if args.at is not None:
        raise UsageError("--at: a campaign's draws are reviewed at their equilibrium; drop --at")

    def progress(done, runs):
        if done == runs or done % 10 == 0:
            print(f"quadland: margins --campaign: {done} of {runs} draws reviewed", flush=True)

    result, path = run_campaign_margins(args.scenario, args.overrides, args.runs, args.out,
                                        requirement, args.delay_periods, progress)
    print(format_campaign(result), end="")
    print(f"quadland: wrote {path} ({result.runtime_s:.1f} s)")
    if result.all_passed:
        return 0
    n = len(result.draws)
    print(f"quadland: margins below the requirement {requirement.gain_margin_db:g} dB / "
          f"{requirement.phase_margin_deg:g} deg: {n - result.passed} of {n} draws "
          f"({result.count('invalid')} invalid, {result.count('failed')} without an operating "
          "point)", file=sys.stderr)
    return 1


def _run_campaign(args) -> int:
    from quadland.campaign.execute import run_campaign
    from quadland.campaign.summary import counted_text, summary_counts
    from quadland.engine.heap import keep_freed_memory

    keep_freed_memory()     # quadland's own process, which may fly the runs itself
    result = run_campaign(args.scenario, args.overrides, args.runs, args.out, args.workers,
                          args.scheduler, progress=sys.stderr.isatty(), plots=not args.no_plots)
    summary = result.summary
    rate = ""
    if summary is not None and summary.get("flown"):
        lo, hi = summary["confidence"]["interval"]
        rate = (f": {summary['successes']} of {summary['flown']} runs within limits "
                f"({100 * summary['success_rate']:.1f} %, 95 % interval {100 * lo:.1f} to "
                f"{100 * hi:.1f} %){counted_text(summary['model'], summary_counts(summary))}")
    elif summary is not None:
        rate = (f": no run flown, the draws of all {summary['runs']} were invalid (runs.csv "
                "says why)")
    print(f"quadland: wrote {result.folder}{rate}{_session(result)}")
    return 0


def _run_envelope(args) -> int:
    from quadland.campaign.grid import run_envelope
    from quadland.campaign.summary import counted_text
    from quadland.engine.heap import keep_freed_memory

    keep_freed_memory()     # quadland's own process, which may fly the runs itself
    seed = [] if args.seed is None else [f"campaign.seed={args.seed}"]
    result = run_envelope(args.scenario, args.overrides + seed, args.axis, args.runs_per_cell,
                          args.out, args.workers, args.scheduler, args.hold, args.polar,
                          progress=sys.stderr.isatty(), plots=not args.no_plots)
    env = result.envelope
    cells = "" if env is None else (f": {len(env['cells'])} cells, {env['successes']} of "
                                    f"{env['flown']} runs within limits"
                                    f"{counted_text(env['model'], env.get('counts', {}))}")
    print(f"quadland: wrote {result.folder}{cells}{_session(result)}")
    return 0


def _session(result) -> str:
    """What a campaign's command did itself, as its last line says it (as summary.json)."""
    invalid = (f"{result.invalid} invalid draw{'s' if result.invalid != 1 else ''} "
               "recorded") if result.invalid else ""
    if result.flown:
        speed = (f" ({result.flown / result.elapsed:.1f} runs/s)" if result.elapsed > 0
                 else "")
        return (f"; flew {result.flown} run{'s' if result.flown != 1 else ''} in "
                f"{result.elapsed:.1f} s{speed}" + (f", {invalid}" if invalid else ""))
    if invalid:
        return f"; {invalid} in {result.elapsed:.1f} s"
    return "; no run left to fly"


def _message(exc: QuadlandError) -> str:
    """The error's message, naming a parameter by its flag."""
    text = str(exc)
    if text.startswith("override "):           # a scenario override is a --set here
        return "--set " + text.removeprefix("override ")
    name, sep, rest = text.partition(":")
    return f"{_FLAGS[name]}{sep}{rest}" if sep and name in _FLAGS else text


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``quadland`` console script."""
    swallowed, default_hook = [], sys.unraisablehook

    def hook(unraisable):
        # a Ctrl-C landing in a callback Python cannot raise from (importlib's module
        # locks while a module loads) is printed and dropped: keep it as the interrupt
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            swallowed.append(unraisable)
            return
        default_hook(unraisable)

    sys.unraisablehook = hook
    try:                                        # Ctrl-C while the parser imports its modules
        parser = build_parser()
        try:
            args = parser.parse_args(argv)
        except UsageError as exc:
            print(f"quadland: error: {exc}", file=sys.stderr)
            return 2
        if swallowed:
            raise KeyboardInterrupt
        _quiet_matplotlib()
        with warnings.catch_warnings(), interrupt.catching():
            warnings.showwarning = _one_line_warning
            status = _dispatch(args)
            if status != 130:                   # not one _dispatch already reported
                interrupt.check()
        if swallowed and status != 130:         # one SIGINT, swallowed then raised again by
            raise KeyboardInterrupt             # interrupt.check, is reported once
        return status
    except KeyboardInterrupt:
        print("quadland: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:
        # a Ctrl-C that cut short an extension module's initialization (NumPy, CasADi,
        # matplotlib load on first use) surfaces as ImportError from it, and one while
        # ctypes converted a call's arguments as its ArgumentError
        if not (isinstance(exc, ImportError) and isinstance(exc.__cause__ or exc.__context__,
                                                             KeyboardInterrupt)
                or interrupt.wrapped_by_ctypes(exc)):
            raise
        print("quadland: interrupted", file=sys.stderr)
        return 130
    finally:
        sys.unraisablehook = default_hook


def _quiet_matplotlib() -> None:
    """Keep matplotlib from adding lines to quadland's one.

    Where its configuration and cache folder cannot be written (a read-only
    home), matplotlib makes a temporary one and says so in two lines, even
    when only imported (python-control imports it); here ``MPLCONFIGDIR``
    names a private temporary folder first, removed at exit (and inherited by
    a campaign's workers). Its log is limited to errors: a font cache it
    cannot save (a full disk) is no concern of a run's.
    """
    logging.getLogger("matplotlib").setLevel(logging.ERROR)
    if os.environ.get("MPLCONFIGDIR"):
        return
    home = Path.home()
    if sys.platform.startswith(("linux", "freebsd")):
        config = Path(os.environ.get("XDG_CONFIG_HOME") or home / ".config") / "matplotlib"
        cache = Path(os.environ.get("XDG_CACHE_HOME") or home / ".cache") / "matplotlib"
    else:
        config = cache = home / ".matplotlib"
    if all(_could_write(folder) for folder in (config, cache)):
        return
    import atexit
    import shutil
    import tempfile

    folder = tempfile.mkdtemp(prefix="quadland-matplotlib-")
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    os.environ["MPLCONFIGDIR"] = folder


def _could_write(folder: Path) -> bool:
    """Whether ``folder`` is, or could be made as, a writable folder (nothing is made)."""
    path = folder
    while not path.exists():
        if path.parent == path:
            return False
        path = path.parent
    return path.is_dir() and os.access(path, os.W_OK | os.X_OK)


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    print(f"quadland: warning: {message}", file=sys.stderr if file is None else file)


def _dispatch(args) -> int:
    try:
        return args.handler(args)
    except SimulationError as exc:
        print(f"quadland: error: {_message(exc)}", file=sys.stderr)
        return 3
    except CampaignStopped as exc:              # resumable: its finished runs are kept
        print(f"quadland: error: {_message(exc)}", file=sys.stderr)
        return 4
    except QuadlandError as exc:
        print(f"quadland: error: {_message(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:            # a campaign's says what it kept
        print(f"quadland: interrupted{': ' if str(exc) else ''}{exc}", file=sys.stderr)
        return 130
    except OSError as exc:
        if exc.errno not in (errno.ENAMETOOLONG, errno.ELOOP):
            raise
        # a path no file system holds, wherever a command first touched it
        name = str(exc.filename)
        shown = name if len(name) <= 80 else f"{name[:60]}... ({len(name):,} characters)"
        print(f"quadland: error: {shown}: {exc.strerror}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
