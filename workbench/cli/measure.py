"""``measure``: run a calibration sequence on a headset with a CS-2000 (or the simulation).

::

    vr-workbench measure (--simulate [--effect ID[:MAGNITUDE]]... [--time-scale S] | --port DEVICE|auto)
                         [--display simulated|window[:SCREEN]|tcp:HOST:PORT
                                    |rgb-text:HOST:PORT[:SETTLE_S]|value-shot:HOST:PORT]
                         [--eye both|left|right] [--sync none|internal:HZ|external] [--target]
                         [--plan paper|quick|apl|paper+apl|paper+greys|authors-2024 | --plan-file FILE]
                         [--seed N] --out DIR [--resume | --add-plan FILE]

Writes ``DIR/journal.jsonl`` as it goes (one fsynced line per patch), then
``DIR/session.csv`` and ``DIR/session.ti3``; shows a progress bar on stderr
and ends with a one-line summary on stdout. Exit status: 0 when every patch
was measured, 1 when some failed (they are named, and ``--resume`` measures
them again), 2 for an error the user can fix (the message says how), 130 when
cancelled with Ctrl-C.

With ``--simulate`` the patches go to the simulated headset (Table 1 of the
paper, plus the ``--effect`` given), the CS-2000 emulator measures it on a
pseudo-terminal, and the real driver talks to that. The journal's times are
then the instrument's modelled times; ``--time-scale`` only sets how long the
emulator makes the run wait (0: not at all, 1: real timing). ``--seed`` seeds
the validation colours and the instrument noise (with ``--plan-file`` too;
without ``--seed`` a fresh noise seed is drawn), and the journal keeps it.
A resumed simulation draws its noise from ``SeedSequence([seed, k])`` for
its k-th resume, recorded in the journal's resume record, so that it does not
repeat the noise of the measurements already made.

``--add-plan FILE`` measures the patches of a plan file into the finished
session in ``--out DIR`` (the follow-up ``diagnose DIR --follow-up FILE``
proposes): the journal's resume machinery appends them (a resume record
naming them, fsynced before the first is measured, then one line per
patch), so a run killed in the middle of the follow-up is continued by
``--resume``; ``session.csv`` and ``session.ti3`` are then rewritten with
every measurement, and ``diagnose DIR`` reads them all. It refuses (exit 2)
a directory without a finished journal, and the same mismatches ``--resume``
refuses (a real instrument for a simulated session, other effects, another
instrument serial), and a patch display other than the session's. A
header-only plan (an empty follow-up) measures nothing and says so.

``--plan apl`` (or ``paper+apl``) measures APL patches: white and mid grey
as windows of the field on black and on grey surrounds, for the
``apl-dependence`` diagnosis of OLED brightness limiting; the display must
show a patch as a window on a surround (the simulated headset, the window,
or a patch server that accepts the protocol's ``window`` and ``surround``
fields; another stops the run at the first APL patch with a message).
``--effect apl-dependence[:LOSS]`` gives the simulated headset such a limiter.

``--port auto`` finds the CS-2000 by its USB VID/PID (0x132B/0x2104); with
none or several connected it stops with a list of the candidate ports.
Remote mode is entered with ``RMTS,2`` (settings are not written to the
instrument's flash memory, which spares it over long sessions); an instrument
that answers ``RMTS,2`` with an error code is put in remote mode with
``RMTS,1`` instead. An instrument error outside a patch's measurement (at
``IDDR``, say) ends the run with a message giving the code, what it means
and what to do.

``--display`` says where the patches are shown: ``simulated`` (the simulated
headset; the default with ``--simulate``), ``window[:SCREEN]`` (a full-screen
Qt window on screen SCREEN, by default the last screen, which is the headset
in extended mode; the measurement then runs off the GUI thread) or
``tcp:HOST:PORT`` (a VR application speaking the patch protocol of
:mod:`instruments.patch_display`). With ``--simulate``, patches shown in a
window or a VR application are also shown to the simulated headset, which is
what the emulator measures.

``rgb-text:HOST:PORT[:SETTLE_S]`` and ``value-shot:HOST:PORT`` drive an
engine that follows the seed authors' own conventions (their Unity and
Unreal projects; :mod:`instruments.engine_displays`): ``R,G,B`` on a new
connection per patch and a settle time (default 2 s) instead of an
acknowledgement, or ``Value:r,g,b`` on one connection, sent again every
second until the engine answers ``SHOT``. They show full-field patches to
both eyes only: a plan with APL patches, ``--eye left|right`` or
``--target`` with them is refused before anything starts.

``--eye left|right`` shows each patch to one panel (the other is black):
the patch protocol's ``eye`` field (sent only when not ``both``, so a server
that predates it sees nothing new otherwise; one that refuses it stops the
run with a message, the journal kept for ``--resume``). A desktop window has
no eyes and refuses it. ``--sync`` puts the CS-2000 in no, internal (``SCMS,1``
at HZ × 100: ``internal:90`` → ``SCMS,1,9000``) or external sync for the run
(``SCMS``, sent always, default ``none``; the previous mode is put back at
the end). The journal header's settings record ``eye`` and ``sync``; a resume
or ``--add-plan`` keeps them (``--eye``/``--sync`` given then must agree).
``--target`` shows the centring target (``target`` of the patch protocol,
rings and a cross in the patch window) and waits for Enter before the run.
"""

