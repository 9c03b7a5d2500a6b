"""Generated hyperspectral Ishihara plates: plate types, specs, the paper's 10-plate set.

A plate is a label image (dot id per pixel, 0 = paper) and one reflectance
spectrum per dot: a palette colour (:mod:`workbench.ishihara.palette`) times a
random lightness factor. :meth:`Plate.cube` expands it to an ``(H, W, 401)``
reflectance cube when one is needed; everything else works on the dots.

Plate types (:data:`PLATE_TYPES`, Ishihara's instructions), with the colours
each region of the plate gets (``A``: what a normal observer reads, ``B``: what
protans and deutans read):

``demonstration``
    Figure ``purple`` on a ``green-p``/``green-d`` background: red–green *and*
    blue–yellow contrast, read by everyone.
``transformation``
    ``A ∩ B`` purple, ``A \\ B`` ochre, ``B \\ A`` blue-green (p or d), the rest
    green (p or d). A normal observer groups by red–green (ochre and purple
    against the greens) and reads A; for a protan or deutan ochre merges with
    the greens and blue-green with purple, so the dominant difference is the S
    shift and they read B.
``vanishing``
    Figure ochre on green-p/green-d: normal observers read it; each dichromat
    sees the ochre merge with one of the two greens, so no digit emerges.
``hidden-digit``
    Figure purple/blue-green on an ochre/green background: the normal
    observer's strong red–green mosaic masks the S-shift figure, which the
    red–green deficient observer sees.
``classification``
    Two digits on a bluish-green background: the one protans cannot see in
    ``red-protan`` (on the background's protan line), the one deutans cannot
    see in ``red-deutan``.

Scale: image pixels (square plates, the disc centred); reflectance on 0..1 at
the working wavelengths (380–780 nm, 1 nm).

References
----------
Ishihara, S. *Ishihara's Tests for Colour Deficiency*, 38 Plates Edition,
Kanehara Trading: "Explanation of the plates" (plate types and answers).

Díaz-Barrancas et al. (2020), Table 6 (the 10-plate set and its reference
answers, :mod:`workbench.ishihara.paper`).
"""

from __future__ import annotations

import json
import zipfile
import zlib
from dataclasses import asdict, dataclass
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Callable

import numpy as np

from workbench.colorimetry import WORKING_WAVELENGTHS
from workbench.errors import InputError, SpectrumFileError
from workbench.fileio import atomic_writer
from workbench.ishihara.glyphs import text_mask
from workbench.ishihara.packing import DotLayout, pack_dots
from workbench.ishihara.palette import Palette, design_palette
from workbench.ishihara.paper import PAPER_TABLE5, PAPER_TABLE6_REFERENCE
from workbench.ishihara.reading import NOTHING_READ, dots_in_mask

__all__ = [
    "DEFAULT_PLATE_SIZE",
    "DEFAULT_SEED",
    "PAPER_REFLECTANCE",
    "PLATE_FILE_VERSION",
    "PlateSpec",
    "PlateType",
    "PLATE_TYPES",
    "Plate",
    "infer_plate_kind",
    "paper_plate_set_specs",
    "generate_plate",
    "generate_plate_set",
    "PAPER_FAMILY_OF_COLOUR",
    "paper_coloured_plate",
    "save_plate",
    "load_plate",
    "plate_preview_srgb8",
    "write_plate_preview",
]

DEFAULT_PLATE_SIZE = 192
"""Plate image size (pixels) of generated plates unless told otherwise."""

DEFAULT_SEED = 1917
"""Base seed of the paper set (plate N uses ``seed + N``); 1917, Ishihara's first edition."""

PAPER_REFLECTANCE = 0.8
"""Spectrally flat reflectance of the card between the dots (a matte white card)."""

PLATE_FILE_VERSION = 1


@dataclass(frozen=True)
class PlateSpec:
    """What a plate shows and how each observer should read it.

    Attributes
    ----------
    number : int
        Position in its set (1-based).
    kind : str
        A key of :data:`PLATE_TYPES`.
    normal, protan, deutan : str
        What a normal, a protan and a deutan observer read (``"-"``: nothing).
    """

    number: int
    kind: str
    normal: str
    protan: str
    deutan: str

    def expected(self, deficiency: str) -> str:
        """The answer of an observer with ``deficiency`` (``"tritan"`` reads as normal)."""
        if deficiency in ("normal", "tritan"):
            return self.normal
        if deficiency in ("protan", "deutan"):
            return getattr(self, deficiency)
        raise InputError(f"no expected answer for {deficiency!r}; use normal, protan or deutan")


