"""What a guided calibration measures, with what, and where it shows the patches (no Qt).

:class:`CalibrationSetup` is what the Calibrate page's form produces;
:func:`open_run` turns it into a :class:`~workbench.measurement.runner.MeasurementRun`
wired the way ``measure`` wires it (the simulated headset measured by the
CS-2000 emulator on a pty, or a real CS-2000; the simulated headset, a
full-screen patch window, a VR application's patch server, a headset's
browser (the WebXR page of :mod:`workbench.vr`), or a Unity or Unreal
project following the seed authors' conventions; the panel of one eye
or both; the instrument's sync), a new session or the resumption of the one
journaled in the output directory.
:func:`plan_estimate` says how many patches a plan has and how long the
instrument would take, before anything starts; :func:`adaptive_estimate` says
what the adaptive plan starts from and the budget it grows within (it is
given its planner, as ``measure --plan adaptive`` is).

This module imports no Qt: a test or a script drives a calibration with it
exactly as the window does.
"""

from __future__ import annotations

import secrets
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from instruments.cs2000 import SyncMode, find_cs2000_ports, open_cs2000
from instruments.engine_displays import RGB_TEXT_DEFAULT_SETTLE_S, RgbTextPatchDisplay, ValueShotPatchDisplay
from instruments.headset import HEADSET_EFFECTS, SimulatedHeadset
from instruments.patch_display import (
    EYES,
    MirroredPatchDisplay,
    PatchDisplayError,
    SimulatedPatchDisplay,
    TcpPatchDisplay,
)
from workbench.errors import InputError, WorkbenchError
from workbench.measurement.adaptive import (
    ADAPTIVE_PLAN,
    DEFAULT_VALIDATION,
    PAPER_SHARE,
    AdaptivePlanner,
    AdaptiveSettings,
    adaptive_core_plan,
)
from workbench.measurement.journal import read_journal
from workbench.measurement.plans import MEASUREMENT_PLANS, MeasurementPlan, measurement_plan, read_plan_file
from workbench.measurement.runner import JOURNAL_NAME, MeasurementRun
from workbench.measurement.simulation import modelled_plan_duration_s, open_simulated_instrument
from workbench.vr.server import DEFAULT_PORT as WEBXR_DEFAULT_PORT

__all__ = ["SIMULATED", "DISPLAY_KINDS", "ENGINE_DEFAULT_ADDRESSES", "ONE_EYE_DISPLAYS", "SYNC_CHOICES",
           "PLAN_DESCRIPTIONS", "PLAN_NAMES", "WEBXR_DEFAULT_ADDRESS", "CalibrationSetup", "PlanEstimate",
           "plan_estimate", "AdaptiveEstimate", "adaptive_estimate",
           "cs2000_ports", "planned", "open_run", "check_tcp_display"]

SIMULATED = "simulated"
"""The instrument (and display) name of the simulation."""

DISPLAY_KINDS = {
    "simulated": "simulated headset",
    "window": "full-screen window",
    "tcp": "VR application (TCP patch protocol)",
    "rgb-text": "Unity project (R,G,B text)",
    "value-shot": "Unreal project (Value/SHOT)",
    "webxr": "headset browser (WebXR)",
}
"""Patch display kind → how the form names it."""

ENGINE_DEFAULT_ADDRESSES = {"rgb-text": ("127.0.0.1", 55001), "value-shot": ("127.0.0.1", 8890)}
"""Where the authors' Unity and Unreal projects listen (``ConnectionUnity.m``, ``ConnectionUnreal.m``)."""

ONE_EYE_DISPLAYS = ("simulated", "tcp", "webxr")
"""The displays that can show a patch to one eye (the simulation records it)."""

WEBXR_DEFAULT_ADDRESS = ("127.0.0.1", WEBXR_DEFAULT_PORT)
"""Where the WebXR page is served by default (loopback: a PC headset's browser, or a Quest over USB
with ``adb reverse``); another interface adds a token to the URL and HTTPS (:mod:`workbench.vr.security`)."""

SYNC_CHOICES = {"none": "no sync", "internal": "internal, at the panel's refresh rate", "external": "external"}
"""The CS-2000's sync modes as the form names them."""

VALUE_SHOT_RESEND_S = 1.0
"""How often the Unreal convention's value is sent again until the engine answers ``SHOT``."""

