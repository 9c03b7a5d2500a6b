"""``bench NAME``: timing benchmarks (design §7: timing goals live here, never in unit tests).

:data:`BENCHMARKS` maps a name to a :class:`Benchmark`; adding one is one line
in it. Each benchmark adds its own options and returns a result with
``to_json()`` and ``summary()``; ``--json`` prints the former.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["Benchmark", "BENCHMARKS", "register"]


@dataclass(frozen=True)
class Benchmark:
    """A benchmark the ``bench`` command can run.

    Attributes
    ----------
    help : str
        One line for ``bench --help``.
    add_arguments : callable
        ``add_arguments(parser)`` adds the benchmark's options.
    run : callable
        ``run(args)`` → a result with ``to_json() -> dict`` and ``summary() -> str``.
    """

    help: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], object]


def _relight_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--size", type=int, default=1024,
                        help="cube side in texels (default 1024: 1024×1024×101 bands, ~420 MB)")
    parser.add_argument("--repeats", type=int, default=20, help="timed relights per source")
    parser.add_argument("--full-band-repeats", type=int, default=3,
                        help="timed full-band runs per source")
    parser.add_argument("--kernel", default="auto",
                        help="the runtime arithmetic: auto (compiled where the display inverse "
                             "has no correction table), numba or numpy")
    parser.add_argument("--threads", type=int, default=None,
                        help="threads of the compiled kernel (default: every CPU)")
    parser.add_argument("--profile", help="a .vrprofile.json: its display model "
                                          "(default: ideal sRGB)")


def _relight_run(args: argparse.Namespace):
    from workbench.hyperspectral.benchmark import benchmark_relight

    display, options = None, {}
    if args.profile:
        from workbench.profile import load_profile

        profile = load_profile(args.profile)
        display = profile.display_model()
        options = {"k": profile.k, "observer": profile.observer}
    return benchmark_relight(args.size, repeats=args.repeats,
                             full_band_repeats=args.full_band_repeats, display=display,
                             kernel=args.kernel, threads=args.threads, **options)


def _diagnose_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--repeats", type=int, default=5, help="timed runs (each a new interpreter)")


def _diagnose_run(args: argparse.Namespace):
    from workbench.diagnostics.benchmark import benchmark_diagnose

    return benchmark_diagnose(args.repeats)


def _gui_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--plan", default="quick", choices=("quick", "paper"),
                        help="plan of the simulated calibration whose event-loop stalls are measured (default quick)")
    parser.add_argument("--time-scale", type=float, default=0.01,
                        help="fraction of real instrument timing the emulator waits (default 0.01)")


def _gui_run(args: argparse.Namespace):
    # workbench.gui is imported by name only: nothing outside it may import it (import-linter).
    import importlib

    from workbench.errors import WorkbenchError

    try:
        benchmark = importlib.import_module("workbench.gui.benchmark")
    except ImportError as error:
        raise WorkbenchError(f"bench gui needs Qt (PySide6), which cannot be loaded here ({error})") from None
    return benchmark.benchmark_gui(plan=args.plan, time_scale=args.time_scale)


def _real_data_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--folder", help="the real-data folder (default: shared/data/real beside "
                                         "the checkout, or $VR_WORKBENCH_SHARED/data/real)")
    parser.add_argument("--markdown", action="store_true", help="print the README's table")
    parser.add_argument("--no-argyll", action="store_true", help="leave the Argyll peer out")


def _real_data_run(args: argparse.Namespace):
    from workbench.diagnostics.real_data import real_data_table

    table = real_data_table(args.folder, with_argyll=not args.no_argyll)
    if args.markdown:
        return _Markdown(table)
    return table


@dataclass(frozen=True)
class _Markdown:
    table: object

    def to_json(self) -> dict:
        return self.table.to_json()

    def summary(self) -> str:
        return self.table.markdown()


def _suite_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--seed", type=int, default=0, help="first suite seed (default 0)")
    parser.add_argument("--suites", type=int, default=None, metavar="N",
                        help="suites pooled, seeds SEED … SEED+N−1 (default: the acceptance "
                             "test's 10, 940 sessions)")


def _from_tests(module: str):
    """A module of the checkout's tests/diagnostics (the independent generator lives there)."""
    import importlib

    try:
        return importlib.import_module(f"tests.diagnostics.{module}")
    except ImportError as error:
        from workbench.errors import WorkbenchError

        raise WorkbenchError("the acceptance suite's independent generator lives in the "
                             f"checkout's tests/diagnostics ({error}); run this from the "
                             "checkout's root") from None


def _suite_run(args: argparse.Namespace):
    suite = _from_tests("suite")
    SUITE_SEEDS, pooled_cases, run_suite = suite.SUITE_SEEDS, suite.pooled_cases, suite.run_suite
    suites = SUITE_SEEDS if args.suites is None else args.suites
    if suites < 1:
        from workbench.errors import InputError

        raise InputError(f"--suites {suites}: give at least 1 suite to run")
    return run_suite(cases=pooled_cases(suites, args.seed))


def _seeds_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--seeds", type=int, default=3, metavar="N",
                        help="sessions per plan and scenario (default 3; the README's figures: 10)")


@dataclass(frozen=True)
class _BenchTable:
    """A bench of the independent generator: its summary rows and its printed table."""

    rows: list
    text: str

    def to_json(self) -> dict:
        return {"rows": self.rows}

    def summary(self) -> str:
        return self.text


def _checked_seeds(args) -> int:
    if args.seeds < 1:
        from workbench.errors import InputError

        raise InputError(f"--seeds {args.seeds}: give at least 1 session per scenario")
    return args.seeds


