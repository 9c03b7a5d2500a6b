"""Measurement plans: which patches a calibration shows, in which order.

A plan is a sequence of :class:`Patch` (a session kind and the DAC triplet to
show, full field or, for an APL patch, as a centred window of the field on a
surround). :data:`MEASUREMENT_PLANS` holds the built-in plans and
:func:`measurement_plan` picks one by name; :func:`read_plan_file` reads a plan
from a CSV file with columns ``kind,r,g,b`` and optionally ``window,sr,sg,sb``.

Built-in plans
--------------
``paper``
    As in Díaz-Barrancas et al. (2020): black, white, each channel swept from 5
    to 255 in steps of 5 (kinds ``ramp-r``, ``ramp-g``, ``ramp-b``), then 50
    seeded random validation colours; a white is re-measured after every 25
    patches, and once more at the end, as drift references (214 patches).
``quick``
    The same structure with five levels per channel (51 to 255 in steps of 51)
    and 10 validation colours, for a fast look (28 patches).
``apl``
    For ``apl-dependence`` (OLED brightness limiting): white and mid grey (128)
    as windows of :data:`APL_WINDOWS` of the field on black, and white and mid
    grey as a :data:`APL_SMALL_WINDOW` window on grey surrounds of
    :data:`APL_SURROUNDS`, in a seeded random order, with a full-field white
    reference after every :data:`APL_REFERENCE_INTERVAL` patches and at both
    ends (these are also the drift references). White and grey APL patches
    have kind ``grey`` (only a full-field white is a ``white`` reference). 31
    patches (24 APL patches, the mid grey full field, 6 whites); 2.1 min of modelled CS-2000 time on
    the clean simulated headset (every patch is bright).
``paper+apl``
    ``paper`` followed by the ``apl`` block: 244 patches, 69.3 min of
    modelled CS-2000 time on the clean simulated headset (the ``paper``
    part's dark patches dominate).
``paper+greys``
    ``paper`` with, before the validation colours, a grey ramp
    (:data:`GREY_LEVELS`, kind ``grey``) and the partial-drive mixtures of a
    3 × 3 × 3 cube of :data:`MIXTURE_LEVELS` other than its greys (kind
    ``mixture``): the fit rows then show how the channels combine below full
    drive, which the paper's plan (whose only mixture is white) cannot; the
    diagnosis fits a channel interaction's shape on the greys and
    cross-validates it on the mixtures. 254 patches.
``authors-2024``
    The seed authors' own protocol (their public code,
    rkl-gilro/ColorCharacterization, ``src/HMD_ColourCharacterisation.m``):
    black, white, each channel swept from 5 to 255 in steps of 5, the
    ``paper`` plan's 50 validation colours for the same seed, then a grey ramp
    (r = g = b, kind ``grey``) from 5 to 250 closed by the white at 255, with
    the ``paper`` plan's drift references (their protocol measures one white; the
    diagnosis needs repeated whites to test drift): 266 patches, 77.8 min of
    modelled CS-2000 time on the clean simulated headset. It is what the
    authors' grey-ramp linearisation (:mod:`workbench.diagnostics.authors`)
    is built from, measured as they measure it; the greys come last, in the
    state a profile describes (:func:`measurement_plan_authors_2024`).
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from workbench.errors import InputError, SpectrumFileError
from workbench.fileio import atomic_writer
from workbench.session import SESSION_KINDS

__all__ = [
    "APL_WINDOWS",
    "APL_SMALL_WINDOW",
    "APL_SURROUNDS",
    "APL_REFERENCE_INTERVAL",
    "apl_block",
    "measurement_plan_apl",
    "measurement_plan_paper_apl",
    "measurement_plan_paper_greys",
    "measurement_plan_authors_2024",
    "AUTHORS_2024_LEVELS",
    "GREY_LEVELS",
    "MIXTURE_LEVELS",
    "Patch",
    "MeasurementPlan",
    "DRIFT_REFERENCE_INTERVAL",
    "MEASUREMENT_PLANS",
    "measurement_plan",
    "measurement_plan_paper",
    "measurement_plan_quick",
    "read_plan_file",
    "write_plan_file",
    "EMPTY_PLAN_HINT",
]

DRIFT_REFERENCE_INTERVAL = 25
"""A white drift reference is shown after this many patches without one."""

APL_WINDOWS = (0.01, 0.03, 0.1, 0.2, 0.35, 0.5, 0.75)
"""Window sizes (fractions of the field) of the ``apl`` plan's patches on black (and full field)."""

