"""Display gamuts on a chromaticity diagram, and how much of a reference gamut a display covers.

- Diagrams (:data:`DIAGRAMS`): CIE 1931 ``xy`` and CIE 1976 ``u'v'`` (the
  more perceptually uniform one, where areas compare better), colour-science's
  conversions.
- The spectral locus from the CIE 1931 2° colour-matching functions.
- Reference gamuts (:data:`REFERENCE_GAMUTS`): sRGB, DCI-P3 and Rec. 2020
  primaries from ``colour.RGB_COLOURSPACES``.
- A display's gamut (:func:`display_gamut`): the convex hull of the
  chromaticities of the surface of its RGB cube through its forward model, so
  a model with channel interaction or a black offset gets its real outline,
  not only the triangle of its primaries.
- Coverage (:func:`gamut_coverage`): the share of a reference gamut's area
  that the display's gamut covers (area of the intersection over the
  reference's area) and the display's gamut area relative to the reference's,
  in the chosen diagram.
- Validation colours (:func:`validation_points`): measured vs predicted
  chromaticities of a session's validation patches.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import colour
import numpy as np
from scipy.spatial import ConvexHull

from workbench.colorimetry import observer_cmfs
from workbench.display import DisplayModel
from workbench.errors import InputError

__all__ = [
    "DIAGRAMS",
    "REFERENCE_GAMUTS",
    "LOCUS_LABELS_NM",
    "Gamut",
    "Coverage",
    "ValidationPoints",
    "to_diagram",
    "spectral_locus",
    "reference_gamut",
    "display_gamut",
    "polygon_area",
    "clip_convex",
    "gamut_coverage",
    "validation_points",
    "shipped_profile_gamuts",
]


def _xy(XYZ):
    return colour.XYZ_to_xy(np.asarray(XYZ, dtype=float))


def _xy_to_XYZ(xy):
    return colour.xy_to_XYZ(np.asarray(xy, dtype=float))


DIAGRAMS = {
    "xy": ("CIE 1931 x", "CIE 1931 y", _xy),
    "u'v'": ("CIE 1976 u′", "CIE 1976 v′", lambda XYZ: colour.xy_to_Luv_uv(_xy(XYZ))),
}
"""Diagram id → (horizontal axis label, vertical axis label, XYZ → coordinates)."""

REFERENCE_GAMUTS = {"sRGB": "sRGB", "DCI-P3": "DCI-P3", "Rec. 2020": "ITU-R BT.2020"}
"""Reference gamut name → colour-science colourspace name."""

LOCUS_LABELS_NM = (460, 480, 490, 500, 520, 540, 560, 580, 600, 620)
"""Wavelengths labelled on the spectral locus."""


def _check_diagram(diagram: str) -> None:
    if diagram not in DIAGRAMS:
        raise InputError(f"unknown chromaticity diagram {diagram!r}; use one of {list(DIAGRAMS)}")


def to_diagram(XYZ, diagram: str = "xy") -> np.ndarray:
    """Chromaticity coordinates of ``XYZ`` (…, 3) in ``diagram``."""
    _check_diagram(diagram)
    return np.asarray(DIAGRAMS[diagram][2](XYZ), dtype=float)


@dataclass(frozen=True, eq=False)
class Gamut:
    """A gamut outline: its name and polygon vertices (counter-clockwise) in CIE 1931 xy."""

    name: str
    xy: np.ndarray

    def vertices(self, diagram: str = "xy") -> np.ndarray:
        """The outline in ``diagram`` (straight edges stay straight: both maps are projective)."""
        return to_diagram(_xy_to_XYZ(self.xy), diagram)


@dataclass(frozen=True)
class Coverage:
    """How much of ``reference`` the display covers in ``diagram``.

    ``covered_pct``: area of (display ∩ reference) / area of reference × 100.
    ``relative_area_pct``: area of display / area of reference × 100 (can exceed 100).
    """

    reference: str
    diagram: str
    covered_pct: float
    relative_area_pct: float


@dataclass(frozen=True, eq=False)
class ValidationPoints:
    """Validation patches: measured and predicted chromaticity (CIE 1931 xy) and the model used."""

    measured_xy: np.ndarray
    predicted_xy: np.ndarray
    model: str

    def __len__(self) -> int:
        return len(self.measured_xy)


def spectral_locus(diagram: str = "xy", start_nm: float = 380.0, end_nm: float = 700.0
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Wavelengths and coordinates of the spectral locus (CIE 1931 2°) in ``diagram``."""
    cmfs = observer_cmfs("cie1931-2")
    wavelengths = np.asarray(cmfs.wavelengths)
    keep = (wavelengths >= start_nm) & (wavelengths <= end_nm)
    return wavelengths[keep], to_diagram(cmfs.values[keep], diagram)