from __future__ import annotations

import importlib
import secrets
import signal
import sys
import threading
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from tqdm import tqdm

from instruments.cs2000 import CS2000Error, SyncMode, open_cs2000
from instruments.engine_displays import RGB_TEXT_DEFAULT_SETTLE_S, RgbTextPatchDisplay, ValueShotPatchDisplay
from instruments.headset import HEADSET_EFFECTS, HeadsetError, parse_effect
from instruments.patch_display import (
    EYES,
    MirroredPatchDisplay,
    PatchDisplayError,
    SimulatedPatchDisplay,
    TcpPatchDisplay,
    show_target,
)
from workbench.errors import InputError, WorkbenchError
from workbench.measurement.journal import read_journal
from workbench.measurement.plans import EMPTY_PLAN_HINT, MEASUREMENT_PLANS, measurement_plan, read_plan_file
from workbench.measurement.runner import (
    JOURNAL_NAME,
    MeasurementRun,
    PatchMeasured,
    PatchStarted,
    RunFinished,
    RunPaused,
    format_duration,
)
from workbench.measurement.simulation import open_simulated_instrument
from workbench.vr import patch_display as webxr_display
from workbench.measurement.adaptive import (
    ADAPTIVE_PLAN,
    AdaptivePlanner,
    AdaptiveSettings,
    adaptive_core_plan,
    held_out_summary,
)

__all__ = ["register", "DisplayKind", "DISPLAY_KINDS", "parse_display", "parse_sync"]

_DISPLAY_TIMEOUT_S = 10.0
_INSTRUMENT_TIMEOUT_S = 10.0  # design §6: read timeout at least 10 s


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "measure", help="measure a calibration sequence (CS-2000 or simulation) into a journal",
        description="Show each patch of a plan on the headset, measure it with the CS-2000, journal it "
                    "(crash-safe; --resume continues), then write session.csv and session.ti3.")
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--simulate", action="store_true",
                        help="measure the simulated headset with the CS-2000 emulator (on a pty)")
    source.add_argument("--port", metavar="DEVICE|auto",
                        help="serial port of the CS-2000 (e.g. /dev/ttyACM0), or auto: the one CS-2000 "
                             "connected by USB")
    parser.add_argument("--effect", action="append", default=[], metavar="ID[:MAGNITUDE]",
                        help=f"with --simulate: a physical effect of the headset, repeatable; one of "
                             f"{', '.join(HEADSET_EFFECTS)}")
    parser.add_argument("--time-scale", type=float, default=0.0, metavar="S",
                        help="with --simulate: fraction of real instrument timing to wait (default 0)")
    parser.add_argument("--display", metavar="|".join(kind.syntax for kind in DISPLAY_KINDS.values()),
                        help="where patches are shown: the simulated headset (default with --simulate), a "
                             "full-screen window on screen SCREEN (default: the last, i.e. the headset in "
                             "extended mode), a VR application's patch server (vr-workbench-patch/1), or an "
                             "engine following the seed authors' Unity (rgb-text: R,G,B per connection, then "
                             f"SETTLE_S seconds, default {RGB_TEXT_DEFAULT_SETTLE_S:g}) or Unreal convention "
                             "(value-shot: Value:r,g,b until SHOT)")
    parser.add_argument("--eye", choices=EYES, default=None,
                        help="which panel shows the patches (default both; left/right: the other is black; "
                             "needs a patch server of vr-workbench-patch/1 with 'eye', or the simulation)")
    parser.add_argument("--sync", default=None, metavar="none|internal:HZ|external",
                        help="the CS-2000's synchronisation to the panel (default none): internal:HZ at the "
                             "panel's refresh rate (20-200 Hz, e.g. internal:90 for a 90 Hz HMD, whose "
                             "low-persistence panel flashes once a frame), or external (a sync signal)")
    parser.add_argument("--target", action="store_true",
                        help="before the run, show the centring target (rings and a cross on black) and "
                             "wait for Enter while the instrument is aimed at its centre")
    plans = parser.add_mutually_exclusive_group()
    plans.add_argument("--plan", choices=sorted(MEASUREMENT_PLANS) + [ADAPTIVE_PLAN],
                       help="built-in plan (default paper); adaptive: a small core, then each next patch "
                            "chosen by the held-out error it removes per second of instrument time")
    plans.add_argument("--plan-file", metavar="FILE", help="CSV plan with columns kind,r,g,b (and optionally window,sr,sg,sb)")
    plans.add_argument("--add-plan", metavar="FILE",
                       help="measure this plan file (e.g. diagnose --follow-up's) into the finished session "
                            "in --out DIR: appended to its journal (crash-safe; --resume continues it), "
                            "session.csv and session.ti3 rewritten with every measurement")
    parser.add_argument("--seed", type=int, help="seed of the validation colours and, with --simulate, the "
                                                 "instrument noise (default: a fresh one, kept in the journal)")
    parser.add_argument("--budget-min", type=float, metavar="M",
                        help="with --plan adaptive: the instrument time the session may take, minutes "
                             "(default: 30 %% of what the paper plan would take on this display)")
    parser.add_argument("--target-dE00", type=float, metavar="T",
                        help="with --plan adaptive: stop once the predicted held-out mean ΔE00 is at or below T")
    parser.add_argument("--validation", type=int, metavar="N",
                        help="with --plan adaptive: validation colours measured at the end (default 30; "
                             "without --budget-min, fewer, never under 12, where all of them would take the "
                             "session past 33 %% of the paper plan's time; the held-out score is given with "
                             "its 95 %% confidence interval)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument("--resume", action="store_true",
                        help="continue the run journaled in DIR (failed patches are measured again)")
    parser.set_defaults(handler=_run)