APL_SMALL_WINDOW = 0.03
"""Window size of the ``apl`` plan's patches on a lit surround."""

APL_SURROUNDS = (32, 64, 128, 192, 255)
"""Grey surround levels (DAC) of the ``apl`` plan's small-window patches."""

GREY_LEVELS = tuple(range(16, 241, 16))
"""DAC levels of the ``paper+greys`` plan's grey ramp (15 greys, 6 % to 94 % drive)."""

MIXTURE_LEVELS = (64, 128, 192)
"""Per-channel DAC levels of the ``paper+greys`` plan's partial-drive mixtures (a 3 × 3 × 3
cube without its 3 greys: 24 mixtures)."""

AUTHORS_2024_LEVELS = tuple(range(5, 256, 5))
"""DAC levels of the ``authors-2024`` plan's sweeps and grey ramp (their DAC 0 is the black)."""

APL_REFERENCE_INTERVAL = 6
"""The ``apl`` plan shows a full-field white after this many APL patches."""

_APL_GREY = 128

_BLACK, _WHITE = (0, 0, 0), (255, 255, 255)
_RAMP_KINDS = {"ramp-r": 0, "ramp-g": 1, "ramp-b": 2}


@dataclass(frozen=True)
class Patch:
    """One patch of a plan.

    Attributes
    ----------
    kind : str
        A session kind (``black``, ``white``, ``ramp-r`` … ``validation``).
    rgb : (int, int, int)
        DAC values to show, 0..255.
    window : float
        Fraction of the field the patch covers, 0 < window <= 1 (1: full field).
    surround : (int, int, int)
        DAC values of the rest of the field (black by default).
    """

    kind: str
    rgb: tuple
    window: float = 1.0
    surround: tuple = (0, 0, 0)

    @property
    def is_apl(self) -> bool:
        """Whether the patch is shown as a window on a surround (not full field)."""
        return self.window < 1.0

    def describe(self) -> str:
        """E.g. ``"ramp-g (0, 35, 0)"`` or ``"grey (255, 255, 255) in 3 % of the field on (64, 64, 64)"``."""
        text = f"{self.kind} ({self.rgb[0]}, {self.rgb[1]}, {self.rgb[2]})"
        if self.is_apl:
            text += f" in {100 * self.window:g} % of the field on ({', '.join(map(str, self.surround))})"
        return text


@dataclass(frozen=True)
class MeasurementPlan:
    """A named sequence of patches.

    Attributes
    ----------
    name : str
        ``paper``, ``quick``, or the plan file's path.
    patches : tuple of Patch
    seed : int or None
        Seed of the random validation colours (``None`` for a plan file).
    """

    name: str
    patches: tuple
    seed: int | None = None

    def __len__(self) -> int:
        return len(self.patches)

    def counts(self) -> dict:
        """Number of patches of each kind, in first-appearance order."""
        counts: dict = {}
        for patch in self.patches:
            counts[patch.kind] = counts.get(patch.kind, 0) + 1
        return counts


def _ramps(levels) -> list:
    patches = []
    for kind, channel in _RAMP_KINDS.items():
        for level in levels:
            rgb = [0, 0, 0]
            rgb[channel] = int(level)
            patches.append(Patch(kind, tuple(rgb)))
    return patches


def _validation(count: int, seed: int) -> list:
    rng = np.random.default_rng(seed)
    return [Patch("validation", tuple(int(v) for v in rgb)) for rgb in rng.integers(0, 256, size=(count, 3))]


def apl_block(seed: int) -> list:
    """The APL patches of the ``apl`` plan, in a seeded random order, without references.

    White and mid grey on black at each of :data:`APL_WINDOWS` and full field,
    and white and mid grey in a :data:`APL_SMALL_WINDOW` window on each grey of
    :data:`APL_SURROUNDS`.
    """
    grey = (_APL_GREY,) * 3
    patches = [Patch("grey", rgb, window) for window in APL_WINDOWS for rgb in (_WHITE, grey)]
    patches.append(Patch("grey", grey))  # the mid grey full field (its reference load)
    patches += [Patch("grey", rgb, APL_SMALL_WINDOW, (level,) * 3)
                for level in APL_SURROUNDS for rgb in (_WHITE, grey)]
    order = np.random.default_rng([int(seed), 0xA91]).permutation(len(patches))
    return [patches[i] for i in order]


