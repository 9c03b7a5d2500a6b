#!/usr/bin/env python3
"""Reference consumer of a VR colour workbench runtime bundle: what a runtime must compute.

Needs only Python 3 and numpy (no workbench): it reads the bundle's files as
a game engine would and computes, with the engine's float32 arithmetic,

- ``python reference_consumer.py BUNDLE light ID`` → ``{"rgb8": [r, g, b]}``:
  the level-1 light colour (8-bit sRGB-encoded) to set in the engine;
- ``python reference_consumer.py BUNDLE texture NAME --light ID --out FILE.png``:
  the level-2 texture of cube ``NAME`` under light ``ID`` (what the shader
  renders), and ``{"texels": N, "unreachable": M}`` on standard output;
- ``python reference_consumer.py BUNDLE cube R G B``: the ``display_inverse.cube``
  sampled trilinearly at sRGB-encoded ``R G B`` (0..1) → ``{"dac": [...]}`` (0..255).

Level 2, per texel (the shaders do the same):
``drive = matrix · channels + offset`` (3 × C, float32); where
``display_inverse.json`` names a correction table, ``drive = trilinear(table,
(clamp(drive, lo, hi) − lo)/(hi − lo))``; ``u = sqrt(clamp(drive, 0, 1))``;
``DAC_c = #{thresholds_c ≤ u_c}`` (found from ``cells``, a lower bound per cell of ``u``,
stepping up as the shaders do); ``texel_c = texel_table[c][DAC_c]``;
unreachable where any ``DAC_c ≥ unreachable_dac[c]``.

Every problem with a bundle is one line on standard error and exit status 2.
"""

import argparse
import json
import struct
import sys
import zlib
from pathlib import Path

import numpy as np

SUPPORTED_VERSION = 1
BUNDLE_FORMAT = "vr-colour-workbench-bundle"
MAX_JSON_BYTES = 64 * 1024 * 1024


class BundleError(Exception):
    """The bundle is missing, truncated, of another version, or malformed."""


def _reject_constant(name):
    raise BundleError(f"{name} is not a JSON number")


def read_json(path):
    path = Path(path)
    if not path.is_file():
        raise BundleError(f"{path}: missing from the bundle")
    if path.stat().st_size > MAX_JSON_BYTES:
        raise BundleError(f"{path}: larger than {MAX_JSON_BYTES} bytes; not a bundle file")
    try:
        document = json.loads(path.read_text(encoding="utf-8"), parse_constant=_reject_constant)
    except (UnicodeDecodeError, json.JSONDecodeError, BundleError) as error:
        raise BundleError(f"{path}: not valid JSON ({error}); export the bundle again") from None
    if not isinstance(document, dict):
        raise BundleError(f"{path}: expected a JSON object")
    return document


def numbers(document, key, count, where, dtype=np.float32, low=None, high=None):
    """``document[key]`` as a finite numeric array of ``count`` values."""
    value = document.get(key) if isinstance(document, dict) else None
    if not isinstance(value, list) or len(value) != count or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise BundleError(f"{where}: '{key}' must be a list of {count} numbers")
    array = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(array)) or (low is not None and np.any(array < low)) or \
            (high is not None and np.any(array > high)):
        raise BundleError(f"{where}: '{key}' holds a value out of range")
    return array.astype(dtype)


def integer(document, key, where, low, high):
    value = document.get(key) if isinstance(document, dict) else None
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise BundleError(f"{where}: '{key}' must be an integer in {low}..{high}")
    return value


