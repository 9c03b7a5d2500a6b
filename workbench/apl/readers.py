"""Readers for real measurements of OLED displays whose output depends on the rest of the picture.

Both data sets are described in ``../shared/data/real/README.md`` (``oled-apl/``).

**Samsung OLED, BrainardLab ``.mat``** (``runParams``, ``allCondsData``; PR-650):
a 100 px grey target (``targetGrays``) on a 1920×1080 frame made of a uniform
"stabilizer" surround (``stabilizerGrays``), a static noise scene of mean
``sceneGrays`` inset 250 px from each edge (1420×580), a grey-1.0 "bias"
square (``biasSizes``) centred on the target, and a second 100 px target
(the unused right radiometer's, grey ``targetGrays[rightTargetGrayIndex-1]``)
300 px right of centre. The geometry is that of BrainardLab's
``SamsungOLEDCalibrator`` of that time (border 250 px, targets at ±300 px).
A session row is the target as a window of ``100²/1920·1080`` of the field on
a uniform surround whose linear drive gives the frame the same load as the
real frame (the load is all an APL curve depends on); the surround DAC value
uses the grey transfer fitted on the least-loaded condition. Rows are labelled
by stabilizer level and bias size for held-out tests.

**Dell AW3225QF QD-OLED, HDR10** (``toru-ver4/sample_code``; colorimeter):

- ``cc_measure_lumi-<L>_win-<W>.csv``: 18 ColorChecker colours shown one at a
  time as a window of W % of the screen on black, the chart's white at L cd/m².
  The file has no code values; they are reconstructed as the HDR10 signal
  (BT.2020 primaries, PQ) of the colour measured in the 3 % window at the same
  L (the least-loaded condition), scaled to 0..255. Load uses the PQ transfer
  with 1000 cd/m² as linear 1. Rows are labelled by window size.
- ``measure_<MODE>_<WIN>_patch.csv``: a white window at code value 16·k
  (k = 0..63, last 1023) covering WIN % of the screen, for one monitor preset.

Greys (R = G = B) are kind ``grey``, other colours ``mixture``; a full white
is kind ``white`` only when shown full field (a drift reference), otherwise
``grey``; DAC 0 is ``black``.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

import colour
import numpy as np

from workbench.errors import SpectrumFileError
from workbench.session import Session

__all__ = [
    "SAMSUNG_FRAME_PX",
    "read_samsung_apl_mat",
    "read_aw3225qf_colorchecker",
    "read_aw3225qf_white_windows",
    "is_samsung_apl_mat",
    "apl_session_reader",
    "preset_of_white_window_file",
]

SAMSUNG_FRAME_PX = (1920, 1080)
"""Frame of the Samsung OLED measurements (pixels)."""

_SAMSUNG_BORDER_PX = 250
_SAMSUNG_TARGET_PX = 100
_PQ_PEAK_CD_M2 = 1000.0
_CC_FILE = re.compile(r"^cc_measure_lumi-(\d+)_win-(\d+)\.csv$", re.IGNORECASE)
_WINDOW_FILE = re.compile(r"^measure_(.+)_(\d{3})_patch(\d*)\.csv$", re.IGNORECASE)
_CMFS = "CIE 1931 2 Degree Standard Observer"


def _kind(rgb: np.ndarray, window: float, surround: np.ndarray) -> str:
    if np.all(rgb <= 0):
        return "black"
    if np.ptp(rgb) > 0:
        return "mixture"
    if np.all(rgb >= 255) and window >= 1:
        return "white"
    return "grey"


def _spd_XYZ(spd: np.ndarray, start: float, step: float) -> np.ndarray:
    count = spd.shape[-1]
    cmfs = colour.MSDS_CMFS[_CMFS].copy().align(
        colour.SpectralShape(start, start + step * (count - 1), step)).values
    return float(colour.constants.CONSTANT_K_M) * (spd @ cmfs)


def is_samsung_apl_mat(path) -> bool:
    """Whether ``path`` is a MATLAB file with BrainardLab's ``runParams`` and ``allCondsData``."""
    import scipy.io

    try:
        names = {name for name, *_ in scipy.io.whosmat(str(path))}
    except (ValueError, NotImplementedError, OSError):
        return False
    return {"runParams", "allCondsData"} <= names