def _with_drift_references(patches: list, interval: int = DRIFT_REFERENCE_INTERVAL) -> tuple:
    """Insert a white after every ``interval`` patches without one, and end on a white."""
    out, since_white = [], 0
    for patch in patches:
        out.append(patch)
        since_white = 0 if patch.kind == "white" else since_white + 1
        if since_white == interval:
            out.append(Patch("white", _WHITE))
            since_white = 0
    if out[-1].kind != "white":
        out.append(Patch("white", _WHITE))
    return tuple(out)


def _plan(name: str, levels, validation_count: int, seed: int) -> MeasurementPlan:
    patches = [Patch("black", _BLACK), Patch("white", _WHITE), *_ramps(levels),
               *_validation(validation_count, seed)]
    return MeasurementPlan(name, _with_drift_references(patches), seed)


def measurement_plan_paper(seed: int) -> MeasurementPlan:
    """The paper's plan: black, white, 5..255 step 5 per channel, 50 validation colours.

    Parameters
    ----------
    seed : int
        Seed of the validation colours (uniform over the 8-bit RGB cube).

    Returns
    -------
    MeasurementPlan
        214 patches: 1 black, 1 + 9 whites, 3 × 51 ramp levels, 50 validation.

    References
    ----------
    Díaz-Barrancas et al. (2020), Sensors 20(19) 5658, section 2.
    """
    return _plan("paper", range(5, 256, 5), 50, seed)


def measurement_plan_quick(seed: int) -> MeasurementPlan:
    """A fast look: black, white, 51..255 step 51 per channel, 10 validation colours (28 patches)."""
    return _plan("quick", range(51, 256, 51), 10, seed)


def measurement_plan_apl(seed: int) -> MeasurementPlan:
    """The ``apl`` plan: APL patches (:func:`apl_block`) with full-field white references between.

    Parameters
    ----------
    seed : int
        Seeds the order of the APL patches.

    Returns
    -------
    MeasurementPlan
        31 patches: 6 full-field whites (first, last and after every
        :data:`APL_REFERENCE_INTERVAL` patches of the block), 24 APL patches
        and the mid grey full field.
    """
    patches = [Patch("white", _WHITE), *apl_block(seed)]
    return MeasurementPlan("apl", _with_drift_references(patches, APL_REFERENCE_INTERVAL), seed)


def measurement_plan_paper_apl(seed: int) -> MeasurementPlan:
    """The paper's plan followed by the ``apl`` block (its APL patches with white references between)."""
    paper = measurement_plan_paper(seed).patches
    block = _with_drift_references([Patch("white", _WHITE), *apl_block(seed)], APL_REFERENCE_INTERVAL)
    return MeasurementPlan("paper+apl", paper + block[1:], seed)


def measurement_plan_paper_greys(seed: int) -> MeasurementPlan:
    """The paper's plan with a grey ramp and partial-drive mixtures among the fit rows.

    Parameters
    ----------
    seed : int
        Seed of the validation colours (the same colours as ``paper`` with this seed).

    Returns
    -------
    MeasurementPlan
        254 patches: 1 black, 1 + 10 whites, 3 × 51 ramp levels, 15 greys
        (:data:`GREY_LEVELS`), 24 mixtures (:data:`MIXTURE_LEVELS`), 50
        validation colours, in that order with the drift references between.
    """
    greys = [Patch("grey", (level,) * 3) for level in GREY_LEVELS]
    mixtures = [Patch("mixture", (r, g, b)) for r in MIXTURE_LEVELS for g in MIXTURE_LEVELS
                for b in MIXTURE_LEVELS if not r == g == b]
    patches = [Patch("black", _BLACK), Patch("white", _WHITE), *_ramps(range(5, 256, 5)),
               *greys, *mixtures, *_validation(50, seed)]
    return MeasurementPlan("paper+greys", _with_drift_references(patches), seed)


