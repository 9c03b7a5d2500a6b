"""Read measured display data from the formats colour scientists have: one dispatcher.

:func:`read_session` takes

- a session CSV (design §4),
- an Argyll CGATS ``.ti3`` (DisplayCAL): RGB 0–100, XYZ normalised to the
  white's Y = 100 with the absolute white in ``LUMINANCE_XYZ_CDM2``.
  Single-channel rows become ramps, ``r = g = b`` rows become ``grey``
  (except black and white), every other mixture becomes a held-out
  ``validation`` row;
- a Psychtoolbox calibration ``.mat`` (MATLAB v5, variable ``cals``): per-gun
  spectra at ``rawdata.rawGammaInput`` levels (ambient-subtracted, so the
  ambient ``P_ambient`` is added back and reported as the black), wavelengths
  from ``describe.S``; ramps only, no white and no mixtures;
- a gamma-matrix profile (``.vrprofile.json``): its published black, white
  and full-drive primaries (what a paper's characterization table gives);
- a measurement directory (``session.csv`` inside it).

XYZ are absolute (cd/m²) where the file says so (``.ti3``); Psychtoolbox
spectra are integrated with 683 lm/W as given (their radiometric unit is the
meter's), which is a constant scale factor for every diagnosis.
"""

from __future__ import annotations

import os
import re
import shlex
from pathlib import Path

import colour
import numpy as np

from workbench.errors import SpectrumFileError
from workbench.session import Session, check_measured_XYZ, read_session_csv

__all__ = ["SESSION_READERS", "read_session", "read_ti3", "read_psychtoolbox_mat",
           "read_profile_primaries"]


def _ti3_kind(rgb: np.ndarray) -> str:
    lit = rgb > 0
    if not lit.any():
        return "black"
    if np.all(rgb >= 255):
        return "white"
    if lit.sum() == 1:
        return ("ramp-r", "ramp-g", "ramp-b")[int(np.argmax(lit))]
    if rgb[0] == rgb[1] == rgb[2]:
        return "grey"
    return "validation"


def read_ti3(path) -> Session:
    """Read an Argyll ``.ti3`` display measurement (first data table)."""
    path = Path(path)
    if not path.is_file():
        raise SpectrumFileError(path, None, "no such file", "check the path")
    lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    keywords, fields, rows, row_lines = {}, None, [], []
    state = "header"
    for number, line in enumerate(lines, start=1):
        text = line.strip()
        if state == "header":
            if text == "BEGIN_DATA_FORMAT":
                state = "format"
            elif text and not text.startswith("#"):
                parts = text.split(None, 1)
                if len(parts) == 2:
                    keywords[parts[0]] = parts[1].strip().strip('"')
        elif state == "format":
            if text == "END_DATA_FORMAT":
                state = "between"
            else:
                fields = (fields or []) + text.split()
        elif state == "between":
            if text == "BEGIN_DATA":
                state = "data"
            elif text.startswith("NUMBER_OF_SETS"):
                keywords["NUMBER_OF_SETS"] = text.split(None, 1)[-1].strip().strip('"')
        elif state == "data":
            if text == "END_DATA":
                break
            if text:
                rows.append(shlex.split(text))
                row_lines.append(number)
    if not fields or not rows:
        raise SpectrumFileError(path, None, "no CGATS data table",
                                "give an Argyll .ti3 with BEGIN_DATA_FORMAT/BEGIN_DATA sections")
    declared = keywords.get("NUMBER_OF_SETS")
    if declared is not None and declared.strip().isdigit() and int(declared) != len(rows):
        raise SpectrumFileError(path, None, f"NUMBER_OF_SETS says {int(declared)} rows but the "
                                f"first data table holds {len(rows)}",
                                "the file is truncated or was edited: re-export it from "
                                "DisplayCAL/Argyll, or correct NUMBER_OF_SETS if rows were "
                                "removed on purpose")
    index = {name: i for i, name in enumerate(fields)}
    needed = ["RGB_R", "RGB_G", "RGB_B", "XYZ_X", "XYZ_Y", "XYZ_Z"]
    missing = [name for name in needed if name not in index]
    if missing:
        raise SpectrumFileError(path, None, f"the data format lacks {missing}",
                                "export the measurement with RGB and XYZ fields (COLOR_REP RGB_XYZ)")
    values = []
    for row, number in zip(rows, row_lines):
        try:
            values.append([float(row[index[name]]) for name in needed])
        except (ValueError, IndexError):
            raise SpectrumFileError(path, number, "a data row is not numeric or too short",
                                    "repair or re-export the file") from None
    values = np.array(values)
    rgb = np.round(values[:, :3] * 2.55, 4)
    XYZ = values[:, 3:]
    scale = 1.0
    if "LUMINANCE_XYZ_CDM2" in keywords:
        try:
            absolute = [float(v) for v in re.split(r"[\s,]+", keywords["LUMINANCE_XYZ_CDM2"].strip())]
            if len(absolute) != 3:
                raise ValueError
        except ValueError:
            raise SpectrumFileError(path, None, f"LUMINANCE_XYZ_CDM2 {keywords['LUMINANCE_XYZ_CDM2']!r} is not "
                                    "three numbers", "give the white's absolute X Y Z in cd/m², e.g. "
                                    '"95.1 100.0 108.9", or re-export the file') from None
        if keywords.get("NORMALIZED_TO_Y_100", "NO").upper() == "YES":
            scale = absolute[1] / 100.0
    if np.any(rgb < -1e-6) or np.any(rgb > 255 + 1e-6):
        row = int(np.flatnonzero(np.any((rgb < -1e-6) | (rgb > 255 + 1e-6), axis=1))[0])
        raise SpectrumFileError(path, row_lines[row], f"RGB {values[row, :3].tolist()} outside "
                                "0..100", "a display .ti3 gives RGB_R/G/B in percent, 0..100")
    check_measured_XYZ(XYZ, path, row_lines)
    kinds = np.array([_ti3_kind(v) for v in rgb], dtype=object)
    return Session(kind=kinds, rgb=np.clip(rgb, 0, 255), XYZ=XYZ * scale, source=str(path),
                   metadata={"format": "ti3", "instrument": keywords.get("TARGET_INSTRUMENT", ""),
                             "created": keywords.get("CREATED", "")})


