"""``gui``: the workbench window.

::

    vr-workbench gui [--simulate] [--time-scale S] [FILE]
    vr-workbench gui --screenshot DIR [--simulate] [FILE]

Opens the window (with FILE: a session CSV, ``.ti3``, ``.mat``, measurement
directory or profile, opened and diagnosed). ``--simulate`` makes the
simulated CS-2000 the instrument (otherwise: the CS-2000 found by USB
VID/PID). ``--screenshot DIR`` runs a simulated calibration to the end, writes
every page to ``DIR/<page>.png`` and exits (run it under Xvfb where there is
no display: ``xvfb-run -a -s "-screen 0 1920x1200x24"``).
"""

from __future__ import annotations

import importlib

from workbench.errors import WorkbenchError

__all__ = ["register"]


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "gui", help="the workbench window (calibrate, diagnose, gamut, illuminants, scene, export)",
        description="Open the workbench window; --screenshot DIR renders every page to DIR/<page>.png and exits.")
    parser.add_argument("file", nargs="?", metavar="FILE",
                        help="a session CSV, .ti3, .mat, measurement directory or .vrprofile.json to open")
    parser.add_argument("--simulate", action="store_true",
                        help="calibrate with the simulated CS-2000 (the emulator on a pty) and headset")
    parser.add_argument("--time-scale", type=float, metavar="S",
                        help="with --simulate: fraction of real instrument timing to wait")
    parser.add_argument("--screenshot", metavar="DIR",
                        help="run a simulated calibration, write DIR/<page>.png for every page, and exit")
    parser.set_defaults(handler=_run)


def _run(args) -> int:
    # Imported here, at the CLI edge: nothing outside workbench.gui imports it (an import-linter
    # contract), and the CLI must work where Qt cannot be loaded.
    try:
        app = importlib.import_module("workbench.gui.app")
    except ImportError as error:
        raise WorkbenchError(f"the window needs Qt (PySide6), which cannot be loaded here ({error}); "
                             "install PySide6-Essentials") from None
    if args.time_scale is not None and args.time_scale < 0:
        raise WorkbenchError(f"--time-scale {args.time_scale} is negative; give 0 (no waiting) to 1 (real timing)")
    return app.run_gui(args.file, simulate=args.simulate, screenshot_dir=args.screenshot,
                       time_scale=args.time_scale)
