"""Command line: ``python -m workbench <command> ...`` (also ``vr-workbench``).

Each command lives in its own module of this package, which exposes
``register(subparsers)``; :data:`COMMAND_MODULES` lists them. A command's
handler returns the process exit status. Errors that a user can fix
(:class:`workbench.errors.WorkbenchError`) are printed as one clear message
with exit status 2, never as a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys

from workbench import __version__
from workbench.errors import WorkbenchError

__all__ = ["COMMAND_MODULES", "build_parser", "main"]

COMMAND_MODULES = (
    "workbench.cli.illuminants",
    "workbench.cli.reproduce",
    "workbench.cli.bench",
    "workbench.cli.relight",
    "workbench.cli.diagnose",
    "workbench.cli.measure",
    "workbench.cli.ishihara",
    "workbench.cli.export",
    "workbench.cli.gui",
    "workbench.cli.vr",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="vr-workbench",
        description="Spectral colour management workbench for VR headsets.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="more logging (-v info, -vv debug: every instrument frame)")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=(logging.WARNING, logging.INFO, logging.DEBUG)[min(args.verbose, 2)],
        format="%(asctime)s %(name)s %(levelname)s %(message)s",
    )
    if not getattr(args, "handler", None):
        parser.print_help()
        return 1
    try:
        return int(args.handler(args) or 0)
    except WorkbenchError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader went away (e.g. '| head'); silence the flush at exit too.
        sys.stdout = open(os.devnull, "w")
        return 0
