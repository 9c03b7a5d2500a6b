"""``display_inverse.cube``: the display inverse as a 3D LUT for Unity HDRP and DaVinci Resolve.

Contract of the file (recorded in the profile's ``lut3d`` block):

- **in**: the engine's output, sRGB-encoded (IEC 61966-2-1) on 0..1, read as
  colours of the ideal sRGB display — what the application would send to a
  standard monitor;
- **white mapping**: linear sRGB (1, 1, 1) is CIE D65 at ``Y = k · Y_white``
  of the headset (the profile's ``k``, relative colorimetry of design §2: the
  same white a perfect diffuser has under D65 at level 1), so
  ``XYZ = k · Y_white · M_sRGB · srgb_decode(in)`` with ``M_sRGB`` normalized to Y = 1;
- **out**: the headset's DAC / 255 from the profile's display inverse
  (out of gamut: clipped per channel in linear drive, as every model here).

Format: the Iridas/Resolve ``.cube`` text form Unity's HDRP importer and
Resolve read: ``TITLE``, ``#`` comments, ``LUT_3D_SIZE N``, no ``DOMAIN_``
lines (the default 0..1 domain), then N³ lines ``r g b`` with **red fastest**,
values in [0, 1].
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import colour
import numpy as np

from workbench.colorimetry import delta_E2000
from workbench.display import DisplayModel, srgb_decode
from workbench.errors import InputError
from workbench.export.runtime_inverse import sample_trilinear
from workbench.fileio import atomic_writer

__all__ = [
    "DEFAULT_LUT_SIZE",
    "CubeAccuracy",
    "white_mapping_XYZ",
    "srgb_input_to_XYZ",
    "display_inverse_table",
    "write_cube_file",
    "read_cube_file",
    "cube_accuracy",
]

DEFAULT_LUT_SIZE = 33

_SRGB_TO_XYZ = np.asarray(colour.models.RGB_COLOURSPACE_sRGB.matrix_RGB_to_XYZ, dtype=np.float64)


def white_mapping_XYZ(display: DisplayModel, k: float) -> np.ndarray:
    """XYZ that sRGB white maps to: D65 (sRGB's white) at ``Y = k · Y_white`` of the display."""
    return _SRGB_TO_XYZ.sum(axis=1) * (k * float(display.white_XYZ[1]))


def srgb_input_to_XYZ(encoded, display: DisplayModel, k: float) -> np.ndarray:
    """XYZ (display scale) of sRGB-encoded engine output on 0..1 under the white mapping."""
    linear = srgb_decode(np.clip(np.asarray(encoded, dtype=np.float64), 0.0, 1.0))
    return linear @ _SRGB_TO_XYZ.T * (k * float(display.white_XYZ[1]))


def display_inverse_table(display: DisplayModel, k: float, size: int = DEFAULT_LUT_SIZE
                          ) -> np.ndarray:
    """``(size, size, size, 3)`` DAC/255 at the grid nodes, indexed ``[b, g, r]`` (red fastest)."""
    if not 2 <= size <= 129:
        raise InputError(f"--lut-size {size}: a .cube has 2..129 nodes per axis (33 is usual)")
    nodes = np.linspace(0.0, 1.0, size)
    b, g, r = np.meshgrid(nodes, nodes, nodes, indexing="ij")
    encoded = np.stack([r, g, b], axis=-1)
    dac = display.inverse(srgb_input_to_XYZ(encoded.reshape(-1, 3), display, k))
    return np.clip(dac / 255.0, 0.0, 1.0).reshape(size, size, size, 3)


def write_cube_file(path, table: np.ndarray, *, title: str, comments=()) -> Path:
    """Write ``table`` ``[b, g, r, 3]`` as a ``.cube`` (module doc), atomically."""
    table = np.asarray(table, dtype=np.float64)
    size = table.shape[0]
    if table.shape != (size, size, size, 3) or not np.all(np.isfinite(table)):
        raise InputError(f"a .cube table must be finite with shape (N, N, N, 3); got {table.shape}")
    if np.any(table < 0) or np.any(table > 1):
        raise InputError("a .cube table for Unity/Resolve must hold values in [0, 1]")
    lines = [f'TITLE "{title}"'] + [f"# {line}" for line in comments] + [f"LUT_3D_SIZE {size}"]
    rows = table.reshape(-1, 3)  # [b][g][r] C order: red fastest
    lines += [f"{r:.6f} {g:.6f} {b:.6f}" for r, g, b in rows]
    with atomic_writer(path, newline="\n") as handle:
        handle.write("\n".join(lines) + "\n")
    return Path(path)


def read_cube_file(path) -> np.ndarray:
    """Read a ``.cube`` written as above: ``(N, N, N, 3)`` indexed ``[b, g, r]``."""
    size, values = None, []
    for number, line in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), start=1):
        text = line.strip()
        if not text or text.startswith("#") or text.startswith("TITLE"):
            continue
        if text[0].isalpha() and not text.startswith("LUT_3D_SIZE"):
            raise InputError(f"{path}, line {number}: unsupported keyword {text.split()[0]!r}")
        try:
            if text.startswith("LUT_3D_SIZE"):
                size = int(text.split()[1])
            else:
                values.append([float(v) for v in text.split()])
        except (ValueError, IndexError):
            raise InputError(f"{path}, line {number}: {text[:40]!r} is not a size or a row of "
                             "numbers") from None
    if size is None or size < 2 or len(values) != size ** 3 or any(len(v) != 3 for v in values):
        raise InputError(f"{path}: expected LUT_3D_SIZE and N³ rows; got size {size} and "
                         f"{len(values)} rows")
    return np.asarray(values, dtype=np.float64).reshape(size, size, size, 3)


@dataclass(frozen=True)
class CubeAccuracy:
    """CIEDE2000 of the trilinearly sampled ``.cube`` against the exact inverse, in gamut.

    ``samples`` random sRGB-encoded inputs whose XYZ the display shows without
    clipping; colours compared as the display shows them (its forward model of
    the float DAC), CIELAB white = the white mapping's XYZ.
    """

    mean_dE00: float
    p95_dE00: float
    max_dE00: float
    samples: int
    size: int

    def to_json(self) -> dict:
        return {"mean_dE00": round(self.mean_dE00, 4), "p95_dE00": round(self.p95_dE00, 4),
                "max_dE00": round(self.max_dE00, 4), "n": self.samples}


def cube_accuracy(table: np.ndarray, display: DisplayModel, k: float, *, samples: int = 20000,
                  seed: int = 0) -> CubeAccuracy:
    """Measure a ``.cube`` table against ``display``'s exact inverse (:class:`CubeAccuracy`)."""
    encoded = np.random.default_rng(seed).uniform(0.0, 1.0, (samples, 3))
    XYZ = srgb_input_to_XYZ(encoded, display, k)
    keep = display.in_gamut(XYZ)
    if not np.any(keep):
        raise InputError(f"no sRGB colour is in the gamut of {display.describe()!r} under the "
                         "white mapping; check the profile's k and white")
    encoded, XYZ = encoded[keep], XYZ[keep]
    exact = display.inverse(XYZ)
    sampled = np.clip(sample_trilinear(table, encoded).astype(np.float64) * 255.0, 0.0, 255.0)
    dE = delta_E2000(display.forward(sampled), display.forward(exact),
                     white_mapping_XYZ(display, k))
    return CubeAccuracy(float(np.mean(dE)), float(np.percentile(dE, 95)), float(np.max(dE)),
                        int(keep.sum()), int(table.shape[0]))