PEER_PROBES = ("wide-gamut", "chromaticity-noise", "correlated-noise", "current-load")
"""The peer bench's probes (``tests.diagnostics.independent_generator.PROBES``), named here so
that ``--help`` lists them without importing the tests."""


def _peers_arguments(parser: argparse.ArgumentParser) -> None:
    _seeds_arguments(parser)
    parser.add_argument("--probe", choices=PEER_PROBES,
                        help="draw every session with a display or noise the generator's forms do "
                             "not: a wide-gamut panel, a spectroradiometer's chromaticity noise, "
                             "a slow correlated gain, or a power limit loaded by current")


def _peers_run(args: argparse.Namespace):
    bench = _from_tests("peer_bench")
    outcomes = bench.run_peer_bench(seeds=_checked_seeds(args), probe=getattr(args, "probe", None))
    return _BenchTable(bench.summarize(outcomes), bench.table(outcomes))


def _follow_up_run(args: argparse.Namespace):
    bench = _from_tests("follow_up_bench")
    outcomes = bench.run_follow_up_bench(seeds=_checked_seeds(args),
                                         probe=getattr(args, "probe", None))
    return _BenchTable(bench.summarize(outcomes), bench.table(outcomes))


def _plans_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--sessions", type=int, default=2, metavar="N",
                        help="displays per scenario (default 2)")
    parser.add_argument("--scenarios", nargs="+", metavar="NAME",
                        help="only these scenarios (default: clean, every effect form, the pairs, "
                             "the simulated headset)")
    parser.add_argument("--plans", nargs="+", metavar="PLAN",
                        help="measure only these plans (default: paper, paper+greys, adaptive; "
                             "paper-repeat: the paper plan again on the same displays, another "
                             "draw of the instrument's noise, for the reference's repeatability)")
    parser.add_argument("--speed-mode", choices=("normal", "fast"), default="normal",
                        help="the CS-2000's speed mode for every plan (fast: 16 s at most in the dark, "
                             "another dark end; default normal, up to 242 s)")
    parser.add_argument("--markdown", action="store_true", help="print the docs' table")


def _plans_run(args: argparse.Namespace):
    bench = _from_tests("plans_bench")
    if args.sessions < 1:
        from workbench.errors import InputError

        raise InputError(f"--sessions {args.sessions}: give at least 1 display per scenario")
    known = bench.scenarios()
    unknown = [name for name in args.scenarios or () if name not in known]
    if unknown:
        from workbench.errors import InputError

        raise InputError(f"--scenarios: unknown {', '.join(map(repr, unknown))}; use some of "
                         f"{', '.join(known)}")
    unknown_plans = [name for name in args.plans or () if name not in bench.KNOWN_PLANS]
    if unknown_plans:
        from workbench.errors import InputError

        raise InputError(f"--plans: unknown {', '.join(map(repr, unknown_plans))}; use some of "
                         f"{', '.join(bench.KNOWN_PLANS)}")
    outcomes = bench.run_plans_bench(args.sessions, args.scenarios,
                                     plans=tuple(args.plans) if args.plans else bench.PLANS,
                                     speed_mode=bench.SPEED_MODES[args.speed_mode])
    return bench.PlansBenchResult(outcomes, args.markdown)


BENCHMARKS: dict[str, Benchmark] = {
    "relight": Benchmark("level-2 relight by the runtime bundle's method (K + S float16 "
                         "channels) vs the full-band path",
                         _relight_arguments, _relight_run),
    "diagnose": Benchmark("diagnose on a 214-measurement session, wall time with start-up",
                          _diagnose_arguments, _diagnose_run),
    "real-data": Benchmark("every real display in shared/data/real diagnosed, beside Argyll's "
                           "shaper + matrix", _real_data_arguments, _real_data_run),
    "diagnose-suite": Benchmark("the seeded acceptance suite of the independent generator: "
                                "false-finding and detection rates", _suite_arguments, _suite_run),
    "peers": Benchmark("the exported profile beside the seed authors' grey-ramp method on the "
                       "independent generator's forms, on paper, paper+greys and authors-2024: "
                       "hidden-colour ΔE00, causes named, false findings",
                       _peers_arguments, _peers_run),
    "follow-up": Benchmark("the proposed follow-up measured on the same generated display: its "
                           "share of the instrument time and the held-out gain before and after",
                           _peers_arguments, _follow_up_run),
    "plans": Benchmark("paper, paper+greys and adaptive measured through the CS-2000 emulator on the "
                       "independent generator's displays and the simulated headset: instrument time, "
                       "hidden-colour ΔE00, effects named", _plans_arguments, _plans_run),
    "gui": Benchmark("the window: event-loop stalls while calibrating, source switch, first paint",
                     _gui_arguments, _gui_run),
}
"""Benchmark name → :class:`Benchmark`."""


def register(subparsers) -> None:
    parser = subparsers.add_parser("bench", help="timing benchmarks",
                                   description="Timing benchmarks; --json for machine-readable "
                                               "output.")
    names = parser.add_subparsers(dest="benchmark", metavar="BENCHMARK", required=True)
    for name, benchmark in BENCHMARKS.items():
        sub = names.add_parser(name, help=benchmark.help, description=benchmark.help)
        sub.add_argument("--json", action="store_true", help="machine-readable output")
        benchmark.add_arguments(sub)
        sub.set_defaults(handler=_run, bench=benchmark)


def _run(args) -> int:
    result = args.bench.run(args)
    if args.json:
        json.dump(result.to_json(), sys.stdout, indent=1)
        print()
    else:
        print(result.summary())
    return 0