@dataclass(frozen=True)
class PlateType:
    """One kind of plate.

    Attributes
    ----------
    kind : str
    description : str
    check : callable
        ``check(spec)`` raises :class:`InputError` when the answers do not fit the kind.
    assign : callable
        ``assign(spec, layout, rng) → dot colour names`` (one palette name per dot).
    """

    kind: str
    description: str
    check: Callable
    assign: Callable


def _digits(text: str, what: str, spec: PlateSpec) -> str:
    if not (text.isdigit() and 1 <= len(text) <= 2):
        raise InputError(f"plate {spec.number} ({spec.kind}): {what} {text!r} must be one or two "
                         "digits")
    return text


def _in_text(layout: DotLayout, text: str, slot: str | None = None) -> np.ndarray:
    return dots_in_mask(layout, text_mask(text, layout.size, slot))


def _pick(rng, choices, count) -> np.ndarray:
    return np.asarray(choices, dtype=object)[rng.integers(0, len(choices), count)]


_GREENS = ("green-p", "green-d")
_BLUE_GREENS = ("blue-green-p", "blue-green-d")


def _check_demonstration(spec: PlateSpec) -> None:
    _digits(spec.normal, "the answer", spec)
    if not spec.normal == spec.protan == spec.deutan:
        raise InputError(f"plate {spec.number}: a demonstration plate is read alike by everyone; "
                         f"got {spec.normal!r}, {spec.protan!r}, {spec.deutan!r}")


def _assign_demonstration(spec: PlateSpec, layout: DotLayout, rng) -> np.ndarray:
    colours = _pick(rng, _GREENS, layout.count)
    colours[_in_text(layout, spec.normal)] = "purple"
    return colours


def _check_transformation(spec: PlateSpec) -> None:
    _digits(spec.normal, "the normal answer", spec)
    _digits(spec.protan, "the protan answer", spec)
    if spec.protan != spec.deutan or spec.protan == spec.normal:
        raise InputError(f"plate {spec.number}: a transformation plate is read one way by normal "
                         f"observers and another, the same, by protans and deutans; got "
                         f"{spec.normal!r}, {spec.protan!r}, {spec.deutan!r}")


def _assign_transformation(spec: PlateSpec, layout: DotLayout, rng) -> np.ndarray:
    in_a, in_b = _in_text(layout, spec.normal), _in_text(layout, spec.protan)
    colours = _pick(rng, _GREENS, layout.count)
    colours[in_b & ~in_a] = _pick(rng, _BLUE_GREENS, int(np.sum(in_b & ~in_a)))
    colours[in_a & ~in_b] = "ochre"
    colours[in_a & in_b] = "purple"
    return colours


def _check_vanishing(spec: PlateSpec) -> None:
    _digits(spec.normal, "the normal answer", spec)
    if spec.protan != NOTHING_READ or spec.deutan != NOTHING_READ:
        raise InputError(f"plate {spec.number}: on a vanishing plate protans and deutans read "
                         f"nothing ('-'); got {spec.protan!r}, {spec.deutan!r}")


def _assign_vanishing(spec: PlateSpec, layout: DotLayout, rng) -> np.ndarray:
    colours = _pick(rng, _GREENS, layout.count)
    colours[_in_text(layout, spec.normal)] = "ochre"
    return colours


def _check_hidden(spec: PlateSpec) -> None:
    _digits(spec.protan, "the protan answer", spec)
    if spec.normal != NOTHING_READ or spec.protan != spec.deutan:
        raise InputError(f"plate {spec.number}: on a hidden-digit plate normal observers read "
                         f"nothing and protans and deutans the same digits; got {spec.normal!r}, "
                         f"{spec.protan!r}, {spec.deutan!r}")


def _assign_hidden(spec: PlateSpec, layout: DotLayout, rng) -> np.ndarray:
    colours = _pick(rng, ("ochre",) + _GREENS, layout.count)
    figure = _in_text(layout, spec.protan)
    colours[figure] = _pick(rng, ("purple",) + _BLUE_GREENS, int(figure.sum()))
    return colours


def _check_classification(spec: PlateSpec) -> None:
    _digits(spec.normal, "the normal answer", spec)
    if len(spec.normal) != 2 or sorted(spec.protan + spec.deutan) != sorted(spec.normal) \
            or spec.protan == spec.deutan:
        raise InputError(f"plate {spec.number}: a classification plate shows two digits; protans "
                         f"read one, deutans the other; got {spec.normal!r}, {spec.protan!r}, "
                         f"{spec.deutan!r}")