@dataclass(frozen=True)
class DisplayKind:
    """A kind of patch display ``--display`` can name (an entry of :data:`DISPLAY_KINDS`).

    Attributes
    ----------
    name : str
        What ``--display`` starts with (``tcp``).
    syntax, example : str
        How it is spelt (``tcp:HOST:PORT``), and an example, for help and errors.
    parse : callable
        ``parse(rest)`` → the address tuple, from what follows ``NAME:``
        (``None`` when there is no colon); raises ``ValueError`` saying what is wrong.
    open : callable
        ``open(stack, address, eye)`` → the :class:`~instruments.patch_display.PatchDisplay`
        (entered into ``stack`` where it must be closed); ``None`` for the
        displays this module opens itself (the simulated headset, the window).
    eyes : bool
        Whether it can show a patch to one eye (``--eye left|right``).
    apl : bool
        Whether it can show APL patches (a window on a surround).
    target : str
        ``"shown"`` (it draws the centring target), ``"nothing to aim"`` (the
        simulation), or why it has none.
    """

    name: str
    syntax: str
    example: str
    parse: Callable[[str | None], tuple]
    open: Callable | None = None
    eyes: bool = False
    apl: bool = True
    target: str = "shown"
    eyes_refusal: str = ""


def _no_address(rest):
    if rest is not None:
        raise ValueError("it takes no address")
    return ()


def _screen(rest):
    if rest is None:
        return (None,)
    if rest.isdigit():
        return (int(rest),)
    raise ValueError(f"screen {rest!r} is not a number")


def _host_port(rest):
    host, _, port = (rest or "").rpartition(":")
    if host and port.isdigit() and 0 < int(port) < 65536:
        return host, int(port)
    raise ValueError("it needs HOST:PORT")


def _host_port_only(rest):
    if (rest or "").count(":") != 1:
        raise ValueError("it needs HOST:PORT")
    return _host_port(rest)


def _host_port_settle(rest):
    parts = (rest or "").split(":")
    if len(parts) == 3:
        try:
            settle = float(parts[2])
        except ValueError:
            raise ValueError(f"settle time {parts[2]!r} is not a number of seconds") from None
        if not 0 <= settle <= 60:
            raise ValueError(f"settle time {parts[2]} s must lie in 0..60 s")
        return (*_host_port(":".join(parts[:2])), settle)
    return (*_host_port_only(rest), RGB_TEXT_DEFAULT_SETTLE_S)


def _open_tcp(stack, address, eye):
    host, port = address
    return stack.enter_context(TcpPatchDisplay(host, port, _DISPLAY_TIMEOUT_S, client="vr-workbench", eye=eye))


