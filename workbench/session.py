"""Measured display sessions and the session CSV (design §4).

A :class:`Session` holds what was measured on a display: for each row its
``kind`` (``black``, ``white``, ``ramp-r``, ``ramp-g``, ``ramp-b``,
``validation``, ``grey``, ``mixture``), the DAC triplet shown (0..255), the
absolute tristimulus values measured (cd/m² scale), optionally the time since
the session began (``t_s``) and the spectral radiance (``nm380`` … ``nm780``).

The CSV has a header row; columns come in any order and are matched
case-insensitively. Rows of kind ``validation`` are never used to fit a model
whose validation figure is reported.
"""

from __future__ import annotations

import csv
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from workbench.errors import SpectrumFileError
from workbench.fileio import atomic_writer

__all__ = [
    "SESSION_KINDS",
    "Session",
    "read_session_csv",
    "write_session_csv",
]

SESSION_KINDS = ("black", "white", "ramp-r", "ramp-g", "ramp-b", "validation", "grey", "mixture")

_REQUIRED = ("kind", "r", "g", "b", "x", "y", "z")
_SPECTRAL = re.compile(r"^nm(\d{3})$")


@dataclass(frozen=True, eq=False)
class Session:
    """Measurements of one display.

    Attributes
    ----------
    kind : ndarray of str, shape (N,)
    rgb : ndarray, shape (N, 3)
        DAC values shown, 0..255.
    XYZ : ndarray, shape (N, 3)
        Measured tristimulus values, absolute (cd/m² for Y).
    t_s : ndarray, shape (N,), or None
        Seconds since the session began.
    wavelengths : ndarray, shape (W,), or None
        Wavelengths (nm) of the spectral columns.
    spectra : ndarray, shape (N, W), or None
        Spectral radiance, W·sr⁻¹·m⁻²·nm⁻¹.
    source : str
        Where the data came from (file name or description).
    """

    kind: np.ndarray
    rgb: np.ndarray
    XYZ: np.ndarray
    t_s: np.ndarray | None = None
    wavelengths: np.ndarray | None = None
    spectra: np.ndarray | None = None
    source: str = ""
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        kind = np.asarray(self.kind, dtype=object)
        rgb = np.asarray(self.rgb, dtype=float).reshape(-1, 3)
        XYZ = np.asarray(self.XYZ, dtype=float).reshape(-1, 3)
        if not (len(kind) == len(rgb) == len(XYZ)):
            raise ValueError(
                f"session {self.source!r}: kind, rgb and XYZ have {len(kind)}, {len(rgb)} "
                f"and {len(XYZ)} rows; they must have the same number of rows"
            )
        unknown = sorted(set(kind) - set(SESSION_KINDS))
        if unknown:
            raise ValueError(
                f"session {self.source!r}: unknown kind(s) {unknown}; use one of {list(SESSION_KINDS)}"
            )
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "rgb", rgb)
        object.__setattr__(self, "XYZ", XYZ)
        if self.t_s is not None:
            object.__setattr__(self, "t_s", np.asarray(self.t_s, dtype=float).reshape(-1))
        if self.spectra is not None:
            object.__setattr__(self, "spectra", np.asarray(self.spectra, dtype=float))
            object.__setattr__(self, "wavelengths", np.asarray(self.wavelengths, dtype=float))

    def __len__(self) -> int:
        return len(self.kind)

    def mask(self, *kinds: str) -> np.ndarray:
        """Boolean mask of the rows whose kind is one of ``kinds``."""
        return np.isin(self.kind, kinds)

    def subset(self, mask: np.ndarray) -> "Session":
        """A new session with only the rows where ``mask`` is true."""
        mask = np.asarray(mask)
        return Session(
            kind=self.kind[mask],
            rgb=self.rgb[mask],
            XYZ=self.XYZ[mask],
            t_s=None if self.t_s is None else self.t_s[mask],
            wavelengths=self.wavelengths,
            spectra=None if self.spectra is None else self.spectra[mask],
            source=self.source,
            metadata=dict(self.metadata),
        )

    def select(self, *kinds: str) -> "Session":
        """The rows of the given kinds, in their original order."""
        return self.subset(self.mask(*kinds))

    def without(self, *kinds: str) -> "Session":
        """The rows of every kind but the given ones."""
        return self.subset(~self.mask(*kinds))

    @property
    def has_white(self) -> bool:
        """Whether a white (255, 255, 255) was measured."""
        return bool(np.any(self.mask("white") | np.all(self.rgb >= 255, axis=1)))

    @property
    def white_XYZ(self) -> np.ndarray:
        """Mean XYZ of the ``white`` rows (or of the rows at DAC 255,255,255)."""
        rows = self.XYZ[self.mask("white") | np.all(self.rgb >= 255, axis=1)]
        if len(rows) == 0:
            raise ValueError(f"session {self.source!r} has no white (255,255,255) measurement")
        return rows.mean(axis=0)

    @property
    def black_XYZ(self) -> np.ndarray:
        """Mean XYZ of the ``black`` rows (or of the rows at DAC 0,0,0); zeros if none."""
        rows = self.XYZ[self.mask("black") | np.all(self.rgb <= 0, axis=1)]
        return rows.mean(axis=0) if len(rows) else np.zeros(3)