def _assign_classification(spec: PlateSpec, layout: DotLayout, rng) -> np.ndarray:
    colours = np.full(layout.count, "bluish-green", dtype=object)
    for slot, digit in zip(("left", "right"), spec.normal):
        # the digit protans read is the one that vanishes for deutans, and vice versa
        colour = "red-deutan" if digit == spec.protan else "red-protan"
        colours[_in_text(layout, digit, slot)] = colour
    return colours


PLATE_TYPES = {
    "demonstration": PlateType("demonstration", "read alike by everyone",
                               _check_demonstration, _assign_demonstration),
    "transformation": PlateType("transformation", "normal and red-green deficient observers "
                                "read different digits", _check_transformation,
                                _assign_transformation),
    "vanishing": PlateType("vanishing", "normal observers read it, red-green deficient do not",
                           _check_vanishing, _assign_vanishing),
    "hidden-digit": PlateType("hidden-digit", "red-green deficient observers read it, normal "
                              "do not", _check_hidden, _assign_hidden),
    "classification": PlateType("classification", "protans read one digit, deutans the other",
                                _check_classification, _assign_classification),
}
"""Plate kind → :class:`PlateType`."""


def _plate_type(kind: str) -> PlateType:
    try:
        return PLATE_TYPES[kind]
    except KeyError:
        raise InputError(f"unknown plate kind {kind!r}; use one of {sorted(PLATE_TYPES)}") from None


def infer_plate_kind(normal: str, protan: str, deutan: str) -> str:
    """The plate kind whose answers are ``normal``, ``protan``, ``deutan``."""
    if protan != deutan:
        return "classification"
    if normal == protan:
        return "demonstration"
    if protan == NOTHING_READ:
        return "vanishing"
    if normal == NOTHING_READ:
        return "hidden-digit"
    return "transformation"


def paper_plate_set_specs() -> tuple:
    """The 10-plate set of the paper: specs from Table 6's reference answers (Ref1–Ref3)."""
    rows = {r.qualification: r.answers for r in PAPER_TABLE6_REFERENCE}
    specs = []
    for i, answers in enumerate(zip(rows["normal"], rows["protan"], rows["deutan"]), start=1):
        spec = PlateSpec(i, infer_plate_kind(*answers), *answers)
        _plate_type(spec.kind).check(spec)
        specs.append(spec)
    return tuple(specs)


@dataclass(frozen=True, eq=False)
class Plate:
    """A generated plate.

    Attributes
    ----------
    spec : PlateSpec
    layout : DotLayout
        Label image and dot geometry.
    dot_colours : tuple of str
        Palette colour of each dot (N,).
    dot_lightness : ndarray, shape (N,)
        Factor each dot's palette reflectance is scaled by.
    dot_reflectances : ndarray, shape (N, 401)
        Reflectance of each dot (0..1).
    paper_reflectance : ndarray, shape (401,)
        Reflectance of the card between the dots.
    seed : int
    """

    spec: PlateSpec
    layout: DotLayout
    dot_colours: tuple
    dot_lightness: np.ndarray
    dot_reflectances: np.ndarray
    paper_reflectance: np.ndarray
    seed: int

    @property
    def size(self) -> int:
        return self.layout.size

    @property
    def labels(self) -> np.ndarray:
        return self.layout.labels

    @cached_property
    def colour_names(self) -> tuple:
        """The distinct palette colours on the plate, sorted."""
        return tuple(sorted(set(self.dot_colours)))

    def cube(self, dtype=np.float32) -> np.ndarray:
        """The plate as a reflectance cube ``(H, W, 401)`` (paper where there is no dot).

        A 192-pixel plate takes 59 MB in float32.
        """
        table = np.vstack([self.paper_reflectance[None, :], self.dot_reflectances]).astype(dtype)
        return table[self.layout.labels]


def generate_plate(spec: PlateSpec, size: int = DEFAULT_PLATE_SIZE, seed: int | None = None,
                   palette: Palette | None = None) -> Plate:
    """Generate the plate ``spec`` describes.

    Parameters
    ----------
    spec : PlateSpec
    size : int
        Image size in pixels (64 or more; 128–256 is plenty for reading).
    seed : int, optional
        Seed of the dots and their colours (default ``DEFAULT_SEED + spec.number``).
    palette : Palette, optional
        Default: :func:`design_palette`.
    """
    plate_type = _plate_type(spec.kind)
    plate_type.check(spec)
    seed = DEFAULT_SEED + spec.number if seed is None else int(seed)
    palette = palette or design_palette()
    layout = pack_dots(size, seed)
    rng = np.random.default_rng([seed, 1])
    colours = plate_type.assign(spec, layout, rng)
    lightness = rng.uniform(*palette.lightness_range, layout.count)
    reflectances = palette.reflectances(colours) * lightness[:, None]
    return Plate(spec=spec, layout=layout, dot_colours=tuple(str(c) for c in colours),
                 dot_lightness=lightness, dot_reflectances=reflectances,
                 paper_reflectance=np.full(WORKING_WAVELENGTHS.size, PAPER_REFLECTANCE), seed=seed)