def read_psychtoolbox_mat(path) -> Session:
    """Read a Psychtoolbox calibration file (``cals``, MATLAB v5) as ramps + black."""
    import scipy.io

    path = Path(path)
    if not path.is_file():
        raise SpectrumFileError(path, None, "no such file", "check the path")
    try:
        contents = scipy.io.loadmat(str(path), squeeze_me=True, struct_as_record=False)
    except (ValueError, NotImplementedError, OSError) as error:
        raise SpectrumFileError(path, None, f"not a MATLAB v5 file ({error})",
                                "save the calibration with save(..., '-v7') or read it in "
                                "Psychtoolbox and export a session CSV") from None
    if "cals" not in contents:
        raise SpectrumFileError(path, None, "no variable 'cals'",
                                "give a Psychtoolbox calibration file (LoadCalFile format)")
    cals = contents["cals"]
    cal = cals[-1] if isinstance(cals, np.ndarray) else cals  # the most recent calibration
    try:
        start, step, count = (int(v) for v in np.atleast_1d(cal.describe.S))
        levels = np.atleast_1d(np.asarray(cal.rawdata.rawGammaInput, dtype=float)).reshape(-1)
        mon = np.asarray(cal.rawdata.mon, dtype=float)
        ambient = np.asarray(cal.P_ambient, dtype=float).reshape(-1)
    except AttributeError as error:
        raise SpectrumFileError(path, None, f"the calibration lacks a field ({error})",
                                "give a calibration with describe.S, rawdata.mon, "
                                "rawdata.rawGammaInput and P_ambient") from None
    wavelengths = start + step * np.arange(count)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(
        colour.SpectralShape(start, start + step * (count - 1), step)).values
    k_m = float(colour.constants.CONSTANT_K_M)

    def to_XYZ(spectra):
        return k_m * np.asarray(spectra) @ cmfs

    kinds, rgb, XYZ, spectra = ["black"], [[0.0, 0.0, 0.0]], [to_XYZ(ambient)], [ambient]
    for channel, kind in enumerate(("ramp-r", "ramp-g", "ramp-b")):
        per_level = mon[:, channel].reshape(len(levels), count)
        for level, spectrum in zip(levels, per_level):
            triplet = [0.0, 0.0, 0.0]
            triplet[channel] = round(255.0 * level, 4)
            measured = spectrum + ambient
            kinds.append(kind)
            rgb.append(triplet)
            XYZ.append(to_XYZ(measured))
            spectra.append(measured)
    return Session(kind=np.array(kinds, dtype=object), rgb=np.array(rgb), XYZ=np.array(XYZ),
                   wavelengths=wavelengths.astype(float), spectra=np.array(spectra),
                   source=str(path), metadata={"format": "psychtoolbox",
                                               "monitor": str(getattr(cal.describe, "monitor", ""))})


def read_profile_primaries(path) -> Session:
    """A gamma-matrix profile's published numbers as a session: black, white, R, G, B at full drive.

    This is what a paper's characterization table gives (e.g. Table 1 of
    Díaz-Barrancas et al. 2020); the profile's gammas travel in the metadata
    as the baseline, since there are no sweeps to fit them on.
    """
    from workbench.profile import load_profile

    profile = load_profile(path)
    if profile.display_model_type != "gamma-matrix":
        raise SpectrumFileError(path, None, f"a {profile.display_model_type!r} profile has no "
                                "published primaries to diagnose",
                                "diagnose the session the profile was made from instead")
    model = profile.display_model()
    rgb = [[0, 0, 0], [255, 255, 255], [255, 0, 0], [0, 255, 0], [0, 0, 255]]
    XYZ = [model.black_XYZ, model.white_XYZ, *model.matrix.T]
    return Session(kind=np.array(["black", "white", "ramp-r", "ramp-g", "ramp-b"], dtype=object),
                   rgb=np.array(rgb, dtype=float), XYZ=np.array(XYZ), source=str(path),
                   metadata={"format": "profile", "baseline_parameters": model.parameters()})


def _read_directory(path: Path) -> Session:
    candidate = path / "session.csv"
    if not candidate.is_file():
        raise SpectrumFileError(path, None, "the directory has no session.csv",
                                "run 'python -m workbench measure --out DIR' to the end, or "
                                "'--resume' it, to write DIR/session.csv")
    return read_session_csv(candidate)


SESSION_READERS = {
    ".csv": read_session_csv,
    ".ti3": read_ti3,
    ".mat": read_psychtoolbox_mat,
    ".json": read_profile_primaries,
}


def read_session(path: str | os.PathLike) -> Session:
    """Read a session from a CSV, an Argyll ``.ti3``, a Psychtoolbox ``.mat`` or a directory."""
    path = Path(path)
    from workbench.apl.readers import apl_session_reader  # OLED APL data sets (Samsung .mat, AW3225QF)
    if (apl_reader := apl_session_reader(path)) is not None:
        return apl_reader(path)
    if path.is_dir():
        return _read_directory(path)
    reader = SESSION_READERS.get(path.suffix.lower())
    if reader is None:
        raise SpectrumFileError(path, None, f"unknown session format {path.suffix!r}",
                                f"give one of {sorted(SESSION_READERS)} or a measurement directory")
    return reader(path)