def read_samsung_apl_mat(path) -> Session:
    """Read the BrainardLab Samsung OLED APL conditions as a session with window/surround columns."""
    import scipy.io

    path = Path(path)
    if not path.is_file():
        raise SpectrumFileError(path, None, "no such file", "check the path")
    try:
        contents = scipy.io.loadmat(str(path), squeeze_me=True, struct_as_record=False)
    except (ValueError, NotImplementedError, OSError) as error:  # as read_psychtoolbox_mat
        raise SpectrumFileError(path, None, f"not a readable MATLAB v5 file ({error})",
                                "the file is truncated or damaged: copy it again from its source") from None
    try:
        params = contents["runParams"]
        conditions = np.atleast_1d(contents["allCondsData"])
        stabilizer = np.atleast_1d(np.asarray(params.stabilizerGrays, dtype=float))
        scene = float(np.atleast_1d(params.sceneGrays)[0])
        bias_grey = float(np.atleast_1d(params.biasGrays)[0])
        bias_sizes = np.atleast_2d(np.asarray(params.biasSizes, dtype=float))
        targets = np.atleast_1d(np.asarray(params.targetGrays, dtype=float))
        spd = np.array([np.asarray(c.leftSPD, dtype=float).reshape(-1) for c in conditions])
        index = np.array([[int(c.stabilizerGrayIndex), int(c.biasSizeIndex), int(c.leftTargetGrayIndex),
                           int(c.rightTargetGrayIndex)] for c in conditions]) - 1
    except (KeyError, AttributeError, ValueError) as error:
        raise SpectrumFileError(path, None, f"not a BrainardLab OLED calibration ({error})",
                                "give the file with runParams (stabilizerGrays, biasSizes, targetGrays) "
                                "and allCondsData (leftSPD and the condition indices)") from None
    if spd.shape[1] != 101:
        raise SpectrumFileError(path, None, f"leftSPD has {spd.shape[1]} samples, not 101 (380:4:780 nm)",
                                "give the PR-650 spectra at 380:4:780 nm")
    # Psychtoolbox convention: power per 4 nm band, so no step factor (as read_psychtoolbox_mat)
    XYZ = _spd_XYZ(spd, 380.0, 4.0)
    target_grey = targets[index[:, 2]]
    right_grey = targets[index[:, 3]]
    stabilizer_grey = stabilizer[index[:, 0]]
    bias = bias_sizes[index[:, 1]]
    # the grey transfer, from the least-loaded condition (darkest stabilizer, smallest bias square)
    quiet = (index[:, 0] == np.argmin(stabilizer)) & (index[:, 1] == np.argmin(bias_sizes.prod(axis=1)))
    gamma = _grey_gamma(target_grey[quiet], XYZ[quiet, 1])
    width, height = SAMSUNG_FRAME_PX
    total = float(width * height)
    scene_area = (width - 2 * _SAMSUNG_BORDER_PX) * (height - 2 * _SAMSUNG_BORDER_PX)
    target_area = float(_SAMSUNG_TARGET_PX ** 2)
    bias_area = bias.prod(axis=1)
    lin = lambda g: np.clip(g, 0, 1) ** gamma  # noqa: E731
    rest_load = ((total - scene_area) * lin(stabilizer_grey)
                 + (scene_area - bias_area - target_area) * lin(scene)
                 + target_area * lin(right_grey)
                 + (bias_area - target_area) * lin(bias_grey))
    window = target_area / total
    surround_linear = rest_load / (total - target_area)
    surround = 255.0 * surround_linear ** (1.0 / gamma)
    rgb = np.repeat(255.0 * target_grey[:, None], 3, axis=1)
    kinds = np.array([_kind(v, window, None) for v in rgb], dtype=object)
    return Session(kind=kinds, rgb=rgb, XYZ=XYZ,
                   wavelengths=380.0 + 4.0 * np.arange(101), spectra=spd,
                   source=str(path), window=np.full(len(rgb), window),
                   surround=np.repeat(surround[:, None], 3, axis=1),
                   metadata={"format": "brainardlab-oled-apl",
                             "transfer": {"method": "power", "gammas": [gamma] * 3},
                             "apl_folds": {
                                 "stabilizer level": np.array([f"stabilizer {s:g}" for s in stabilizer_grey],
                                                              dtype=object),
                                 "bias size": np.array([f"bias {int(b[0])} px" for b in bias], dtype=object)},
                             "note": ("surround = uniform grey giving the frame the same load as the real "
                                      f"stabilizer/scene/bias/second-target frame (grey gamma {gamma:.3f} "
                                      "fitted on the least-loaded condition)")})


def _grey_gamma(grey: np.ndarray, Y: np.ndarray) -> float:
    black = Y[grey <= 0].mean() if np.any(grey <= 0) else 0.0
    top = Y[grey >= grey.max()].mean() - black
    ok = (grey > 0) & (grey < grey.max()) & (Y - black > 0.02 * top)
    x = np.log(grey[ok] / grey.max())
    return float(np.sum(x * np.log((Y[ok] - black) / top)) / np.sum(x * x))


def _read_colorimeter_csv(path: Path) -> np.ndarray:
    with path.open(newline="", encoding="utf-8-sig") as handle:
        rows = list(csv.reader(handle))
    if not rows or [c.strip() for c in rows[0][:3]] != ["X", "Y", "Z"]:
        raise SpectrumFileError(path, 1, "the header does not start with X,Y,Z",
                                "give the colorimeter CSV as written by the AW3225QF measurement script")
    values = []
    for line, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        try:
            if len(row) < 3:
                raise ValueError
            values.append([float(v) for v in row[:3]])
        except ValueError:
            raise SpectrumFileError(path, line, f"{row!r} is not three numbers X,Y,Z", "repair the file") from None
    return np.array(values, dtype=float).reshape(-1, 3)