def measurement_plan_authors_2024(seed: int) -> MeasurementPlan:
    """The seed authors' own measurement protocol: channel sweeps and a grey ramp every 5 DAC.

    Their public code (rkl-gilro/ColorCharacterization,
    ``src/HMD_ColourCharacterisation.m``) measures the red, green and blue
    channels and a grey (r = g = b) at DAC 0, 5, …, 255, one white and a set of
    random validation colours; the grey ramp carries the tone curves of their
    model (:mod:`workbench.diagnostics.authors`). Here the four DAC-0 levels
    are one ``black`` patch, the sweeps (kinds ``ramp-r``, ``ramp-g``,
    ``ramp-b``) run over :data:`AUTHORS_2024_LEVELS`, the grey ramp (kind
    ``grey``) over 5..250 and its 255 level is a ``white``, and the validation
    colours are the ``paper`` plan's for the same seed.

    Their protocol measures a single white; this plan keeps the ``paper``
    plan's drift references (a white after every
    :data:`DRIFT_REFERENCE_INTERVAL` patches), which the diagnosis needs to
    test ``temporal-drift`` and to correct for it.

    The grey ramp is measured last, closed by its white, which ends the plan:
    the greys carry the exported tone curves (the authors' method's and the
    workbench's grey ramp), and a drift-corrected profile describes the display
    in the state of the last two whites (the warmed-up display, for a warm-up).
    Measured there, the greys need little correcting, and the correction's own
    noise (each white read with the instrument's noise) reaches them least.
    With the greys before the validation colours, on the peer bench's
    ``authors-2024`` sessions of seeds 63000–63009, 64000–, 65000– and 66000–
    (920 sessions, 300 hidden colours each), the exported profile was worse
    than the authors' method by more than 0.01 ΔE00 on 6; with the greys last
    on 3, and the drift forms' mean hidden error fell (a wander 0.087 → 0.068
    and 0.089 → 0.081, a decline 0.072 → 0.057 and 0.075 → 0.071). With a
    fifth set measured after the change (68000–, 1150 sessions in all): 7 → 5
    worse than the authors' method, and sessions with a finding not injected
    8 → 16 (docs/diagnostics/peers.md says which, and why).

    Parameters
    ----------
    seed : int
        Seed of the validation colours (the same colours as ``paper`` with this seed).

    Returns
    -------
    MeasurementPlan
        266 patches: 1 black, 3 × 51 ramp levels, 50 validation colours, 50
        greys (5..250) and 12 whites (the first, 10 drift references and the
        grey ramp's 255, which ends the plan), in the order black, white, red,
        green, blue, validation, greys, white.

    References
    ----------
    Díaz-Barrancas et al. (2020), Sensors 20(19) 5658; code:
    github.com/rkl-gilro/ColorCharacterization (``src/HMD_ColourCharacterisation.m``).
    """
    greys = [Patch("grey", (level,) * 3) for level in AUTHORS_2024_LEVELS if level < 255]
    patches = [Patch("black", _BLACK), Patch("white", _WHITE), *_ramps(AUTHORS_2024_LEVELS),
               *_validation(50, seed), *greys, Patch("white", _WHITE)]
    return MeasurementPlan("authors-2024", _with_drift_references(patches), seed)


MEASUREMENT_PLANS = {
    "paper": measurement_plan_paper,
    "quick": measurement_plan_quick,
    "apl": measurement_plan_apl,
    "paper+apl": measurement_plan_paper_apl,
    "paper+greys": measurement_plan_paper_greys,
    "authors-2024": measurement_plan_authors_2024,
}
"""Built-in plans by name: each a function of the validation seed."""


def measurement_plan(name: str, seed: int) -> MeasurementPlan:
    """The built-in plan ``name`` with validation colours drawn from ``seed``.

    Raises
    ------
    InputError
        For an unknown name; the message lists the valid ones.
    """
    try:
        build = MEASUREMENT_PLANS[name]
    except KeyError:
        raise InputError(
            f"unknown measurement plan {name!r}; use one of {', '.join(MEASUREMENT_PLANS)}, "
            "or --plan-file FILE with columns kind,r,g,b"
        ) from None
    return build(int(seed))


EMPTY_PLAN_HINT = ("a follow-up plan written by `diagnose --follow-up` has only its header when "
                   "the diagnosis left nothing a measurement could identify: there is nothing to measure")
"""What a header-only plan file means, for the messages that meet one."""