PLAN_DESCRIPTIONS = {
    "paper": "as in the paper",
    "paper+greys": "with greys and mixtures",
    "apl": "windows on surrounds",
    "paper+apl": "with the APL block",
    "authors-2024": "the authors' own protocol with a grey ramp",
    ADAPTIVE_PLAN: "a small core, then each next patch chosen by the held-out error it removes per second "
                   "of instrument time",
}
"""What a built-in plan is, in words (the Calibrate form's estimate says it; the plan list only names it)."""

PLAN_NAMES = (*MEASUREMENT_PLANS, ADAPTIVE_PLAN)
"""The plans the form lists: the fixed ones (:data:`~workbench.measurement.plans.MEASUREMENT_PLANS`)
and the adaptive plan (:mod:`workbench.measurement.adaptive`), which grows as it measures."""

_INSTRUMENT_TIMEOUT_S = 10.0  # design §6: read timeout at least 10 s
_DISPLAY_TIMEOUT_S = 10.0


@dataclass(frozen=True)
class CalibrationSetup:
    """A calibration to run.

    Attributes
    ----------
    out_dir : Path
        Output directory (journal, ``session.csv``, ``session.ti3``); a
        journal already there is resumed.
    instrument : str
        :data:`SIMULATED`, a serial device (``/dev/ttyACM0``), or ``"auto"``
        (the one CS-2000 connected by USB, found by VID/PID).
    effects : dict
        With the simulation: headset effect id → magnitude
        (:data:`instruments.headset.HEADSET_EFFECTS`).
    time_scale : float
        With the simulation: fraction of real instrument timing to wait.
    display : str
        A key of :data:`DISPLAY_KINDS`.
    screen : int or None
        For ``window``: the screen; ``None`` is the last (the headset in extended mode).
    tcp_address : (str, int) or None
        For ``tcp``: the patch server's host and port.
    plan_name : str
        A built-in plan (``paper``, ``quick``) or ``"file"``.
    plan_file : Path or None
        For ``plan_name == "file"``: a CSV plan (``kind,r,g,b``).
    seed : int or None
        Seed of the validation colours and the simulated noise; ``None`` draws one.
    faults : tuple
        Emulator faults to inject (:mod:`instruments.cs2000.emulator`), for
        rehearsing what the window shows when the instrument fails.
    remeasure : tuple of int
        Plan indices to measure again on resume (the newer record wins).
    add_plan : Path or None
        A plan file to measure into the finished session in ``out_dir``
        (``measure --add-plan``: a follow-up of
        :mod:`workbench.diagnostics.follow_up`); the session's own
        instrument and effects are used, as on resume.
    engine_address : (str, int) or None
        For ``rgb-text`` and ``value-shot``: where the engine listens.
    settle_s : float
        For ``rgb-text``: seconds to wait after sending a patch (no acknowledgement).
    eye : str
        Which panel shows the patches (``both``, ``left``, ``right``;
        :data:`ONE_EYE_DISPLAYS` only for one eye). A resumed session keeps its own.
    sync : str
        The CS-2000's sync: ``none``, ``internal:HZ`` (20-200 Hz) or
        ``external``. A resumed session keeps its own.
    webxr_address : (str, int) or None
        For ``webxr``: where the page is served when :func:`open_run` is given
        no running server (a script; the window shares one server).
    budget_min, target_dE00 : float or None
        For the ``adaptive`` plan: the instrument time the session may take
        (None: :data:`~workbench.measurement.adaptive.PAPER_SHARE` of the
        paper plan's) and the predicted held-out ΔE00 to stop at (None: no target).
    validation : int
        For the ``adaptive`` plan: validation colours measured at the end.
    """

    out_dir: Path
    instrument: str = SIMULATED
    effects: dict = field(default_factory=dict)
    time_scale: float = 0.0
    display: str = "simulated"
    screen: int | None = None
    tcp_address: tuple | None = None
    plan_name: str = "paper"
    plan_file: Path | None = None
    seed: int | None = None
    faults: tuple = ()
    remeasure: tuple = ()
    add_plan: Path | None = None
    engine_address: tuple | None = None
    settle_s: float = RGB_TEXT_DEFAULT_SETTLE_S
    eye: str = "both"
    sync: str = "none"
    webxr_address: tuple | None = None
    budget_min: float | None = None
    target_dE00: float | None = None
    validation: int = DEFAULT_VALIDATION

    def __post_init__(self):
        simulated = self.instrument == SIMULATED
        if self.display not in DISPLAY_KINDS:
            raise InputError(f"unknown patch display {self.display!r}; choose one of {', '.join(DISPLAY_KINDS)}")
        if self.display == "simulated" and not simulated:
            raise InputError("a real CS-2000 cannot measure the simulated headset; show the patches in a "
                             "full-screen window or a VR application")
        if self.display == "webxr" and not self.webxr_address:
            raise InputError("the headset browser (WebXR) needs the address to serve its page on "
                             "(e.g. 127.0.0.1:47900)")
        if self.display == "tcp" and not self.tcp_address:
            raise InputError("the TCP patch display needs a host and a port (e.g. 127.0.0.1:47800)")
        if self.display in ENGINE_DEFAULT_ADDRESSES and not self.engine_address:
            host, port = ENGINE_DEFAULT_ADDRESSES[self.display]
            raise InputError(f"the {DISPLAY_KINDS[self.display]} needs the engine's host and port "
                             f"(e.g. {host}:{port})")
        if not 0 <= self.settle_s <= 60:
            raise InputError(f"settle time {self.settle_s:g} s must lie in 0..60 s")
        if self.eye not in EYES:
            raise InputError(f"eye {self.eye!r} must be one of {', '.join(EYES)}")
        if self.eye != "both" and self.display not in ONE_EYE_DISPLAYS:
            raise InputError(f"the {DISPLAY_KINDS[self.display]} shows each patch to both eyes; choose both "
                             "eyes, or show the patches in a VR application (TCP patch protocol), which can "
                             "show a patch to one eye")
        try:
            SyncMode.parse(self.sync)
        except ValueError as error:
            raise InputError(str(error)) from None
        if self.effects and not simulated:
            raise InputError("headset effects apply to the simulated CS-2000 only")
        unknown = sorted(set(self.effects) - set(HEADSET_EFFECTS))
        if unknown:
            raise InputError(f"unknown headset effect {unknown[0]!r}; known: {', '.join(HEADSET_EFFECTS)}")
        if self.time_scale < 0:
            raise InputError(f"time scale {self.time_scale} is negative; give 0 (no waiting) to 1 (real timing)")
        if self.plan_name != "file" and self.plan_name not in PLAN_NAMES:
            raise InputError(f"unknown plan {self.plan_name!r}; choose one of "
                             f"{', '.join(sorted(PLAN_NAMES))} or a plan file")
        if self.plan_name == ADAPTIVE_PLAN:
            self.adaptive_settings(0)  # the budget, target and validation count are checked here
        if self.plan_name == "file" and not self.plan_file:
            raise InputError("choose a plan file (CSV with columns kind,r,g,b)")

    @property
    def simulated(self) -> bool:
        return self.instrument == SIMULATED

    def plan(self, seed: int | None = None) -> MeasurementPlan:
        """The plan to measure (a built-in one is drawn with ``seed``, else :attr:`seed`)."""
        if self.plan_name == "file":
            return read_plan_file(self.plan_file)
        seed = seed if seed is not None else self.seed
        if self.plan_name == ADAPTIVE_PLAN:
            return adaptive_core_plan(0 if seed is None else seed)  # it grows by the planner's decisions
        return measurement_plan(self.plan_name, 0 if seed is None else seed)

    @property
    def adaptive(self) -> bool:
        """Whether the plan is the adaptive one."""
        return self.plan_name == ADAPTIVE_PLAN

    def adaptive_settings(self, seed: int) -> AdaptiveSettings:
        """The adaptive plan's settings (``measure --budget-min/--target-dE00/--validation``) for ``seed``.

        Raises
        ------
        InputError
            For a budget or target that is not above 0, or fewer than 1 validation colour.
        """
        return AdaptiveSettings(seed=int(seed), budget_min=self.budget_min, target_dE00=self.target_dE00,
                                validation=int(self.validation))

    def describe_instrument(self) -> str:
        """E.g. ``"simulated CS-2000 (channel-interaction 0.1)"`` or ``"CS-2000 on /dev/ttyACM0"``."""
        if self.simulated:
            effects = ", ".join(f"{k} {v:g}" for k, v in self.effects.items())
            return f"simulated CS-2000{f' ({effects})' if effects else ''}"
        return "CS-2000 (found by USB VID/PID)" if self.instrument == "auto" else f"CS-2000 on {self.instrument}"

    def describe_display(self) -> str:
        """E.g. ``"full-screen window on screen 1"``."""
        if self.display == "window":
            return f"full-screen window on {'the last screen' if self.screen is None else f'screen {self.screen}'}"
        if self.display == "tcp":
            eye = "" if self.eye == "both" else f", {self.eye} eye"
            return f"VR application at tcp:{self.tcp_address[0]}:{self.tcp_address[1]}{eye}"
        if self.display == "rgb-text":
            host, port = self.engine_address
            return f"Unity project at rgb-text:{host}:{port}:{self.settle_s:g}"
        if self.display == "value-shot":
            host, port = self.engine_address
            return f"Unreal project at value-shot:{host}:{port}"
        if self.display == "webxr":
            host, port = self.webxr_address
            eye = "" if self.eye == "both" else f", {self.eye} eye"
            where = f"webxr:{port}" if host == WEBXR_DEFAULT_ADDRESS[0] else f"webxr:{host}:{port}"
            return f"headset browser at {where}{eye}"
        return DISPLAY_KINDS[self.display]


