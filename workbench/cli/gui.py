"""``gui``: the workbench window.

::

    vr-workbench gui [--simulate] [--time-scale S] [--size WxH] [FILE]
    vr-workbench gui --screenshot DIR [--simulate] [--size WxH] [FILE]

Opens the window (with FILE: a session CSV, ``.ti3``, ``.mat``, measurement
directory or profile, opened and diagnosed). ``--simulate`` makes the
simulated CS-2000 the instrument (otherwise: the CS-2000 found by USB
VID/PID). ``--screenshot DIR`` runs a simulated calibration to the end, writes
every page to ``DIR/<page>.png`` and exits (run it under Xvfb where there is
no display: ``xvfb-run -a -s "-screen 0 1920x1200x24"``). ``--size WxH`` gives
the window that size in pixels (e.g. ``1366x768``, a laptop screen) instead of
its default 1500x950.
"""

from __future__ import annotations

import importlib

from workbench.errors import WorkbenchError

__all__ = ["register", "parse_size"]


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
    parser.add_argument("--size", metavar="WxH",
                        help="the window's size in pixels (e.g. 1366x768); default 1500x950")
    parser.set_defaults(handler=_run)


def parse_size(text: str) -> tuple:
    """``"1366x768"`` (or ``1366×768``) as ``(1366, 768)``; a WorkbenchError naming the fix otherwise."""
    parts = str(text).lower().replace("×", "x").split("x")
    try:
        width, height = (int(part) for part in parts)
    except ValueError:
        width = height = 0
    if width < 320 or height < 240:
        raise WorkbenchError(f"--size {text!r} is not WIDTHxHEIGHT in pixels of at least 320x240; give e.g. 1366x768")
    return width, height


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
    size = None if args.size is None else parse_size(args.size)
    return app.run_gui(args.file, simulate=args.simulate, screenshot_dir=args.screenshot,
                       time_scale=args.time_scale, size=size)
