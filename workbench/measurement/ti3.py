"""Argyll CGATS ``.ti3`` export of a measured session (design §4).

The file is what Argyll's ``dispread`` writes and ``colprof`` reads: device
values ``RGB_R RGB_G RGB_B`` on 0..100 (DAC / 255 × 100) and tristimulus values
``XYZ_X XYZ_Y XYZ_Z`` normalised so that the session's white has ``Y = 100``,
with the absolute white (cd/m²) in ``LUMINANCE_XYZ_CDM2``. The white is the
mean of the session's white measurements (drift references included), as in
:attr:`workbench.session.Session.white_XYZ`.

References
----------
Argyll CMS documentation, "ti3 file format" (``.ti3`` is a CGATS.17 text file).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from workbench.fileio import atomic_writer
from workbench.measurement.journal import SOFTWARE
from workbench.session import Session

__all__ = ["session_to_ti3_text", "write_session_ti3"]


def session_to_ti3_text(session: Session, instrument: str = "Konica Minolta CS-2000") -> str:
    """The CGATS text of ``session`` as an Argyll ``.ti3``.

    Parameters
    ----------
    session : Session
        Must contain at least one white (255, 255, 255) measurement.
    instrument : str
        Written as ``TARGET_INSTRUMENT``.

    Returns
    -------
    str
    """
    white = session.white_XYZ
    relative = session.XYZ / white[1] * 100.0
    rgb = session.rgb / 255.0 * 100.0
    lines = [
        "CTI3",
        "",
        'DESCRIPTOR "Argyll Calibration Target chart information 3"',
        f'ORIGINATOR "{SOFTWARE}"',
        f'CREATED "{time.strftime("%a %b %d %H:%M:%S %Y")}"',
        'DEVICE_CLASS "DISPLAY"',
        'COLOR_REP "RGB_XYZ"',
        f'TARGET_INSTRUMENT "{instrument}"',
        f'INSTRUMENT_TYPE_SPECTRAL "{"YES" if session.spectra is not None else "NO"}"',
        f'LUMINANCE_XYZ_CDM2 "{white[0]:.6f} {white[1]:.6f} {white[2]:.6f}"',
        'NORMALIZED_TO_Y_100 "YES"',
        "",
        "NUMBER_OF_FIELDS 7",
        "BEGIN_DATA_FORMAT",
        "SAMPLE_ID RGB_R RGB_G RGB_B XYZ_X XYZ_Y XYZ_Z",
        "END_DATA_FORMAT",
        "",
        f"NUMBER_OF_SETS {len(session)}",
        "BEGIN_DATA",
    ]
    for i, (device, XYZ) in enumerate(zip(rgb, relative), start=1):
        lines.append(f"{i} " + " ".join(f"{v:.6f}" for v in np.r_[device, XYZ]))
    lines += ["END_DATA", ""]
    return "\n".join(lines)


def write_session_ti3(session: Session, path: str | os.PathLike, instrument: str = "Konica Minolta CS-2000") -> Path:
    """Write ``session`` as an Argyll ``.ti3`` at ``path``, atomically; returns the path."""
    path = Path(path)
    with atomic_writer(path, encoding="ascii", newline="\n") as handle:
        handle.write(session_to_ti3_text(session, instrument))
    return path