@dataclass(frozen=True)
class PlanEstimate:
    """A plan's patch count and the instrument time it is expected to take.

    Attributes
    ----------
    patches : int
    counts : dict
        Patches per kind.
    instrument_s : float
        Seconds the CS-2000 would take for every patch on the simulated
        headset of Table 1 (normal speed, auto ND; dark patches take longest).
    """

    patches: int
    counts: dict
    instrument_s: float


def plan_estimate(plan: MeasurementPlan, effects: dict | None = None) -> PlanEstimate:
    """Patch count and modelled instrument time of ``plan`` (see :class:`PlanEstimate`)."""
    headset = SimulatedHeadset(effects or {})
    return PlanEstimate(len(plan), plan.counts(), modelled_plan_duration_s(plan, headset))


@dataclass(frozen=True)
class AdaptiveEstimate:
    """What the adaptive plan is expected to take, before it starts (its patches are chosen as it goes).

    Attributes
    ----------
    core : PlanEstimate
        The core it starts from.
    validation_s : float
        Seconds of the validation colours and the last white (measured at the end; the budget
        keeps them in reserve).
    paper_s : float
        Seconds the ``paper`` plan would take on the same display.
    budget_s : float
        The session's budget: ``budget_min``, else :data:`~workbench.measurement.adaptive.PAPER_SHARE`
        of ``paper_s`` but never less than the core and the validation colours (as the planner
        sets it, from the modelled times rather than the times it will measure).
    budget_given : bool
        Whether the budget is the user's.
    validation : int
        Validation colours it ends with: those asked for, fewer where they would take the session
        past :data:`~workbench.measurement.adaptive.TIME_CAP_SHARE` of ``paper_s``
        (:func:`~workbench.measurement.adaptive.validation_count`).
    """

    core: PlanEstimate
    validation_s: float
    paper_s: float
    budget_s: float
    budget_given: bool
    validation: int