def _number(text: str, path, line: int, column: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise SpectrumFileError(
            path, line, f"column {column!r} holds {text!r}, which is not a number",
            "write a plain decimal number (e.g. 12.5) in every measurement column",
        ) from None
    if not math.isfinite(value):
        raise SpectrumFileError(
            path, line, f"column {column!r} holds {text!r}, which is not finite",
            "remove the row or re-measure the patch",
        )
    return value


def read_session_csv(path: str | os.PathLike) -> Session:
    """Read a session CSV (design §4). Errors name the file, the line and the fix."""
    path = Path(path)
    if not path.exists():
        raise SpectrumFileError(path, None, "no such file", "check the path")
    with path.open(newline="", encoding="utf-8-sig") as handle:
        reader = csv.reader(handle)
        try:
            header = next(reader)
        except StopIteration:
            raise SpectrumFileError(path, 1, "the file is empty",
                                    "write a header row kind,r,g,b,X,Y,Z then one row per patch") from None
        columns = {name.strip().lower(): i for i, name in enumerate(header)}
        missing = [name for name in _REQUIRED if name not in columns]
        if missing:
            raise SpectrumFileError(
                path, 1, f"the header lacks column(s) {missing}",
                "the header must name kind,r,g,b,X,Y,Z (any order, any case); t_s and nm380..nm780 are optional",
            )
        spectral = sorted(
            ((int(m.group(1)), i) for name, i in columns.items() if (m := _SPECTRAL.match(name))),
        )
        kinds, rgb, XYZ, t_s, spectra = [], [], [], [], []
        for line, row in enumerate(reader, start=2):
            if not row or all(not cell.strip() for cell in row):
                continue
            if len(row) < len(header):
                raise SpectrumFileError(
                    path, line, f"the row has {len(row)} fields, the header {len(header)}",
                    "give every row a value for every column (the last line may be truncated)",
                )
            kind = row[columns["kind"]].strip().lower()
            if kind not in SESSION_KINDS:
                raise SpectrumFileError(path, line, f"unknown kind {kind!r}",
                                        f"use one of {', '.join(SESSION_KINDS)}")
            kinds.append(kind)
            dac = [_number(row[columns[c]], path, line, c) for c in "rgb"]
            if any(v < 0 or v > 255 for v in dac):
                raise SpectrumFileError(path, line, f"DAC values {dac} outside 0..255",
                                        "r,g,b are 8-bit DAC values 0..255")
            rgb.append(dac)
            XYZ.append([_number(row[columns[c]], path, line, c.upper()) for c in "xyz"])
            if "t_s" in columns:
                t_s.append(_number(row[columns["t_s"]], path, line, "t_s"))
            if spectral:
                spectra.append([_number(row[i], path, line, f"nm{w}") for w, i in spectral])
    if not kinds:
        raise SpectrumFileError(path, None, "the file has a header but no measurements",
                                "add one row per measured patch")
    return Session(
        kind=np.array(kinds, dtype=object),
        rgb=np.array(rgb),
        XYZ=np.array(XYZ),
        t_s=np.array(t_s) if t_s else None,
        wavelengths=np.array([w for w, _ in spectral], dtype=float) if spectral else None,
        spectra=np.array(spectra) if spectral else None,
        source=str(path),
    )


def write_session_csv(session: Session, path: str | os.PathLike) -> Path:
    """Write ``session`` as a session CSV, atomically (temporary file, fsync, rename)."""
    path = Path(path)
    header = ["kind", "r", "g", "b", "X", "Y", "Z"]
    if session.t_s is not None:
        header.append("t_s")
    if session.spectra is not None:
        header += [f"nm{int(round(w))}" for w in session.wavelengths]
    with atomic_writer(path, newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for i in range(len(session)):
            row = [session.kind[i], *(f"{v:g}" for v in session.rgb[i]),
                   *(f"{v:.6g}" for v in session.XYZ[i])]
            if session.t_s is not None:
                row.append(f"{session.t_s[i]:.3f}")
            if session.spectra is not None:
                row += [f"{v:.6g}" for v in session.spectra[i]]
            writer.writerow(row)
    return path