def _open_rgb_text(stack, address, eye):
    host, port, settle_s = address
    return stack.enter_context(RgbTextPatchDisplay(host, port, settle_s, _DISPLAY_TIMEOUT_S))


def _open_value_shot(stack, address, eye):
    host, port = address
    return stack.enter_context(ValueShotPatchDisplay(host, port, _DISPLAY_TIMEOUT_S, VALUE_SHOT_RESEND_S))


_AUTHORS_NO_EYES = ("shows every patch to both eyes (the convention has no eye); measure with --eye both, or "
                    "show the patches with a patch server of vr-workbench-patch/1 (--display tcp:HOST:PORT)")

DISPLAY_KINDS = {
    kind.name: kind for kind in (
        DisplayKind("simulated", "simulated", "simulated", _no_address, eyes=True, target="nothing to aim"),
        DisplayKind("tcp", "tcp:HOST:PORT", "tcp:127.0.0.1:47800", _host_port, _open_tcp, eyes=True),
        DisplayKind("window", "window[:SCREEN]", "window:1; screens count from 0", _screen,
                    eyes_refusal="a desktop window has no eyes: it covers the whole screen, both panels of a "
                                 "headset in extended mode; measure with --eye both (cover the other lens), or "
                                 "show the patches in the VR application (--display tcp:HOST:PORT), which can "
                                 "show a patch to one eye"),
        DisplayKind("rgb-text", "rgb-text:HOST:PORT[:SETTLE_S]", "rgb-text:127.0.0.1:55001:2", _host_port_settle,
                    _open_rgb_text, apl=False, eyes_refusal=_AUTHORS_NO_EYES,
                    target="the authors' Unity convention (rgb-text) has no centring target"),
        DisplayKind("value-shot", "value-shot:HOST:PORT", "value-shot:127.0.0.1:8890", _host_port_only,
                    _open_value_shot, apl=False, eyes_refusal=_AUTHORS_NO_EYES,
                    target="the authors' Unreal convention (value-shot) has no centring target"),
        DisplayKind("webxr", webxr_display.SYNTAX, webxr_display.EXAMPLE, webxr_display.parse_address,
                    webxr_display.open_display, eyes=True),  # a headset's browser (workbench.vr)
    )
}
"""The patch displays ``--display`` names, by their prefix; :func:`parse_display` dispatches on it."""

VALUE_SHOT_RESEND_S = 1.0
"""How often ``--display value-shot`` sends the value again until the engine answers ``SHOT``."""


def parse_display(text: str | None, simulate: bool) -> tuple[str, tuple]:
    """``(kind, address)`` from ``--display``: the :data:`DISPLAY_KINDS` key and its parsed address.

    E.g. ``("simulated", ())``, ``("window", (screen,))`` (``screen`` ``None``
    for plain ``window``: the last screen), ``("tcp", (host, port))``,
    ``("rgb-text", (host, port, settle_s))``, ``("value-shot", (host, port))``.

    Raises
    ------
    InputError
        For an unknown display or one that cannot work with the instrument chosen.
    """
    if text is None:
        if simulate:
            return "simulated", ()
        raise InputError("--port needs --display tcp:HOST:PORT (the VR application's patch server) "
                         "or --display window[:SCREEN] (a full-screen window, e.g. on a headset in extended mode)")
    name, colon, rest = text.partition(":")
    kind = DISPLAY_KINDS.get(name)
    reason = ""
    if kind is not None:
        try:
            address = kind.parse(rest if colon else None)
        except ValueError as error:
            reason = f" ({kind.name}: {error})"
        else:
            if name == "simulated" and not simulate:
                raise InputError("--display simulated needs --simulate: a real CS-2000 cannot measure the "
                                 "simulated headset; use --display window[:SCREEN] or tcp:HOST:PORT")
            return name, address
    others = ", ".join(f"{k.syntax} (e.g. {k.example})" for k in DISPLAY_KINDS.values() if k.name != "simulated")
    raise InputError(f"--display {text!r} is not understood; use simulated or {others}{reason}")


def parse_sync(text: str | None) -> SyncMode:
    """The CS-2000 sync mode of ``--sync`` (``none`` when not given).

    Raises
    ------
    InputError
        Naming the bad value and what is accepted (internal sync: 20.00–200.00 Hz).
    """
    try:
        return SyncMode.parse("none" if text is None else text)
    except ValueError as error:
        raise InputError(f"--{error}") from None