def adaptive_estimate(setup: CalibrationSetup) -> AdaptiveEstimate:
    """The adaptive plan's core, budget and validation time on the simulated headset of ``setup``'s effects."""
    from workbench.measurement.adaptive import validation_count, validation_patches

    seed = 0 if setup.seed is None else setup.seed
    settings = setup.adaptive_settings(seed)
    headset = SimulatedHeadset(setup.effects or {})
    core = setup.plan()
    core_estimate = PlanEstimate(len(core), core.counts(), modelled_plan_duration_s(core, headset))
    paper_s = modelled_plan_duration_s(measurement_plan("paper", seed), headset)
    asked = validation_patches(seed, settings.validation)
    count = settings.validation
    if settings.budget_min is None:
        def seconds(patch):
            return modelled_plan_duration_s(MeasurementPlan("one", (patch,)), headset)

        count = validation_count(settings.validation, core_estimate.instrument_s,
                                 seconds(core.patches[0]), [seconds(p) for p in asked], paper_s)
    closing = MeasurementPlan("validation", (*asked[:count], *core.patches[:1]))  # and a white
    validation_s = modelled_plan_duration_s(closing, headset)
    if settings.budget_min is not None:
        return AdaptiveEstimate(core_estimate, validation_s, paper_s, 60.0 * settings.budget_min, True,
                                count)
    budget = max(PAPER_SHARE * paper_s, core_estimate.instrument_s + validation_s)
    return AdaptiveEstimate(core_estimate, validation_s, paper_s, budget, False, count)