def reference_gamut(name: str) -> Gamut:
    """sRGB, DCI-P3 or Rec. 2020 (:data:`REFERENCE_GAMUTS`)."""
    if name not in REFERENCE_GAMUTS:
        raise InputError(f"unknown reference gamut {name!r}; use one of {list(REFERENCE_GAMUTS)}")
    primaries = np.asarray(colour.RGB_COLOURSPACES[REFERENCE_GAMUTS[name]].primaries, dtype=float)
    return Gamut(name, _counter_clockwise(primaries))


def _counter_clockwise(points: np.ndarray) -> np.ndarray:
    return points if _signed_area(points) >= 0 else points[::-1]


def _signed_area(points: np.ndarray) -> float:
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def polygon_area(points) -> float:
    """Area of a simple polygon (shoelace formula)."""
    points = np.asarray(points, dtype=float)
    return abs(_signed_area(points)) if len(points) >= 3 else 0.0


def clip_convex(subject, clip) -> np.ndarray:
    """Intersection of convex polygon ``subject`` with convex polygon ``clip`` (Sutherland–Hodgman)."""
    output = [np.asarray(p, dtype=float) for p in subject]
    clip = _counter_clockwise(np.asarray(clip, dtype=float))
    for a, b in zip(clip, np.roll(clip, -1, axis=0)):
        if not output:
            break
        edge = b - a
        inside = [edge[0] * (p[1] - a[1]) - edge[1] * (p[0] - a[0]) >= 0 for p in output]
        clipped = []
        for i, p in enumerate(output):
            q, q_in, p_in = output[i - 1], inside[i - 1], inside[i]
            if p_in != q_in:  # the edge q→p crosses the clip line
                d = p - q
                denom = edge[0] * d[1] - edge[1] * d[0]
                t = (edge[1] * (q[0] - a[0]) - edge[0] * (q[1] - a[1])) / denom
                clipped.append(q + t * d)
            if p_in:
                clipped.append(p)
        output = clipped
    return np.array(output).reshape(-1, 2)


def display_gamut(display: DisplayModel, name: str = "display", samples: int = 17) -> Gamut:
    """The gamut outline of ``display``: convex hull of its RGB cube surface's chromaticities."""
    levels = np.linspace(0.0, 255.0, samples)
    a, b = np.meshgrid(levels, levels)
    a, b = a.ravel(), b.ravel()
    faces = []
    for axis in range(3):
        for value in (0.0, 255.0):
            face = np.empty((a.size, 3))
            face[:, axis] = value
            others = [i for i in range(3) if i != axis]
            face[:, others[0]], face[:, others[1]] = a, b
            faces.append(face)
    rgb = np.vstack(faces)
    rgb = rgb[rgb.max(axis=1) > 0]  # the black corner alone has only the display's black
    XYZ = display.forward(rgb)
    XYZ = XYZ[XYZ.sum(axis=1) > 0]
    xy = _xy(XYZ)
    hull = ConvexHull(xy)
    return Gamut(name, _counter_clockwise(xy[hull.vertices]))


def gamut_coverage(gamut: Gamut, reference: Gamut, diagram: str = "xy") -> Coverage:
    """Share of ``reference`` that ``gamut`` covers, and their area ratio, in ``diagram``."""
    mine, theirs = gamut.vertices(diagram), reference.vertices(diagram)
    reference_area = polygon_area(theirs)
    covered = polygon_area(clip_convex(mine, theirs))
    return Coverage(reference=reference.name, diagram=diagram,
                    covered_pct=100.0 * covered / reference_area,
                    relative_area_pct=100.0 * polygon_area(mine) / reference_area)


def validation_points(diagnosis=None, session=None, display: DisplayModel | None = None
                      ) -> ValidationPoints | None:
    """Measured vs predicted chromaticities of the validation patches, or None without any.

    With a diagnosis: its session's validation rows, predicted by the
    extended model the diagnosis chose. Else ``session``'s validation rows
    predicted by ``display`` (the profile). None when there are no validation rows.
    """
    if diagnosis is not None:
        session, display, model = diagnosis.session, diagnosis.extended, "extended model"
    else:
        model = "profile"
    if session is None or display is None or len(session) == 0:
        return None
    rows = session.select("validation")
    if len(rows) == 0:
        return None
    measured = np.asarray(rows.XYZ, dtype=float)
    predicted = display.forward(np.asarray(rows.rgb, dtype=float))
    keep = (measured.sum(axis=1) > 0) & (predicted.sum(axis=1) > 0)
    return ValidationPoints(measured_xy=_xy(measured[keep]), predicted_xy=_xy(predicted[keep]),
                            model=f"{model}: {display.describe()}")


def shipped_profile_gamuts(directory=None) -> list[tuple[Path, Gamut]]:
    """The gamut of every ``*.vrprofile.json`` in ``directory`` (default: the shipped profiles)."""
    from profiles import PROFILES_DIR
    from workbench.profile import load_profile

    directory = Path(directory) if directory is not None else PROFILES_DIR
    gamuts = []
    for path in sorted(directory.glob("*.vrprofile.json")):
        profile = load_profile(path)
        gamuts.append((path, display_gamut(profile.display_model(),
                                           profile.device.get("name") or path.stem)))
    return gamuts
