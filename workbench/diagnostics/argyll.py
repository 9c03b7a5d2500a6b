"""The peer: ArgyllCMS's shaper + matrix profile on exactly the same fit rows, same held-out score.

ArgyllCMS is the reference open-source display profiler. :func:`score_argyll`
writes a session's fit rows (every row but ``validation``) as an Argyll
``.ti3`` (RGB 0–100, XYZ normalized to the white's Y = 100, the absolute
white in ``LUMINANCE_XYZ_CDM2``), runs ``colprof -as`` (shaper + matrix) on
it, evaluates the profile's forward model on the validation colours through
``icclu -ff -ia -px`` (forward, absolute intent, XYZ PCS), scales its XYZ
(white Y = 1) by the profile's ``lumi`` tag (read with ``iccdump``) back to
cd/m², and scores it in CIEDE2000 against the measured validation colours
with the convention :func:`workbench.diagnostics.diagnose` uses (CIELAB
white: the measured display white).

Where ``colprof`` is not installed :func:`score_argyll` returns an
:class:`ArgyllScore` whose ``unavailable`` says so (Debian package
``argyll``).
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from workbench.colorimetry import delta_E2000
from workbench.diagnostics.peer_score import PeerScore, peer_score
from workbench.errors import WorkbenchError
from workbench.session import Session

__all__ = ["ARGYLL_TOOLS", "ArgyllError", "ArgyllScore", "argyll_missing", "write_fit_ti3",
           "fit_argyll_shaper_matrix", "score_argyll"]

ARGYLL_TOOLS = ("colprof", "icclu", "iccdump")


class ArgyllError(WorkbenchError):
    """An ArgyllCMS tool failed on the data we gave it; the message quotes its output."""


def argyll_missing() -> str | None:
    """Why the peer cannot run (which tool is missing), or None."""
    missing = [tool for tool in ARGYLL_TOOLS if shutil.which(tool) is None]
    if missing:
        return (f"ArgyllCMS not installed ({', '.join(missing)} missing): install the Debian "
                "package argyll")
    return None


ArgyllScore = PeerScore
"""Argyll's shaper + matrix profile scored on the validation colours (a :class:`PeerScore`)."""


def write_fit_ti3(session: Session, path) -> Path:
    """Write ``session``'s rows as an Argyll display ``.ti3`` (RGB 0–100, XYZ with white Y = 100)."""
    path = Path(path)
    white = session.white_XYZ if session.has_white else session.XYZ[np.argmax(session.XYZ[:, 1])]
    scale = 100.0 / float(white[1])
    lines = ["CTI3", "", 'DESCRIPTOR "Argyll Calibration Target chart information 3"',
             'ORIGINATOR "vr-colour-workbench"', 'DEVICE_CLASS "DISPLAY"', 'COLOR_REP "RGB_XYZ"',
             f'LUMINANCE_XYZ_CDM2 "{white[0]:.6f} {white[1]:.6f} {white[2]:.6f}"',
             'NORMALIZED_TO_Y_100 "YES"', "", "NUMBER_OF_FIELDS 7", "BEGIN_DATA_FORMAT",
             "SAMPLE_ID RGB_R RGB_G RGB_B XYZ_X XYZ_Y XYZ_Z", "END_DATA_FORMAT", "",
             f"NUMBER_OF_SETS {len(session)}", "BEGIN_DATA"]
    for i, (rgb, XYZ) in enumerate(zip(session.rgb, session.XYZ), start=1):
        r, g, b = rgb / 2.55
        X, Y, Z = np.maximum(XYZ * scale, 0.0)
        lines.append(f"{i} {r:.5f} {g:.5f} {b:.5f} {X:.6f} {Y:.6f} {Z:.6f}")
    lines += ["END_DATA", ""]
    path.write_text("\n".join(lines), encoding="ascii")
    return path


def _run(command: list[str], cwd: Path, stdin: str | None = None) -> str:
    result = subprocess.run(command, cwd=cwd, input=stdin, capture_output=True, text=True,
                            timeout=300)
    if result.returncode != 0:
        output = (result.stdout + result.stderr).strip().splitlines()[-3:]
        raise ArgyllError(f"{command[0]} failed ({result.returncode}): {' / '.join(output)}")
    return result.stdout


@dataclass(frozen=True)
class _ArgyllProfile:
    path: Path
    luminance: float

    def forward(self, rgb: np.ndarray) -> np.ndarray:
        """Absolute XYZ (cd/m²) the profile predicts for DAC values ``rgb`` (N, 3) on 0..255."""
        text = "\n".join(f"{r:.6f} {g:.6f} {b:.6f}" for r, g, b in np.asarray(rgb) / 255.0)
        output = _run(["icclu", "-ff", "-ia", "-px", str(self.path)], self.path.parent,
                      text + "\n")
        values = [line.split("->")[-1].split("[")[0].split() for line in output.splitlines()
                  if "->" in line]
        XYZ = np.array(values, dtype=float)
        if XYZ.shape != (len(rgb), 3):
            raise ArgyllError(f"icclu returned {XYZ.shape[0]} values for {len(rgb)} colours")
        return XYZ * self.luminance


def fit_argyll_shaper_matrix(fit_rows: Session, folder) -> _ArgyllProfile:
    """``colprof -as`` on ``fit_rows`` written to ``folder``; the profile and its ``lumi`` Y."""
    folder = Path(folder)
    write_fit_ti3(fit_rows, folder / "fit.ti3")
    _run(["colprof", "-as", "-O", "fit.icc", "fit"], folder)
    dump = _run(["iccdump", "-v3", "-t", "lumi", "fit.icc"], folder)
    match = re.search(r"0:\s*([-\d.eE+]+),\s*([-\d.eE+]+),\s*([-\d.eE+]+)", dump)
    if match is None:
        raise ArgyllError("the profile colprof wrote has no readable lumi tag")
    return _ArgyllProfile(path=folder / "fit.icc", luminance=float(match.group(2)))


def score_argyll(session: Session) -> ArgyllScore:
    """Argyll's shaper + matrix on ``session``'s fit rows, scored on its validation rows (module doc)."""
    model = "ArgyllCMS colprof -as (shaper + matrix)"
    missing = argyll_missing()
    if missing:
        return ArgyllScore(model, unavailable=missing)
    validation = session.select("validation")
    if len(validation) == 0:
        return ArgyllScore(model, unavailable="no validation colours to score on")
    fit_rows = session.without("validation")
    white = session.white_XYZ if session.has_white else None
    if white is None:
        return ArgyllScore(model, unavailable="no white measured (ramps only)")
    with tempfile.TemporaryDirectory(prefix="argyll-peer-") as folder:
        profile = fit_argyll_shaper_matrix(fit_rows, folder)
        predicted = profile.forward(validation.rgb)
    return peer_score(model, delta_E2000(predicted, validation.XYZ, white))