def _check_display_options(kind: DisplayKind, eye: str, run_plan, target: bool) -> None:
    """Refuse, before anything starts, what the display cannot do: one eye, APL patches, a target."""
    if eye != "both" and not kind.eyes:
        raise InputError(f"--eye {eye}: --display {kind.name} {kind.eyes_refusal}")
    apl = [p for p in run_plan.patches if p.is_apl] if run_plan is not None else []
    if apl and not kind.apl:
        raise InputError(
            f"the plan {run_plan.name} has {len(apl)} APL patches (a window on a surround, e.g. "
            f"{apl[0].describe()}), and --display {kind.name} shows full-field patches only; measure a plan "
            "without APL patches (e.g. --plan paper), or show them with a patch server of "
            "vr-workbench-patch/1 (--display tcp:HOST:PORT)")
    if target and kind.target not in ("shown", "nothing to aim"):
        raise InputError(f"--target: {kind.target}; aim the instrument at the centre of the field on a white "
                         "patch in the engine, then run without --target")


def _effects(texts: list) -> dict:
    try:
        return dict(parse_effect(text) for text in texts)
    except HeadsetError as error:
        raise InputError(f"--effect: {error}") from None


def _requested_plan(args):
    """The plan asked for on the command line (``None`` if none was, on resume)."""
    if args.plan_file:
        return read_plan_file(args.plan_file)
    if args.plan is None and args.seed is None and args.resume:
        return None
    seed = args.seed if args.seed is not None else secrets.randbelow(2**31)
    if args.plan == ADAPTIVE_PLAN:
        return adaptive_core_plan(seed)
    return measurement_plan(args.plan or "paper", seed)


def _adaptive_settings(args, plan, journal) -> dict | None:
    """The adaptive plan's settings for the journal header (None for another plan)."""
    adaptive_options = [o for o, v in (("--budget-min", args.budget_min), ("--target-dE00", args.target_dE00),
                                       ("--validation", args.validation)) if v is not None]
    if journal is not None:
        if adaptive_options:
            raise InputError(f"{', '.join(adaptive_options)} cannot change a session already begun: "
                             "resume without them (the journal keeps the first run's)")
        return None
    if plan is None or plan.name != ADAPTIVE_PLAN:
        if adaptive_options:
            raise InputError(f"{', '.join(adaptive_options)} apply to --plan adaptive only")
        return None
    options = {"budget_min": args.budget_min, "target_dE00": args.target_dE00}
    if args.validation is not None:
        options["validation"] = args.validation
    return AdaptiveSettings(seed=plan.seed, **options).to_json()


def _planner(settings: dict):
    """The adaptive plan's planner where the session's settings hold one, else None."""
    data = settings.get("adaptive")
    return None if data is None else AdaptivePlanner(AdaptiveSettings.from_json(data))


