"""Measured display sessions and the session CSV (design §4).

A :class:`Session` holds what was measured on a display: for each row its
``kind`` (``black``, ``white``, ``ramp-r``, ``ramp-g``, ``ramp-b``,
``validation``, ``grey``, ``mixture``), the DAC triplet shown (0..255), the
absolute tristimulus values measured (cd/m² scale), optionally the time since
the session began (``t_s``) and the spectral radiance (``nm380`` … ``nm780``).
Patches shown as a window on a surround (for displays whose output depends on
the rest of the picture, ``apl-dependence``) carry ``window`` (the patch's
fraction of the field, 0..1, default 1 = full field) and the surround's DAC
values ``sr, sg, sb`` (default 0); sessions without them are full-field.

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
    "NEGATIVE_TOLERANCE",
    "MEASUREMENT_METADATA",
    "check_measured_XYZ",
    "Session",
    "read_session_csv",
    "write_session_csv",
]

SESSION_KINDS = ("black", "white", "ramp-r", "ramp-g", "ramp-b", "validation", "grey", "mixture")

_REQUIRED = ("kind", "r", "g", "b", "x", "y", "z")

MEASUREMENT_METADATA = ("eye", "sync")
"""How a measured session was measured, written as constant columns of the session CSV (when known)
and read back into ``Session.metadata``: ``eye`` (which panel showed the patches: both, left, right)
and ``sync`` (the instrument's sync mode: none, internal:HZ, external)."""
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
    metadata : dict
        Reader-specific facts (format, instrument, signal encoding).
    window : ndarray, shape (N,), or None
        Fraction of the field the patch covers, 0 < window <= 1; ``None``: every
        patch full-field.
    surround : ndarray, shape (N, 3), or None
        DAC values (0..255) of the rest of the field; ``None``: black.
    """

    kind: np.ndarray
    rgb: np.ndarray
    XYZ: np.ndarray
    t_s: np.ndarray | None = None
    wavelengths: np.ndarray | None = None
    spectra: np.ndarray | None = None
    source: str = ""
    metadata: dict = field(default_factory=dict)
    window: np.ndarray | None = None
    surround: np.ndarray | None = None

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
        self._check_window_surround()

    def _check_window_surround(self) -> None:
        if self.window is None and self.surround is None:
            return
        n = len(self.kind)
        window = np.ones(n) if self.window is None else np.asarray(self.window, dtype=float).reshape(-1)
        surround = (np.zeros((n, 3)) if self.surround is None
                    else np.asarray(self.surround, dtype=float).reshape(-1, 3))
        if len(window) != n or len(surround) != n:
            raise ValueError(f"session {self.source!r}: window and surround have {len(window)} and "
                             f"{len(surround)} rows, the session {n}; give one per row")
        if not np.all((window > 0) & (window <= 1)):
            raise ValueError(f"session {self.source!r}: window values must lie in (0, 1] "
                             "(the patch's fraction of the field)")
        if not np.all((surround >= 0) & (surround <= 255)):
            raise ValueError(f"session {self.source!r}: surround DAC values must lie in 0..255")
        object.__setattr__(self, "window", window)
        object.__setattr__(self, "surround", surround)

    @property
    def has_surround_data(self) -> bool:
        """Whether any patch was shown as a window smaller than the field or on a lit surround."""
        return self.window is not None and bool(np.any(self.window < 1) or np.any(self.surround > 0))

    @property
    def window_or_full(self) -> np.ndarray:
        """The ``window`` column, ones (full field) where the session has none."""
        return np.ones(len(self)) if self.window is None else self.window

    @property
    def surround_or_black(self) -> np.ndarray:
        """The surround DAC values ``(N, 3)``, zeros (black) where the session has none."""
        return np.zeros((len(self), 3)) if self.surround is None else self.surround

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
            window=None if self.window is None else self.window[mask],
            surround=None if self.surround is None else self.surround[mask],
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


NEGATIVE_TOLERANCE = 0.001
"""A measured X, Y or Z below ``−NEGATIVE_TOLERANCE × the session's largest Y`` is refused:
instruments that subtract their dark reading give slightly negative values at black, never more."""


def check_measured_XYZ(XYZ: np.ndarray, path, lines) -> None:
    """Refuse tristimulus values no instrument can measure (clearly negative), naming the line."""
    XYZ = np.asarray(XYZ, dtype=float).reshape(-1, 3)
    if XYZ.size == 0:
        return
    limit = -NEGATIVE_TOLERANCE * max(float(np.max(XYZ[:, 1])), 0.0)
    bad = np.flatnonzero(np.any(XYZ < limit, axis=1))
    if bad.size:
        i = int(bad[0])
        raise SpectrumFileError(
            path, lines[i] if lines is not None else None,
            f"X, Y, Z = {', '.join(f'{v:g}' for v in XYZ[i])} is negative beyond noise (more "
            f"than {100 * NEGATIVE_TOLERANCE:g} % of the session's brightest Y below zero)"
            + (f"; {bad.size} such rows" if bad.size > 1 else ""),
            "re-measure the patch or remove the row; light cannot be negative")


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
                "the header must name kind,r,g,b,X,Y,Z (any order, any case); t_s, window, sr,sg,sb, "
                "eye, sync and nm380..nm780 are optional",
            )
        spectral = sorted(
            ((int(m.group(1)), i) for name, i in columns.items() if (m := _SPECTRAL.match(name))),
        )
        surround_columns = [c for c in ("sr", "sg", "sb") if c in columns]
        if surround_columns and len(surround_columns) != 3:
            raise SpectrumFileError(path, 1, f"the header has {surround_columns} but not all of sr,sg,sb",
                                    "give the surround as three columns sr,sg,sb (DAC 0..255) or none")
        measured_how = {key: set() for key in MEASUREMENT_METADATA if key in columns}
        kinds, rgb, XYZ, t_s, spectra, window, surround = [], [], [], [], [], [], []
        data_lines: list[int] = []
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
            if any(v != round(v) for v in dac):
                raise SpectrumFileError(
                    path, line, f"DAC values {[f'{v:g}' for v in dac]} are not whole numbers",
                    "r,g,b are the 8-bit DAC values the panel received (0..255, integers); "
                    "data on a 0-100 scale (an Argyll .ti3) should be read from the .ti3 itself")
            rgb.append(dac)
            XYZ.append([_number(row[columns[c]], path, line, c.upper()) for c in "xyz"])
            data_lines.append(line)
            if "t_s" in columns:
                t_s.append(_number(row[columns["t_s"]], path, line, "t_s"))
            if "window" in columns:
                fraction = _number(row[columns["window"]], path, line, "window")
                if not 0 < fraction <= 1:
                    raise SpectrumFileError(path, line, f"window {fraction:g} outside (0, 1]",
                                            "window is the patch's fraction of the field, 1 = full field")
                window.append(fraction)
            if surround_columns:
                dac = [_number(row[columns[c]], path, line, c) for c in ("sr", "sg", "sb")]
                if any(v < 0 or v > 255 for v in dac):
                    raise SpectrumFileError(path, line, f"surround DAC values {dac} outside 0..255",
                                            "sr,sg,sb are the surround's 8-bit DAC values 0..255")
                surround.append(dac)
            if spectral:
                spectra.append([_number(row[i], path, line, f"nm{w}") for w, i in spectral])
            for key, values in measured_how.items():
                values.add(row[columns[key]].strip())
    mixed = [key for key, values in measured_how.items() if len(values) > 1]
    if mixed:
        raise SpectrumFileError(path, None, f"the {mixed[0]} column holds {sorted(measured_how[mixed[0]])}: "
                                "rows measured differently (another panel, another sync) in one session",
                                "split the file into one session per panel and sync mode")
    if not kinds:
        raise SpectrumFileError(path, None, "the file has a header but no measurements",
                                "add one row per measured patch")
    check_measured_XYZ(np.array(XYZ), path, data_lines)
    return Session(
        kind=np.array(kinds, dtype=object),
        rgb=np.array(rgb),
        XYZ=np.array(XYZ),
        t_s=np.array(t_s) if t_s else None,
        wavelengths=np.array([w for w, _ in spectral], dtype=float) if spectral else None,
        spectra=np.array(spectra) if spectral else None,
        source=str(path),
        metadata={key: values.pop() for key, values in measured_how.items() if values and "" not in values},
        window=np.array(window) if window else None,
        surround=np.array(surround) if surround else None,
    )


def write_session_csv(session: Session, path: str | os.PathLike) -> Path:
    """Write ``session`` as a session CSV, atomically (temporary file, fsync, rename)."""
    path = Path(path)
    header = ["kind", "r", "g", "b", "X", "Y", "Z"]
    if session.t_s is not None:
        header.append("t_s")
    if session.window is not None:
        header += ["window", "sr", "sg", "sb"]
    measured_how = [key for key in MEASUREMENT_METADATA if session.metadata.get(key)]
    header += measured_how
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
            if session.window is not None:
                row += [f"{session.window[i]:.6g}", *(f"{v:g}" for v in session.surround[i])]
            row += [str(session.metadata[key]) for key in measured_how]
            if session.spectra is not None:
                row += [f"{v:.6g}" for v in session.spectra[i]]
            writer.writerow(row)
    return path