def read_plan_file(path: str | os.PathLike, allow_empty: bool = False) -> MeasurementPlan:
    """Read a plan from a CSV file with a header ``kind,r,g,b`` (any order, any case).

    Parameters
    ----------
    path : path-like
        One row per patch, in the order to show them; ``kind`` is a session
        kind, ``r,g,b`` are integer DAC values 0..255; optional ``window`` (the
        patch's fraction of the field, default 1) and ``sr,sg,sb`` (the
        surround's DAC values, default 0) make APL patches.
    allow_empty : bool
        Return a plan without patches for a file that holds only its header
        (an empty follow-up, :func:`write_plan_file`) instead of refusing it.

    Returns
    -------
    MeasurementPlan
        Named after the file; shown exactly as listed (no drift references added).

    Raises
    ------
    SpectrumFileError
        Naming the file, the line and the fix.
    """
    path = Path(path)
    if not path.is_file():
        raise SpectrumFileError(path, None, "no such plan file", "check the path given to --plan-file")
    patches = []
    with path.open(newline="", encoding="utf-8-sig") as handle:
        reader = csv.reader(handle)
        header = next(reader, None)
        if header is None:
            raise SpectrumFileError(path, 1, "the file is empty", "write a header row kind,r,g,b then one row per patch")
        columns = {name.strip().lower(): i for i, name in enumerate(header)}
        missing = [name for name in ("kind", "r", "g", "b") if name not in columns]
        if missing:
            raise SpectrumFileError(path, 1, f"the header lacks column(s) {missing}",
                                    "the first row must name the columns kind,r,g,b (any order, any case)")
        surround_columns = [c for c in ("sr", "sg", "sb") if c in columns]
        if surround_columns and len(surround_columns) != 3:
            raise SpectrumFileError(path, 1, f"the header has {surround_columns} but not all of sr,sg,sb",
                                    "give the surround as three columns sr,sg,sb or none")
        for line, row in enumerate(reader, start=2):
            if not row or all(not cell.strip() for cell in row):
                continue
            if len(row) < len(header):
                raise SpectrumFileError(path, line, f"the row has {len(row)} fields, the header {len(header)}",
                                        "give every row a kind and three DAC values")
            kind = row[columns["kind"]].strip().lower()
            if kind not in SESSION_KINDS:
                raise SpectrumFileError(path, line, f"unknown kind {kind!r}", f"use one of {', '.join(SESSION_KINDS)}")
            rgb = []
            for channel in ("r", "g", "b", *surround_columns):
                text = row[columns[channel]].strip()
                try:
                    value = int(text)
                except ValueError:
                    value = None
                if value is None or not 0 <= value <= 255:
                    raise SpectrumFileError(path, line, f"column {channel!r} holds {text!r}",
                                            "write an integer DAC value 0..255")
                rgb.append(value)
            window = 1.0
            if "window" in columns:
                text = row[columns["window"]].strip()
                try:
                    window = float(text)
                except ValueError:
                    window = float("nan")
                if not 0 < window <= 1:
                    raise SpectrumFileError(path, line, f"column 'window' holds {text!r}",
                                            "write the patch's fraction of the field, 0 < window <= 1")
            surround = tuple(rgb[3:]) if surround_columns else (0, 0, 0)
            patches.append(Patch(kind, tuple(rgb[:3]), window, surround))
    if not patches and not allow_empty:
        raise SpectrumFileError(path, None, "the file has a header but no patches, so there is nothing to measure",
                                f"add one row kind,r,g,b per patch ({EMPTY_PLAN_HINT})")
    return MeasurementPlan(str(path), tuple(patches), None)


def write_plan_file(patches, path: str | os.PathLike) -> Path:
    """Write ``patches`` (a plan or a sequence of :class:`Patch`) as a plan file; returns the path.

    The columns are ``kind,r,g,b``, and ``window,sr,sg,sb`` too where a
    patch is shown as a window or on a lit surround; :func:`read_plan_file`
    reads the file back to the same patches. No patches: a header-only file
    (which :func:`read_plan_file` reads only with ``allow_empty``). Written
    atomically: a reader never sees half a plan.
    """
    patches = tuple(patches.patches if isinstance(patches, MeasurementPlan) else patches)
    apl = any(p.is_apl or any(p.surround) for p in patches)
    path = Path(path)
    with atomic_writer(path, newline="") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(["kind", "r", "g", "b", *(("window", "sr", "sg", "sb") if apl else ())])
        for patch in patches:
            writer.writerow([patch.kind, *(int(v) for v in patch.rgb),
                             *((f"{patch.window:g}", *(int(v) for v in patch.surround)) if apl else ())])
    return path
