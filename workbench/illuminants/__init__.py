"""The illuminant library: CIE, synthesized, imported and measured light sources.

One dispatcher, :func:`get_illuminant`, takes a stable id (``cie-d65``,
``d65-two-peak`` …) or the path of a CSV / TM-27 file; :func:`list_illuminants`
gives every built-in id. Unknown ids raise an error listing close matches.
"""

from __future__ import annotations

import difflib
from pathlib import Path

from workbench.errors import InputError
from workbench.illuminants.builtin import builtin_illuminant, builtin_illuminant_ids
from workbench.illuminants.files import (
    read_illuminant_file,
    write_illuminant_file,
    SPECTRUM_READERS,
)
from workbench.illuminants.metrics import (
    IlluminantMetrics,
    Level1Adequacy,
    illuminant_metrics,
    level1_adequacy,
)
from workbench.illuminants.source import Illuminant
from workbench.illuminants.synthesized import SYNTHESIZED_SOURCES

__all__ = [
    "Illuminant",
    "IlluminantMetrics",
    "Level1Adequacy",
    "PAPER_SOURCES",
    "get_illuminant",
    "illuminant_metrics",
    "level1_adequacy",
    "list_illuminants",
    "read_illuminant_file",
    "write_illuminant_file",
]

PAPER_SOURCES = ("cie-d65", "d65-simulator", "d65-two-peak", "cie-d50")
"""The four sources of the paper's Tables 3 and 4, in its order."""


def list_illuminants() -> list[str]:
    """Every built-in id: colour-science's CIE/ISO illuminants, then the synthesized ones."""
    return builtin_illuminant_ids() + list(SYNTHESIZED_SOURCES)


def get_illuminant(id_or_path: str) -> Illuminant:
    """A light source by library id, or from a ``.csv`` / ``.xml`` (TM-27) file path."""
    key = str(id_or_path)
    if key in SYNTHESIZED_SOURCES:
        return SYNTHESIZED_SOURCES[key]()
    if key.lower() in builtin_illuminant_ids():
        return builtin_illuminant(key.lower())
    path = Path(key.removeprefix("file:"))
    if path.suffix.lower() in SPECTRUM_READERS:
        return read_illuminant_file(path)
    close = difflib.get_close_matches(key.lower(), list_illuminants(), n=4, cutoff=0.5)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise InputError(f"unknown illuminant {key!r}{hint} Run 'python -m workbench illuminants "
                     "list' for the ids, or give a .csv/.xml spectrum file")