def read_aw3225qf_colorchecker(directory) -> Session:
    """Read the AW3225QF ColorChecker window series (``cc_measure_lumi-<L>_win-<W>.csv``)."""
    directory = Path(directory)
    files = sorted((int(m.group(1)), int(m.group(2)), p) for p in directory.iterdir()
                   if (m := _CC_FILE.match(p.name)))
    if not files:
        raise SpectrumFileError(directory, None, "no cc_measure_lumi-<L>_win-<W>.csv files",
                                "give the AW3225QF measurement directory")
    smallest = min(w for _, w, _ in files)
    measured = {(lumi, win): _read_colorimeter_csv(p) for lumi, win, p in files}
    to_rgb = colour.RGB_COLOURSPACES["ITU-R BT.2020"].matrix_XYZ_to_RGB
    rgb_rows, XYZ_rows, window_rows, fold = [], [], [], []
    for (lumi, win), XYZ in sorted(measured.items()):
        reference = measured.get((lumi, smallest))
        if reference is None or len(reference) != len(XYZ):
            raise SpectrumFileError(directory, None, f"chart white {lumi} cd/m² has no {smallest} % window "
                                    "file with the same colours",
                                    "keep every window size of a chart white together")
        signal = np.clip(reference @ to_rgb.T, 0.0, None)
        code = np.asarray(colour.models.eotf_inverse_ST2084(signal), dtype=float)
        rgb_rows.append(np.round(255.0 * code, 4))
        XYZ_rows.append(XYZ)
        window_rows += [win / 100.0] * len(XYZ)
        fold += [f"window {win} %"] * len(XYZ)
    rgb = np.vstack(rgb_rows)
    window = np.array(window_rows)
    kinds = np.array([_kind(v, w, None) for v, w in zip(rgb, window)], dtype=object)
    return Session(kind=kinds, rgb=rgb, XYZ=np.vstack(XYZ_rows), source=str(directory),
                   window=window, surround=np.zeros_like(rgb),
                   metadata={"format": "aw3225qf-colorchecker",
                             "transfer": {"method": "pq", "gammas": [1.0] * 3, "peak_cd_m2": _PQ_PEAK_CD_M2},
                             "apl_folds": {"window size": np.array(fold, dtype=object)},
                             "note": ("code values reconstructed as the HDR10 (BT.2020, PQ) signal of the "
                                      f"colour measured in the {smallest} % window, scaled to 0..255")})


def read_aw3225qf_white_windows(path) -> Session:
    """Read every window size of one preset's white-window series (``measure_<MODE>_<WIN>_patch.csv``).

    ``path`` is one of the files; the other window sizes (and repeats) of the
    same preset in its directory are read with it.
    """
    path = Path(path)
    match = _WINDOW_FILE.match(path.name)
    if match is None or not path.is_file():
        raise SpectrumFileError(path, None, "not a measure_<MODE>_<WIN>_patch.csv file",
                                "give one of the AW3225QF white-window files")
    mode = match.group(1)
    files = sorted((int(m.group(2)), m.group(3), p) for p in path.parent.iterdir()
                   if (m := _WINDOW_FILE.match(p.name)) and m.group(1) == mode)
    rgb_rows, XYZ_rows, window_rows = [], [], []
    for win, _, file in files:
        XYZ = _read_colorimeter_csv(file)
        code = np.minimum(16 * np.arange(len(XYZ)), 1023)
        rgb_rows.append(np.repeat(255.0 * code[:, None] / 1023.0, 3, axis=1))
        XYZ_rows.append(XYZ)
        window_rows += [win / 100.0] * len(XYZ)
    rgb = np.vstack(rgb_rows)
    window = np.array(window_rows)
    kinds = np.array([_kind(v, w, None) for v, w in zip(rgb, window)], dtype=object)
    return Session(kind=kinds, rgb=rgb, XYZ=np.vstack(XYZ_rows), source=str(path.parent / f"measure_{mode}"),
                   window=window, surround=np.zeros_like(rgb),
                   metadata={"format": "aw3225qf-white-windows", "preset": mode,
                             "transfer": {"method": "pq", "gammas": [1.0] * 3, "peak_cd_m2": _PQ_PEAK_CD_M2}})


def preset_of_white_window_file(path) -> str | None:
    """The preset of an AW3225QF ``measure_<MODE>_<WIN>_patch.csv`` file, else ``None``."""
    match = _WINDOW_FILE.match(Path(path).name)
    return None if match is None else match.group(1)


def apl_session_reader(path):
    """The reader for ``path`` if it is one of the APL data sets above, else ``None``.

    Used by :func:`workbench.session_readers.read_session` before its own dispatch.
    """
    path = Path(path)
    if path.is_dir():
        if any(_CC_FILE.match(p.name) for p in path.iterdir()) and not (path / "session.csv").exists():
            return read_aw3225qf_colorchecker
        return None
    suffix = path.suffix.lower()
    if suffix == ".csv" and _WINDOW_FILE.match(path.name):
        return read_aw3225qf_white_windows
    if suffix == ".csv" and _CC_FILE.match(path.name):
        return lambda p: read_aw3225qf_colorchecker(Path(p).parent)
    if suffix == ".mat" and path.is_file() and is_samsung_apl_mat(path):
        return read_samsung_apl_mat
    return None