def cs2000_ports() -> list:
    """``[(device, description)]`` of the serial ports whose USB VID/PID is a CS-2000's."""
    return find_cs2000_ports()


def check_tcp_display(host: str, port: int, timeout_s: float = 3.0) -> str:
    """Connect to a patch server, say hello and disconnect; returns the display it names.

    Raises
    ------
    WorkbenchError
        If it cannot be reached or speaks another protocol; the message says what to check.
    """
    try:
        with TcpPatchDisplay(host, port, timeout_s, client="vr-workbench gui") as display:
            return display.display_name or f"tcp:{host}:{port}"
    except PatchDisplayError as error:
        raise WorkbenchError(str(error)) from None


def planned(setup: CalibrationSetup) -> tuple:
    """``(plan, journal)``: what :func:`open_run` will measure; the journal in ``out_dir`` (resume) or None.

    With ``setup.add_plan`` the plan is the session's with the plan file's
    patches after it.

    Raises
    ------
    WorkbenchError
        With ``add_plan``: if ``out_dir`` holds no journal, or the plan file cannot be read.
    """
    path = Path(setup.out_dir) / JOURNAL_NAME
    journal = read_journal(path) if path.is_file() else None
    if setup.add_plan is not None:
        if journal is None:
            raise InputError(f"{setup.out_dir} holds no {JOURNAL_NAME}: a follow-up is measured into the "
                             "directory of a finished session; choose that directory, or measure the plan "
                             "file as a new session")
        return journal.header.with_added(read_plan_file(setup.add_plan)).plan, journal
    return (setup.plan() if journal is None else journal.header.plan), journal


@contextmanager
def open_run(setup: CalibrationSetup, window_display=None, on_countdown=None, *, webxr_server=None,
             cancel=None):
    """Open the instrument and the patch display and yield the run (new, or resumed from the journal).

    An ``adaptive`` plan's run gets its planner
    (:class:`~workbench.measurement.adaptive.AdaptivePlanner`, from the
    journal header's settings when resumed), as ``measure --plan adaptive`` does.

    Parameters
    ----------
    setup : CalibrationSetup
    window_display : PatchDisplay, optional
        For ``setup.display == "window"``: the patch window's display, opened
        by the caller in the GUI thread (its ``show`` may be called from a worker).
    on_countdown : callable, optional
        ``on_countdown(remaining_s, total_s)`` while the instrument measures.
    webxr_server : WebXRServer, optional
        For ``setup.display == "webxr"``: the running server whose page shows
        the patches (the window's, shared with the Scene page); without it a
        server is started on ``setup.webxr_address`` for the run. Either way
        this blocks until the headset's browser has the page in VR (up to
        :data:`~workbench.vr.patch_display.DEFAULT_PAGE_TIMEOUT_S`).
    cancel : threading.Event, optional
        Set it to stop waiting for the headset's browser (the window's Cancel).

    Yields
    ------
    MeasurementRun
        Iterate its ``events()``; everything is closed when the block ends.

    Raises
    ------
    WorkbenchError
        If the instrument or the display cannot be opened, or the journal in
        ``out_dir`` was measured another way.
    """
    out_dir = Path(setup.out_dir)
    plan, journal = planned(setup)
    if journal is not None and bool(journal.header.settings.get("simulated")) != setup.simulated:
        raise InputError(f"{journal.path} was measured {'with' if not setup.simulated else 'without'} a "
                         "real CS-2000; resume it with the same instrument, or choose another output directory")
    if setup.display in ENGINE_DEFAULT_ADDRESSES and any(p.is_apl for p in plan.patches):
        raise InputError(f"the plan {plan.name} has APL patches (windows on surrounds), and the "
                         f"{DISPLAY_KINDS[setup.display]} shows full-field patches only; choose a plan without "
                         "them (e.g. paper), or show the patches in a VR application (TCP patch protocol)")
    if journal is None:
        eye, sync = setup.eye, SyncMode.parse(setup.sync)
    else:  # a resumed session is measured as it began (a journal from before they were recorded: both, none)
        eye = journal.header.settings.get("eye", "both")
        sync = SyncMode.parse(journal.header.settings.get("sync", "none"))
    with ExitStack() as stack:
        simulation = None
        settings = ({"simulated": setup.simulated, "eye": eye, "sync": sync.text} if journal is None
                    else dict(journal.header.settings))
        if journal is None and plan.name == ADAPTIVE_PLAN and setup.adaptive:
            settings["adaptive"] = setup.adaptive_settings(plan.seed).to_json()
        if setup.simulated:
            if journal is None:
                seed = setup.seed if setup.seed is not None else (plan.seed if plan.seed is not None
                                                                  else secrets.randbelow(2**31))
                noise, effects = seed, dict(setup.effects)
                settings.update(effects=effects, time_scale=setup.time_scale, noise_seed=seed)
            else:
                recorded = settings.get("noise_seed", plan.seed)
                seed = secrets.randbelow(2**31) if recorded is None else int(recorded)
                noise = np.random.SeedSequence([seed, len(journal.resumes) + 1])
                effects = dict(settings.get("effects", {}))
            simulation = stack.enter_context(open_simulated_instrument(
                effects, seed=noise, time_scale=setup.time_scale, faults=setup.faults,
                clock_offset_s=0.0 if journal is None else journal.session_end_s(), plan=plan,
                session_length_s=settings.get("session_length_s")))
            settings["session_length_s"] = simulation.headset.session_length_s
        display = _open_display(stack, setup, simulation, window_display, eye, webxr_server, cancel)
        port = simulation.server.port if simulation else (None if setup.instrument == "auto" else setup.instrument)
        meter = stack.enter_context(open_cs2000(port, timeout_s=_INSTRUMENT_TIMEOUT_S, no_flash_write="if-supported"))
        stack.enter_context(meter.synchronised(sync))  # SCMS for the run, put back after it
        options = {"on_countdown": on_countdown}
        if settings.get("adaptive") is not None:
            options["planner"] = AdaptivePlanner(AdaptiveSettings.from_json(settings["adaptive"]))
        if simulation:
            options["clock"] = lambda header, journal: simulation.clock
        if journal is None:
            settings["remote_mode"] = meter.remote_mode
            run = MeasurementRun.start(out_dir, plan, display, meter, settings=settings, **options)
        else:
            details = {"noise_seed": [int(v) for v in noise.entropy]} if simulation else None
            added = None if setup.add_plan is None else read_plan_file(setup.add_plan)
            run = MeasurementRun.resume_session(out_dir, display, meter, journal=journal, resume_details=details,
                                                remeasure=setup.remeasure, add_plan=added, **options)
        yield run