def _run(args) -> int:
    if not args.simulate and (args.effect or args.time_scale):
        raise InputError("--effect and --time-scale apply to --simulate only")
    if args.time_scale < 0:
        raise InputError(f"--time-scale {args.time_scale} is negative; give 0 (no waiting) to 1 (real timing)")
    display_kind, display_address = parse_display(args.display, args.simulate)
    effects = _effects(args.effect)
    added = None
    if args.add_plan:
        added = _plan_to_add(args)
        if not added.patches:
            print(f"measure: nothing to measure: {args.add_plan} holds no patches ({EMPTY_PLAN_HINT}); "
                  f"{args.out} is left as it is")
            return 0
        plan, journal = None, _finished_journal(args.out)
    else:
        plan = _requested_plan(args)
        journal = read_journal(f"{args.out}/{JOURNAL_NAME}") if args.resume else None
        if (journal is not None and plan is not None and plan.name == ADAPTIVE_PLAN
                and journal.header.plan.name == ADAPTIVE_PLAN and plan.seed == journal.header.plan.seed):
            plan = None  # the journal's plan has grown by its decisions: resume it as it stands
    adaptive = _adaptive_settings(args, plan, journal)
    eye, sync = args.eye or "both", parse_sync(args.sync)
    settings = {"simulated": bool(args.simulate), "eye": eye, "sync": sync.text}
    if adaptive is not None:
        settings["adaptive"] = adaptive
    if journal is not None:
        _check_resume_settings(journal, args, effects)
        eye, sync = _recorded_eye_and_sync(journal, args)
        settings = journal.header.settings
        effects = settings.get("effects", effects) if args.simulate else effects
    run_plan = plan if journal is None else journal.header.plan
    if added is not None:
        run_plan = journal.header.with_added(added).plan
    _check_display_options(DISPLAY_KINDS[display_kind], eye, run_plan, args.target)
    if added is not None:
        print(f"measure: adding the {len(added)} patches of {args.add_plan} to the {len(journal.header.plan)} "
              f"of {args.out}", file=sys.stderr)
    noise_seed, noise = _noise_seed(args, run_plan, journal) if args.simulate else (None, None)

    ctrl_c = _CtrlCCancels()

    def measure_on(window_display=None):
        """The measurement itself; in a worker thread when ``window_display`` (the patch window) is given."""
        try:
            return run_measurement(window_display)
        except CS2000Error as error:
            raise _instrument_error(error, _instrument_name(args)) from None

    def run_measurement(window_display):
        run_settings = settings
        with ExitStack() as stack:
            simulation = None
            if args.simulate:
                simulation = stack.enter_context(open_simulated_instrument(
                    effects,
                    seed=noise,
                    time_scale=args.time_scale,
                    clock_offset_s=0.0 if journal is None else journal.session_end_s(),
                    plan=run_plan,
                    session_length_s=run_settings.get("session_length_s"),
                ))
                run_settings = {**run_settings, "effects": effects, "time_scale": args.time_scale,
                                "session_length_s": simulation.headset.session_length_s,
                                "noise_seed": noise_seed}
            display, shown = _open_display(stack, display_kind, display_address, simulation, window_display, eye)
            port = simulation.server.port if simulation else (None if args.port == "auto" else args.port)
            # RMTS,2 spares the instrument's flash memory; firmware that answers it with an error
            # code gets RMTS,1 (the driver falls back, and logs it).
            meter = stack.enter_context(open_cs2000(port, timeout_s=_INSTRUMENT_TIMEOUT_S,
                                                    no_flash_write="if-supported"))
            stack.enter_context(meter.synchronised(sync))  # SCMS for the run, put back after it
            if args.target:
                _aim(display_kind, shown, eye, ctrl_c)
            options = {"clock": (lambda header, journal: simulation.clock)} if simulation else {}
            options["planner"] = _planner(run_settings)
            if journal is None:
                run_settings = {**run_settings, "remote_mode": meter.remote_mode}  # RMTS,2 or the fallback
                run = MeasurementRun.start(args.out, run_plan, display, meter, settings=run_settings, **options)
            else:
                details = {"noise_seed": [int(v) for v in noise.entropy]} if simulation else None
                run = MeasurementRun.resume_session(args.out, display, meter, plan=plan, journal=journal,
                                                    resume_details=details, add_plan=added, **options)
            return _drive(run, ctrl_c)

    if display_kind == "window":
        summary = _measure_in_patch_window(display_address[0], measure_on, ctrl_c)
    else:
        summary = measure_on()
    print(f"measure: {summary.one_line('simulated' if args.simulate else 'session')}; "
          f"wrote {', '.join(str(p) for p in summary.outputs)}")
    if summary.status == "finished" and settings.get("adaptive"):
        print(f"measure: {held_out_summary(args.out)}")
    if summary.status == "cancelled":
        print(f"cancelled: run again with --resume --out {args.out} to continue", file=sys.stderr)
        return 130
    return 1 if summary.failed else 0


def _plan_to_add(args):
    """The plan file of ``--add-plan`` (may be empty: a header-only follow-up), after checking the options."""
    if args.resume:
        raise InputError("--add-plan adds patches to a finished session and --resume continues an "
                         "unfinished one: give one of them (a follow-up cut short by a crash is "
                         f"continued with --resume --out {args.out})")
    if args.seed is not None:
        raise InputError("--seed does not apply to --add-plan: the added patches are the plan file's, and "
                         "a simulation draws fresh noise from the journal's seed, as a resume does; drop --seed")
    return read_plan_file(args.add_plan, allow_empty=True)


def _finished_journal(out_dir):
    """The journal of the finished session in ``out_dir``; a clear error where there is none."""
    path = Path(out_dir) / JOURNAL_NAME
    if not path.is_file():
        raise InputError(f"--add-plan needs the measurement directory of a finished session, and {out_dir} "
                         f"holds no {JOURNAL_NAME}; give the --out directory the session was measured into, "
                         "or measure the plan as a new session with --plan-file")
    journal = read_journal(path)
    pending = journal.pending_indices()
    if pending:
        raise InputError(f"{path} is not a finished session: {len(pending)} of its {len(journal.header.plan)} "
                         f"patches have no successful measurement; finish it first with "
                         f"measure --resume --out {out_dir}, then add the plan")
    return journal