class Bundle:
    """A bundle folder, checked as it is read."""

    def __init__(self, folder):
        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise BundleError(f"{self.folder}: no such bundle folder")
        self.manifest = read_json(self.folder / "bundle.json")
        if self.manifest.get("format") != BUNDLE_FORMAT:
            raise BundleError(f"{self.folder}/bundle.json: not a VR colour workbench bundle")
        version = self.manifest.get("format_version")
        if isinstance(version, bool) or not isinstance(version, int):
            raise BundleError(f"{self.folder}/bundle.json: format_version must be an integer")
        if version > SUPPORTED_VERSION:
            raise BundleError(f"{self.folder}: bundle format_version {version} is newer than this "
                              f"consumer supports ({SUPPORTED_VERSION}); use the consumer shipped "
                              "in the bundle's runtime/ folder")

    # level 1 ---------------------------------------------------------------------------
    def light(self, light_id):
        table = read_json(self.folder / "lights.json")
        lights = table.get("lights")
        if not isinstance(lights, list):
            raise BundleError(f"{self.folder}/lights.json: 'lights' must be a list")
        for entry in lights:
            if isinstance(entry, dict) and entry.get("id") == light_id:
                rgb8 = numbers(entry, "rgb8", 3, f"lights.json {light_id}", np.int64, 0, 255)
                return [int(v) for v in rgb8]
        known = [e.get("id") for e in lights if isinstance(e, dict)]
        raise BundleError(f"no light {light_id!r} in the bundle; it has {known}")

    # display inverse -------------------------------------------------------------------
    def display_inverse(self):
        where = "display_inverse.json"
        document = read_json(self.folder / where)
        thresholds = numbers(document, "thresholds", 765, where).reshape(3, 255)
        cells = document.get("cells")
        count = len(cells) // 3 if isinstance(cells, list) else 0
        if count < 2 or len(cells) != 3 * count:
            raise BundleError(f"{where}: 'cells' must be a list of 3 rows of lower bounds")
        cells = numbers(document, "cells", 3 * count, where, np.int64, 0, 255).reshape(3, count)
        correction = document.get("correction")
        if not isinstance(correction, dict):
            raise BundleError(f"{where}: 'correction' must be an object")
        size = integer(correction, "size", where + " correction", 0, 257)
        table, domain = None, None
        if size:
            if size < 2:
                raise BundleError(f"{where}: a correction table needs at least 2 nodes per axis")
            domain = numbers(correction, "domain", 2, where + " correction")
            name = correction.get("file")
            if not isinstance(name, str) or "/" in name or "\\" in name or not name:
                raise BundleError(f"{where}: correction 'file' must be a file name in the bundle")
            table = read_floats(self.folder / name, size ** 3 * 3, "<f4").reshape(size, size, size, 3)
        return thresholds, cells, table, domain

    # level 2 ---------------------------------------------------------------------------
    def level2(self, name, light_id):
        cubes = self.manifest.get("cubes")
        if not isinstance(cubes, list):
            raise BundleError(f"{self.folder}/bundle.json: 'cubes' must be a list")
        cubes = [c for c in cubes if isinstance(c, dict)]
        if not any(c.get("name") == name for c in cubes):
            raise BundleError(f"no level-2 texture {name!r} in the bundle; it has "
                              f"{[c.get('name') for c in cubes]}")
        if "/" in name or "\\" in name or name.startswith("."):
            raise BundleError(f"texture name {name!r} is not a plain name")
        folder = self.folder / "level2" / name
        where = f"level2/{name}/coefficients.json"
        header = read_json(folder / "coefficients.json")
        width = integer(header, "width", where, 1, 1 << 15)
        height = integer(header, "height", where, 1, 1 << 15)
        channels = integer(header, "channels", where, 1, 64)
        layers = integer(header, "layers", where, 1, 16)
        if layers != -(-channels // 4):
            raise BundleError(f"{where}: {channels} channels need {-(-channels // 4)} layers, "
                              f"not {layers}")
        planes = read_floats(folder / "coefficients.bin", layers * height * width * 4, "<f2")
        planes = planes.reshape(layers, height, width, 4).transpose(0, 3, 1, 2)
        planes = planes.reshape(layers * 4, height * width)[:channels]
        lights = read_json(folder / "lights.json").get("lights")
        records = [e for e in lights if isinstance(e, dict) and e.get("id") == light_id] \
            if isinstance(lights, list) else []
        if not records:
            raise BundleError(f"level2/{name}/lights.json: no light {light_id!r}")
        record, lwhere = records[0], f"level2/{name}/lights.json {light_id}"
        matrix = numbers(record, "matrix", 3 * channels, lwhere).reshape(3, channels)
        offset = numbers(record, "offset", 3, lwhere)
        texel_table = numbers(record, "texel_table", 768, lwhere, np.int64, 0, 255).reshape(3, 256)
        unreachable_dac = numbers(record, "unreachable_dac", 3, lwhere, np.int64, 0, 256)
        return (width, height), planes, matrix, offset, texel_table, unreachable_dac


def read_floats(path, count, dtype):
    path = Path(path)
    if not path.is_file():
        raise BundleError(f"{path}: missing from the bundle")
    expected = count * np.dtype(dtype).itemsize
    size = path.stat().st_size
    if size != expected:
        raise BundleError(f"{path}: {size} bytes where its header promises {expected} "
                          "(truncated or from another export); export the bundle again")
    values = np.fromfile(path, dtype=dtype, count=count)
    if not np.all(np.isfinite(values)):
        raise BundleError(f"{path}: holds NaN or infinity")
    return values


def trilinear(table, coordinates):
    """``table`` (n, n, n, C) indexed [b, g, r]; ``coordinates`` (..., 3) r, g, b on 0..1."""
    n = table.shape[0]
    position = np.clip(coordinates.astype(np.float32), 0.0, 1.0) * np.float32(n - 1)
    base = np.minimum(np.floor(position).astype(np.int64), n - 2)
    fraction = (position - base).astype(np.float32)
    r0, g0, b0 = base[..., 0], base[..., 1], base[..., 2]
    fr, fg, fb = (fraction[..., i:i + 1] for i in range(3))
    result = np.zeros(position.shape[:-1] + (table.shape[-1],), dtype=np.float32)
    for db, wb in ((0, 1 - fb), (1, fb)):
        for dg, wg in ((0, 1 - fg), (1, fg)):
            for dr, wr in ((0, 1 - fr), (1, fr)):
                result += (wb * wg * wr) * table[b0 + db, g0 + dg, r0 + dr]
    return result


def level2_texture(bundle, name, light_id):
    """(H, W, 3) uint8 texels and the unreachable count (module doc)."""
    (width, height), planes, matrix, offset, texel_table, unreachable_dac = \
        bundle.level2(name, light_id)
    thresholds, cells, table, domain = bundle.display_inverse()
    drive = planes.astype(np.float32).T @ matrix.T + offset
    if table is not None:
        low, high = np.float32(domain[0]), np.float32(domain[1])
        drive = trilinear(table, (drive - low) / (high - low))
    u = np.sqrt(np.clip(drive, np.float32(0.0), np.float32(1.0))).astype(np.float32)
    dac = np.stack([dac_level(thresholds[c], cells[c], u[:, c]) for c in range(3)], axis=-1)
    texels = texel_table[np.arange(3), dac].astype(np.uint8)
    unreachable = int(np.count_nonzero(np.any(dac >= unreachable_dac, axis=-1)))
    return texels.reshape(height, width, 3), unreachable


def dac_level(thresholds, cells, u):
    """How many of ``thresholds`` (255) are ≤ ``u``: from the cell's lower bound, step up."""
    level = cells[(u * np.float32(len(cells) - 1)).astype(np.int64)]
    padded = np.append(thresholds, np.float32(np.inf))
    while True:
        step = padded[level] <= u
        if not np.any(step):
            return level
        level = level + step


def read_cube(path):
    size, rows = None, []
    if not Path(path).is_file():
        raise BundleError(f"{path}: missing from the bundle")
    try:
        for line in Path(path).read_text(encoding="utf-8").splitlines():
            text = line.strip()
            if not text or text.startswith("#") or text.startswith("TITLE"):
                continue
            if text.startswith("LUT_3D_SIZE"):
                size = int(text.split()[1])
            else:
                rows.append([float(v) for v in text.split()])
    except (UnicodeDecodeError, ValueError, IndexError):
        size = None
    if size is None or size < 2 or len(rows) != size ** 3 or any(len(r) != 3 for r in rows):
        raise BundleError(f"{path}: not a complete .cube (LUT_3D_SIZE and N^3 rows of r g b)")
    table = np.asarray(rows, dtype=np.float32).reshape(size, size, size, 3)
    if not np.all(np.isfinite(table)):
        raise BundleError(f"{path}: holds NaN or infinity")
    return table


def write_png(path, rgb):
    """8-bit RGB PNG (stdlib zlib)."""
    height, width, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(height))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    data = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))
    Path(path).write_bytes(data)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("bundle")
    commands = parser.add_subparsers(dest="command", required=True)
    light = commands.add_parser("light", help="level-1 light colour")
    light.add_argument("id")
    texture = commands.add_parser("texture", help="level-2 texture of a cube under a light")
    texture.add_argument("name")
    texture.add_argument("--light", required=True)
    texture.add_argument("--out", required=True)
    cube = commands.add_parser("cube", help="display_inverse.cube at an sRGB-encoded colour")
    cube.add_argument("rgb", nargs=3, type=float)
    args = parser.parse_args(argv)
    try:
        bundle = Bundle(args.bundle)
        if args.command == "light":
            print(json.dumps({"rgb8": bundle.light(args.id)}))
        elif args.command == "texture":
            texels, unreachable = level2_texture(bundle, args.name, args.light)
            write_png(args.out, texels)
            print(json.dumps({"texels": int(texels.shape[0] * texels.shape[1]),
                              "unreachable": unreachable, "out": args.out}))
        else:
            table = read_cube(bundle.folder / "display_inverse.cube")
            dac = trilinear(table, np.asarray(args.rgb, dtype=np.float32)) * 255.0
            print(json.dumps({"dac": [round(float(v), 4) for v in dac]}))
    except (BundleError, OSError) as error:   # OSError: an unreadable file, an unwritable --out
        print(f"error: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