def _open_display(stack: ExitStack, setup: CalibrationSetup, simulation, window_display, eye: str = "both",
                  webxr_server=None, cancel=None):
    if setup.display == "simulated":
        return SimulatedPatchDisplay(simulation.headset)
    if setup.display == "window":
        if window_display is None:
            raise WorkbenchError("the full-screen patch window was not opened; choose the screen again")
        shown = window_display
    else:
        try:
            if setup.display == "rgb-text":
                shown = RgbTextPatchDisplay(*setup.engine_address, setup.settle_s, _DISPLAY_TIMEOUT_S)
            elif setup.display == "value-shot":
                shown = stack.enter_context(ValueShotPatchDisplay(*setup.engine_address, _DISPLAY_TIMEOUT_S,
                                                                  VALUE_SHOT_RESEND_S))
            elif setup.display == "webxr":
                shown = stack.enter_context(_webxr_display(setup, eye, webxr_server, cancel))
            else:
                host, port = setup.tcp_address
                shown = stack.enter_context(TcpPatchDisplay(host, port, _DISPLAY_TIMEOUT_S,
                                                            client="vr-workbench gui", eye=eye))
        except PatchDisplayError as error:
            raise WorkbenchError(str(error)) from None
    # A simulated session measures the simulated headset, so it must see the patches too.
    return MirroredPatchDisplay(shown, SimulatedPatchDisplay(simulation.headset)) if simulation else shown


def _webxr_display(setup: CalibrationSetup, eye: str, server, cancel):
    """The WebXR page of ``server`` (or of a server started for the run), once it is in VR."""
    from workbench.vr.patch_display import DEFAULT_PAGE_TIMEOUT_S, WebXRPatchDisplay

    options = dict(eye=eye, timeout_s=_DISPLAY_TIMEOUT_S, page_timeout_s=DEFAULT_PAGE_TIMEOUT_S, cancel=cancel,
                   client="vr-workbench gui")
    if server is None:
        host, port = setup.webxr_address
        return WebXRPatchDisplay.serve(port, host=host, announce=None, **options)
    return WebXRPatchDisplay(server, **options)