def _noise_seed(args, run_plan, journal):
    """The simulated instrument's noise seed: ``(session seed, what seeds the emulator)``.

    A new session uses ``--seed``, else the plan's seed, else a fresh one (the
    header's settings keep it). A resumed session takes its seed from the
    journal (``--seed`` on resume only selects the plan, which must be the
    journal's). The k-th resume of a session uses
    ``SeedSequence([session seed, k])``, so that its noise does not repeat
    what the earlier runs drew; its resume record keeps ``[session seed, k]``.
    """
    if journal is None:
        seed = next((s for s in (args.seed, run_plan.seed) if s is not None), None)
        seed = secrets.randbelow(2**31) if seed is None else int(seed)
        return seed, seed
    recorded = journal.header.settings.get("noise_seed", journal.header.plan.seed)
    seed = secrets.randbelow(2**31) if recorded is None else int(recorded)
    return seed, np.random.SeedSequence([seed, len(journal.resumes) + 1])


def _instrument_name(args) -> str:
    if args.simulate:
        return "the emulated CS-2000"
    if args.port == "auto":
        return "the CS-2000 (--port auto)"
    return f"the CS-2000 on {args.port}"


def _instrument_error(error: CS2000Error, name: str) -> WorkbenchError:
    """One message for an instrument error that ends the run: code, meaning, what to do."""
    said = f" answered {error.code}" if error.code else ""
    return WorkbenchError(f"{name}{said}: {error.meaning}. What to do: {error.advice}")


def _check_resume_settings(journal, args, effects: dict) -> None:
    simulated = bool(journal.header.settings.get("simulated"))
    resume, again = (("add the plan", "add it") if getattr(args, "add_plan", None)
                     else ("resume it", "resume"))
    if simulated != bool(args.simulate):
        raise InputError(
            f"{journal.path} was measured {'with --simulate' if simulated else 'with a real CS-2000'}; "
            f"{resume} the same way ({'--simulate' if simulated else '--port DEVICE'})"
        )
    recorded = journal.header.settings.get("effects", {})
    if args.effect and effects != recorded:
        raise InputError(
            f"{journal.path} was simulated with effects {recorded or 'none'}, not {effects}; "
            f"{again} without --effect (the journal's effects are used)"
        )


def _recorded_eye_and_sync(journal, args) -> tuple:
    """The eye and sync of the journaled session (a journal from before they were recorded: both, none);
    ``--eye``/``--sync`` given on resume must be the same."""
    recorded_eye = journal.header.settings.get("eye", "both")
    recorded_sync = parse_sync(journal.header.settings.get("sync", "none"))
    again = "add the plan" if getattr(args, "add_plan", None) else "resume"
    if args.eye is not None and args.eye != recorded_eye:
        raise InputError(f"{journal.path} measured the {_panel(recorded_eye)}, not the {_panel(args.eye)}: "
                         f"{again} with --eye {recorded_eye} (or leave --eye out), or measure the other panel "
                         "as a new session into another --out directory")
    if args.sync is not None and parse_sync(args.sync) != recorded_sync:
        raise InputError(f"{journal.path} was measured with --sync {recorded_sync.text}, not {args.sync}: "
                         f"{again} with --sync {recorded_sync.text} (or leave --sync out); a session mixing "
                         "synchronised and unsynchronised measurements of a pulsed panel scatters")
    return recorded_eye, recorded_sync


def _panel(eye: str) -> str:
    return "panels of both eyes" if eye == "both" else f"{eye} eye's panel"


def _aim(kind: str, display, eye: str, ctrl_c: "_CtrlCCancels") -> None:
    """``--target``: show the centring target and wait for Enter (the simulation has nothing to aim at)."""
    if DISPLAY_KINDS[kind].target == "nothing to aim":
        print("measure: --target: the simulated headset has nothing to aim at; measuring", file=sys.stderr)
        return
    try:
        show_target(display, eye)
    except PatchDisplayError as error:
        raise WorkbenchError(str(error)) from None
    where = "" if eye == "both" else f" in the {eye} eye"
    _wait_for_enter(f"measure: the centring target is shown{where} on {display.describe()}: aim the CS-2000 "
                    "through the lens at the centre of the rings and focus, then press Enter to measure "
                    "(Ctrl-C stops)", ctrl_c)


def _wait_for_enter(prompt: str, ctrl_c: "_CtrlCCancels") -> None:
    """Print ``prompt`` on stderr and wait for a line on stdin; Ctrl-C stops (from any thread)."""
    print(prompt, file=sys.stderr, flush=True)
    got: dict = {}
    done = threading.Event()

    def read() -> None:
        try:
            got["line"] = sys.stdin.readline()
        except (OSError, ValueError) as error:
            got["error"] = error
        done.set()

    threading.Thread(target=read, name="wait-for-enter", daemon=True).start()
    while not done.wait(0.1):
        if ctrl_c.pressed:
            raise KeyboardInterrupt
    if not got.get("line"):
        raise InputError("--target waits for Enter on standard input, which is closed; run measure in a "
                         "terminal, or leave out --target")