@lru_cache(maxsize=8)
def generate_plate_set(size: int = DEFAULT_PLATE_SIZE, seed: int = DEFAULT_SEED) -> tuple:
    """The paper's 10-plate set (:func:`paper_plate_set_specs`), generated; cached."""
    return tuple(generate_plate(spec, size, seed + spec.number) for spec in paper_plate_set_specs())


PAPER_FAMILY_OF_COLOUR = {
    "green-p": "green", "green-d": "green", "ochre": "ochre", "purple": "purple",
    "blue-green-p": "bluish-green", "blue-green-d": "bluish-green", "bluish-green": "bluish-green",
}
"""Designed palette colour → the family of the paper's Table 5 it was derived from."""


def paper_coloured_plate(plate: Plate, palette: Palette | None = None) -> Plate:
    """``plate`` with its dots in the paper's own ten colours (Table 5's P1–P10).

    Each dot takes a colour of the family its designed colour comes from
    (:data:`PAPER_FAMILY_OF_COLOUR`: greens → P1–P3, ochre → P4–P6, purple →
    P7–P8, blue-greens → P9–P10). Within a family the dots, ranked by their
    lightness factor, are dealt out to the family's colours from the darkest
    to the lightest in equal shares, so the plate keeps its figure, its
    lightness mosaic and its layout. The dots' lightness factors become 1: the
    paper's colours carry their own luminance factors. Plate 3 of the paper's
    set (a transformation plate) uses all ten, like the paper's plate 3.

    Raises
    ------
    InputError
        A dot colour with no family in Table 5 (the classification plate's reds).
    """
    palette = palette or design_palette()
    colours = np.asarray(plate.dot_colours, dtype=object)
    unknown = sorted(set(colours) - set(PAPER_FAMILY_OF_COLOUR))
    if unknown:
        raise InputError(f"plate {plate.spec.number} ({plate.spec.kind}) has dot colours "
                         f"{unknown} with no family among the paper's Table 5 colours; use a "
                         "plate without them (e.g. plate 3)")
    families = np.array([PAPER_FAMILY_OF_COLOUR[c] for c in colours], dtype=object)
    recoloured = np.empty(len(colours), dtype=object)
    for family in sorted(set(families)):
        members = np.flatnonzero(families == family)
        dots = sorted((d for d in PAPER_TABLE5 if d.family == family),
                      key=lambda d: d.calculated_xyY[2])
        ranked = members[np.argsort(plate.dot_lightness[members], kind="stable")]
        for share, dot in zip(np.array_split(ranked, len(dots)), dots):
            recoloured[share] = dot.dot
    names = tuple(str(c) for c in recoloured)
    return Plate(spec=plate.spec, layout=plate.layout, dot_colours=names,
                 dot_lightness=np.ones(len(names)), dot_reflectances=palette.reflectances(names),
                 paper_reflectance=plate.paper_reflectance, seed=plate.seed)


def save_plate(plate: Plate, path) -> Path:
    """Write ``plate`` as a compressed ``.npz``, atomically (:func:`workbench.fileio.atomic_writer`).

    Arrays: ``labels`` (H, W) uint16, ``dot_reflectances`` (N, 401) float32,
    ``wavelengths`` (401,) nm, ``paper_reflectance``, ``dot_colours``,
    ``dot_lightness``, ``dot_centres``, ``dot_radii``; ``spec`` and ``seed`` as
    JSON in ``meta``.
    """
    path = Path(path)
    if path.suffix != ".npz":
        raise InputError(f"{path}: plate files end in .npz")
    meta = {"version": PLATE_FILE_VERSION, "spec": asdict(plate.spec), "seed": plate.seed}
    with atomic_writer(path, "wb") as handle:
        np.savez_compressed(
            handle, labels=plate.layout.labels,
            dot_reflectances=plate.dot_reflectances.astype(np.float32),
            wavelengths=WORKING_WAVELENGTHS, paper_reflectance=plate.paper_reflectance,
            dot_colours=np.array(plate.dot_colours), dot_lightness=plate.dot_lightness,
            dot_centres=plate.layout.centres, dot_radii=plate.layout.radii,
            meta=np.array(json.dumps(meta)))
    return path


