"""8-bit RGB PNG files written with the standard library (zlib), atomically.

The engine textures are plain 8-bit RGB images; the PNG format for them is
four chunks (``IHDR``, ``tEXt`` for provenance, ``IDAT``, ``IEND``), each a
length, a type, the data and a CRC-32. Writing it with :mod:`zlib` and
:mod:`struct` needs no image library, keeps the bytes exactly what the
workbench computed (no colour management or gamma chunk that a viewer would
apply: the values *are* the sRGB texels), and lets the writer be atomic like
every other output.

Scanlines use PNG filter type 1 (Sub: each byte minus the one three bytes to
its left), which suits smooth textures and costs one vectorized subtraction.

References
----------
ISO/IEC 15948:2004 / W3C, Portable Network Graphics (PNG) Specification
(Second Edition), §5 (datastream), §9 (filtering), §11.2.2 (IHDR), §11.3.4.3 (tEXt).
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

from workbench.errors import InputError
from workbench.fileio import atomic_output

__all__ = ["PNG_SIGNATURE", "write_png_rgb8", "png_chunks"]

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def _text_chunk(keyword: str, text: str) -> bytes:
    key = keyword.encode("latin-1", "replace")[:79]
    if not key or b"\x00" in key:
        raise InputError(f"PNG text keyword {keyword!r} must be 1–79 Latin-1 characters")
    return _chunk(b"tEXt", key + b"\x00" + text.encode("latin-1", "replace"))


def write_png_rgb8(path, rgb, text: dict[str, str] | None = None, *, level: int = 6) -> Path:
    """Write ``rgb`` ``(H, W, 3)`` uint8 as an 8-bit RGB PNG, atomically.

    Parameters
    ----------
    path : path-like
        Output file (``.png``).
    rgb : array_like (H, W, 3)
        Values 0..255 (integers).
    text : dict, optional
        ``tEXt`` chunks (keyword → Latin-1 text), e.g. provenance.
    level : int
        zlib compression level (0–9).

    Returns
    -------
    Path
    """
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or min(rgb.shape[:2]) == 0:
        raise InputError(f"a PNG texture needs shape (H, W, 3); got {rgb.shape}")
    if rgb.dtype != np.uint8:
        if not np.issubdtype(rgb.dtype, np.integer) or rgb.min() < 0 or rgb.max() > 255:
            raise InputError("PNG texels must be integers 0..255")
        rgb = rgb.astype(np.uint8)
    height, width, _ = rgb.shape
    rows = np.ascontiguousarray(rgb).reshape(height, width * 3)
    filtered = np.empty((height, width * 3 + 1), dtype=np.uint8)
    filtered[:, 0] = 1                                   # filter type Sub
    filtered[:, 1:4] = rows[:, :3]
    np.subtract(rows[:, 3:], rows[:, :-3], out=filtered[:, 4:], casting="unsafe")
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)   # 8-bit truecolour
    body = [PNG_SIGNATURE, _chunk(b"IHDR", header)]
    body += [_text_chunk(key, value) for key, value in (text or {}).items()]
    body += [_chunk(b"IDAT", zlib.compress(filtered.tobytes(), level)), _chunk(b"IEND", b"")]
    path = Path(path)
    with atomic_output(path) as (staged,):
        staged.write_bytes(b"".join(body))
    return path


def png_chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    """``(type, data)`` of every chunk of a PNG datastream, CRCs checked (for tests and tools)."""
    if not data.startswith(PNG_SIGNATURE):
        raise InputError("not a PNG datastream (bad signature)")
    chunks, position = [], len(PNG_SIGNATURE)
    while position < len(data):
        (length,) = struct.unpack(">I", data[position:position + 4])
        kind = data[position + 4:position + 8]
        payload = data[position + 8:position + 8 + length]
        (crc,) = struct.unpack(">I", data[position + 8 + length:position + 12 + length])
        if len(payload) != length or zlib.crc32(kind + payload) & 0xFFFFFFFF != crc:
            raise InputError(f"PNG chunk {kind!r} is truncated or corrupt")
        chunks.append((kind, payload))
        position += 12 + length
    return chunks
