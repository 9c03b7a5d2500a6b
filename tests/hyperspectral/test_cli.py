"""The ``relight`` and ``bench relight`` commands, end to end (small cubes, no timing asserted)."""

import json
import struct
from pathlib import Path

import numpy as np
import pytest

import profiles

from workbench.cli import main
from workbench.hyperspectral import write_cube
from workbench.hyperspectral.png import png_chunks


def _png_size(path):
    chunks = dict(png_chunks(path.read_bytes()))
    width, height = struct.unpack(">II", chunks[b"IHDR"][:8])
    return height, width


@pytest.fixture
def cube_file(tmp_path, small_cube):
    return write_cube(small_cube, tmp_path / "scene.hdr")


@pytest.mark.parametrize("options", [
    ["--level", "2"],
    ["--level", "2", "--basis", "6"],
    ["--level", "2", "--basis", "full"],
    ["--level", "1"],
])
def test_relight_writes_the_texture_in_the_cube_layout(tmp_path, cube_file, small_cube, capsys,
                                                       options):
    out = tmp_path / "texture.png"
    status = main(["relight", str(cube_file), "--illuminant", "cie-a", "--display", "srgb",
                   "--out", str(out), "--json", *options])
    assert status == 0
    assert _png_size(out) == (small_cube.height, small_cube.width)
    summary = json.loads(capsys.readouterr().out)
    assert summary["shape"] == list(small_cube.shape)
    assert len(summary["light_rgb8"]) == 3
    if options[-1] == "6":
        assert summary["basis"]["K"] == 6


VIVE_PROFILE = Path(profiles.__file__).parent / "htc-vive-paper.vrprofile.json"


def test_relight_with_a_profile_and_a_render(tmp_path, cube_file, small_cube, capsys):
    out, render = tmp_path / "t.png", tmp_path / "frame.png"
    status = main(["relight", str(cube_file), "--illuminant", "d65-two-peak", "--profile",
                   str(VIVE_PROFILE), "--out", str(out), "--render", str(render), "--json"])
    assert status == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["texture"].startswith("level 2, spectral basis")
    assert _png_size(render) == _png_size(out) == (small_cube.height, small_cube.width)
    texts = dict(payload.split(b"\x00", 1) for kind, payload in png_chunks(out.read_bytes())
                 if kind == b"tEXt")
    light = ",".join(str(v) for v in summary["light_rgb8"]).encode()
    assert texts[b"workbench.light_rgb8"] == light


def test_level1_texture_does_not_depend_on_the_source(tmp_path, cube_file):
    import zlib

    pixels = []
    for source in ("cie-a", "cie-fl11"):
        out = tmp_path / f"{source}.png"
        assert main(["relight", str(cube_file), "--illuminant", source, "--display", "srgb",
                     "--level", "1", "--out", str(out)]) == 0
        pixels.append(zlib.decompress(dict(png_chunks(out.read_bytes()))[b"IDAT"]))
    assert pixels[0] == pixels[1]


def test_relight_errors_are_one_clear_line(tmp_path, cube_file, capsys):
    status = main(["relight", str(tmp_path / "none.npz"), "--illuminant", "cie-a",
                   "--display", "srgb", "--out", str(tmp_path / "x.png")])
    assert status == 2 and "no such file" in capsys.readouterr().err
    status = main(["relight", str(cube_file), "--illuminant", "cie-a", "--display", "srgb",
                   "--out", str(tmp_path / "x.jpg")])
    assert status == 2 and "*.png" in capsys.readouterr().err
    status = main(["relight", str(cube_file), "--illuminant", "cie-a", "--display", "srgb",
                   "--basis", "many", "--out", str(tmp_path / "x.png")])
    assert status == 2 and "--basis" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_bench_relight_json_has_the_fields(capsys):
    status = main(["bench", "relight", "--size", "32", "--repeats", "2",
                   "--full-band-repeats", "1", "--json"])
    assert status == 0
    result = json.loads(capsys.readouterr().out)
    for field in ("ms_per_relight", "full_band_ms", "speedup_vs_full", "K", "max_dE00",
                  "per_source_max_dE00", "kernel_ms", "plan_ms"):
        assert field in result, field
    assert result["size"] == 32 and result["bands"] == 101
    assert set(result["per_source_max_dE00"]) == {"cie-d65", "cie-a", "cie-fl11", "d65-two-peak"}
    assert result["max_dE00"] == max(result["per_source_max_dE00"].values())
    assert result["ms_per_relight"] > 0 and result["full_band_ms"] > 0
    assert 1 <= result["K"] <= 24 and np.isfinite(result["speedup_vs_full"])


def test_bench_lists_its_benchmarks(capsys):
    with pytest.raises(SystemExit):
        main(["bench", "--help"])
    assert "relight" in capsys.readouterr().out