_PLATE_ARRAYS = ("labels", "dot_reflectances", "wavelengths", "paper_reflectance", "dot_colours",
                 "dot_lightness", "dot_centres", "dot_radii", "meta")


def load_plate(path) -> Plate:
    """Read a plate written by :func:`save_plate`, checking it.

    Raises
    ------
    SpectrumFileError
        Naming the file, the problem and the fix: no such file; not an
        ``.npz``, or one truncated or corrupted (a cut download, a full disk:
        no central directory, a bad CRC, a cut compressed stream); arrays
        missing or unreadable; a bad plate description; shapes, wavelengths or
        reflectances that do not make a plate.
    """
    path = Path(path)
    fix = "regenerate it with 'python -m workbench ishihara generate'"
    try:
        with np.load(path, allow_pickle=False) as data:
            missing = [k for k in _PLATE_ARRAYS if k not in data.files]
            if missing:
                raise SpectrumFileError(path, None, f"not a plate file: missing {missing}", fix)
            arrays = {k: data[k] for k in _PLATE_ARRAYS}
    except FileNotFoundError:
        raise SpectrumFileError(path, None, "no such file", "give the path of a plate .npz") from None
    except (zipfile.BadZipFile, zlib.error, EOFError) as error:
        # a truncated or corrupted archive: no central directory, a bad CRC, a cut stream
        raise SpectrumFileError(path, None, f"truncated or corrupted .npz ({error})",
                                fix) from None
    except (OSError, ValueError, KeyError) as error:
        raise SpectrumFileError(path, None, f"not a readable .npz ({error})", fix) from None
    try:
        meta = json.loads(str(arrays["meta"]))
        spec = PlateSpec(**meta["spec"])
    except (ValueError, TypeError, KeyError) as error:
        raise SpectrumFileError(path, None, f"bad plate description ({error})", fix) from None
    labels, reflectances = arrays["labels"], arrays["dot_reflectances"].astype(float)
    count = len(reflectances)
    problems = []
    if labels.ndim != 2 or labels.shape[0] != labels.shape[1]:
        problems.append(f"label image has shape {labels.shape}; plates are square")
    elif labels.max(initial=0) > count:
        problems.append(f"label image names dot {labels.max()} but there are {count} dots")
    if not np.array_equal(arrays["wavelengths"], WORKING_WAVELENGTHS):
        problems.append("wavelengths are not 380–780 nm at 1 nm")
    if reflectances.shape != (count, WORKING_WAVELENGTHS.size):
        problems.append(f"dot reflectances have shape {reflectances.shape}")
    elif not np.all(np.isfinite(reflectances)) or reflectances.min() < 0 or reflectances.max() > 1:
        problems.append("dot reflectances hold NaN or values outside [0, 1]")
    if any(len(arrays[k]) != count for k in ("dot_colours", "dot_lightness", "dot_radii")):
        problems.append("per-dot arrays disagree on the number of dots")
    if problems:
        raise SpectrumFileError(path, None, "; ".join(problems), fix)
    layout = DotLayout(size=int(labels.shape[0]), labels=labels.astype(np.uint16),
                       centres=arrays["dot_centres"], radii=arrays["dot_radii"])
    return Plate(spec=spec, layout=layout, dot_colours=tuple(str(c) for c in arrays["dot_colours"]),
                 dot_lightness=arrays["dot_lightness"], dot_reflectances=reflectances,
                 paper_reflectance=arrays["paper_reflectance"].astype(float), seed=int(meta["seed"]))


def plate_preview_srgb8(plate: Plate) -> np.ndarray:
    """The plate as 8-bit sRGB ``(H, W, 3)`` under D65, as the ideal sRGB display shows it."""
    from workbench.colour_management import authored_srgb8

    table = authored_srgb8(np.vstack([plate.paper_reflectance[None, :], plate.dot_reflectances]))
    return table[plate.layout.labels].astype(np.uint8)


def write_plate_preview(plate: Plate, path) -> Path:
    """Write :func:`plate_preview_srgb8` as a PNG (Pillow)."""
    from PIL import Image

    path = Path(path)
    with atomic_writer(path, "wb") as handle:
        Image.fromarray(plate_preview_srgb8(plate), mode="RGB").save(handle, format="PNG")
    return path