def _open_display(stack: ExitStack, kind: str, address: tuple, simulation, window_display=None, eye="both"):
    """``(display, shown)``: the patch display for ``--display`` and what shows the patches to the user.

    ``window_display`` is the patch window's, opened by the caller. With the
    simulation, ``display`` also shows each patch to the simulated headset.
    """
    if kind == "simulated":
        display = SimulatedPatchDisplay(simulation.headset)
        return display, display
    if kind == "window":
        shown = window_display
    else:
        try:
            shown = DISPLAY_KINDS[kind].open(stack, address, eye)
        except PatchDisplayError as error:
            raise WorkbenchError(str(error)) from None
    # A simulated session measures the simulated headset, so it must see the patches too.
    return (MirroredPatchDisplay(shown, SimulatedPatchDisplay(simulation.headset)) if simulation else shown), shown


def _measure_in_patch_window(screen_index: int | None, measure_on, ctrl_c: _CtrlCCancels):
    """``measure_on(display)`` in a worker thread while the main thread runs a full-screen patch window."""
    # Imported here, at the CLI edge, and only when --display window is asked for: the science and
    # the CLI must not import Qt (an import-linter contract says so), and the window is opt-in.
    try:
        measure_window = importlib.import_module("workbench.gui.measure_window")
    except ImportError as error:
        raise WorkbenchError(f"--display window needs Qt (PySide6), which cannot be loaded here ({error}); "
                             "install PySide6-Essentials, or use --display tcp:HOST:PORT") from None
    try:
        with ctrl_c.installed():
            return measure_window.run_with_patch_window(screen_index, measure_on, timeout_s=_DISPLAY_TIMEOUT_S)
    except measure_window.PatchWindowUnavailableError as error:
        raise WorkbenchError(f"--display window: Qt cannot open a window here ({error}); run the command in "
                             "a desktop session on the computer the headset is attached to, or show the "
                             "patches in a VR application with --display tcp:HOST:PORT") from None


class _CtrlCCancels:
    """Ctrl-C (SIGINT) cancels the measurement run cleanly, whichever thread drives it.

    Python runs signal handlers in the main thread only; the run may be driven
    by a worker (``--display window``) and may not exist yet when Ctrl-C comes,
    in which case it is cancelled as soon as it is :meth:`watch`-ed.
    """

    def __init__(self):
        self.pressed = False
        self._run: MeasurementRun | None = None

    def __call__(self, signum, frame) -> None:
        self.pressed = True
        run = self._run
        if run is not None:
            run.cancel()

    def watch(self, run: MeasurementRun) -> None:
        """Cancel ``run`` on Ctrl-C (at once if Ctrl-C already came)."""
        self._run = run
        if self.pressed:
            run.cancel()

    @contextmanager
    def installed(self):
        """Handle SIGINT while in this block (only in the main thread; elsewhere nothing changes)."""
        if threading.current_thread() is not threading.main_thread():
            yield self
            return
        previous = signal.signal(signal.SIGINT, self)
        try:
            yield self
        finally:
            signal.signal(signal.SIGINT, previous)


def _drive(run: MeasurementRun, ctrl_c: _CtrlCCancels):
    """Iterate the run with a progress bar; Ctrl-C cancels the measurement cleanly."""
    ctrl_c.watch(run)
    with ctrl_c.installed():  # in the main thread; off it, the caller's handler reaches the run
        return _show_progress(run)


def _show_progress(run: MeasurementRun):
    """Iterate the run with a progress bar on stderr; returns the run's summary."""
    bar = tqdm(total=len(run.plan), unit="patch", file=sys.stderr, disable=not sys.stderr.isatty(),
               dynamic_ncols=True)
    run.on_countdown = lambda remaining, total: bar.set_postfix_str(f"{remaining:.0f} s left of {total:.0f} s")
    try:
        for event in run.events():
            if isinstance(event, PatchStarted):
                bar.total = event.total  # a dynamic plan (adaptive) grows as it goes
                bar.n = event.done
                eta = "" if event.eta_s is None else f", ETA {format_duration(event.eta_s)}"
                bar.set_description(f"#{event.index} {event.patch.describe()}{eta}")
            elif isinstance(event, PatchMeasured):
                bar.n = event.done
                bar.refresh()
            elif isinstance(event, RunPaused):
                bar.set_description("paused")
            elif isinstance(event, RunFinished):
                return event.summary
    finally:
        bar.close()
    raise AssertionError("a measurement run ended without RunFinished")
