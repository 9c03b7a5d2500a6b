"""8-bit RGB PNG texture files, written with Pillow, atomically.

The engine textures are plain 8-bit RGB images with ``tEXt`` chunks for
provenance (the engine light colour, the command's summary). The file holds
exactly the texels the workbench computed: no ``gAMA``, ``cHRM``, ``sRGB`` or
``iCCP`` chunk that a viewer would apply (the values *are* the sRGB texels).
Pillow encodes it (its adaptive per-row filtering, zlib); the bytes go through
:func:`workbench.fileio.atomic_writer`, so a failed write leaves the previous
file and no partial one.

:func:`png_chunks` lists a datastream's chunks (CRCs checked), for tests and
tools that check what a file carries.

References
----------
ISO/IEC 15948:2004 / W3C, Portable Network Graphics (PNG) Specification
(Second Edition), §5 (datastream), §11.3.4.3 (tEXt); Pillow,
``PIL.PngImagePlugin.PngInfo``.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

from workbench.errors import InputError
from workbench.fileio import atomic_writer

__all__ = ["PNG_SIGNATURE", "write_png_rgb8", "png_chunks"]

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _text_info(text: dict[str, str] | None):
    from PIL.PngImagePlugin import PngInfo

    info = PngInfo()
    for keyword, value in (text or {}).items():
        key = str(keyword).encode("latin-1", "replace")[:79]
        if not key or b"\x00" in key:
            raise InputError(f"PNG text keyword {keyword!r} must be 1–79 Latin-1 characters")
        # tEXt holds Latin-1; other characters become '?' (bytes keep Pillow from using iTXt).
        info.add_text(key.decode("latin-1"), str(value).encode("latin-1", "replace"))
    return info


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
    from PIL import Image

    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or min(rgb.shape[:2]) == 0:
        raise InputError(f"a PNG texture needs shape (H, W, 3); got {rgb.shape}")
    if rgb.dtype != np.uint8:
        if not np.issubdtype(rgb.dtype, np.integer) or rgb.min() < 0 or rgb.max() > 255:
            raise InputError("PNG texels must be integers 0..255")
        rgb = rgb.astype(np.uint8)
    if not 0 <= level <= 9:
        raise InputError(f"PNG compression level {level} must be 0..9")
    image = Image.fromarray(np.ascontiguousarray(rgb))
    path = Path(path)
    with atomic_writer(path, "wb") as handle:
        image.save(handle, "PNG", pnginfo=_text_info(text), compress_level=level)
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
