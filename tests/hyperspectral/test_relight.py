"""Level-2 relighting: the basis kernel against the design's level-2 texel, and its parts."""

from dataclasses import dataclass

import numpy as np
import pytest

from workbench.colour_management import authored_srgb8, level2_texture
from workbench.display import GammaMatrixDisplay, SRGBDisplay, quantize_dac
from workbench.errors import InputError
from workbench.hyperspectral import (
    ACCURACY_SOURCES,
    authored_srgb8_cube,
    channel_inverse_lut,
    encode_cube,
    fit_cube_basis,
    is_channel_separable,
    plan_relight,
    relight_full_band,
    relight_texels,
    write_png_rgb8,
)
from workbench.hyperspectral.png import png_chunks
from workbench.illuminants import get_illuminant
from workbench.profile import paper_vive_profile

DISPLAYS = {"srgb": SRGBDisplay(), "vive": paper_vive_profile().display_model()}


@pytest.fixture(scope="module")
def strict_texture(small_cube):
    # Texel-level agreement is stricter than ΔE: where a light channel is dim (blue under
    # CIE A) level 2 divides by it, and one DAC count becomes several texel counts; a
    # target of 0.05 ΔE00 keeps the DAC flips rare enough.
    basis = fit_cube_basis(small_cube, target_max_dE00=0.05)
    return encode_cube(small_cube, basis)


def _within_one(a, b):
    return np.mean(np.abs(a.astype(int).reshape(-1, 3) - b.astype(int).reshape(-1, 3)).max(-1) <= 1)


@pytest.mark.parametrize("display_id", sorted(DISPLAYS))
@pytest.mark.parametrize("source", ACCURACY_SOURCES)
def test_basis_texels_match_the_level2_reference(small_cube, strict_texture, display_id, source):
    display = DISPLAYS[display_id]
    illuminant = get_illuminant(source)
    texels = relight_texels(strict_texture, plan_relight(strict_texture.basis, illuminant, display))
    assert texels.shape == (small_cube.height, small_cube.width, 3) and texels.dtype == np.uint8
    reference = level2_texture(small_cube.texels(), illuminant.sd, display,
                               wavelengths=small_cube.wavelengths)
    assert _within_one(texels, reference.rgb8) >= 0.99


@pytest.mark.parametrize("source", ["cie-a", "d65-two-peak"])
def test_full_band_path_is_the_level2_reference(small_cube, source):
    illuminant = get_illuminant(source)
    display = DISPLAYS["vive"]
    full = relight_full_band(small_cube, illuminant, display)
    reference = level2_texture(small_cube.texels(), illuminant.sd, display,
                               wavelengths=small_cube.wavelengths)
    assert np.mean(full.reshape(-1, 3) == reference.rgb8) >= 0.999


def test_numba_and_numpy_kernels_agree(strict_texture):
    plan = plan_relight(strict_texture.basis, get_illuminant("cie-fl11"), DISPLAYS["vive"])
    fused = relight_texels(strict_texture, plan, kernel="numba")
    generic = relight_texels(strict_texture, plan, kernel="numpy")
    assert np.mean(fused == generic) >= 0.9999
    out = np.zeros_like(fused)
    assert relight_texels(strict_texture, plan, out=out) is out and np.array_equal(out, fused)
    with pytest.raises(InputError, match="numba"):
        relight_texels(strict_texture, plan, kernel="cuda")


@pytest.mark.parametrize("display_id", sorted(DISPLAYS))
def test_channel_tables_are_the_display_inverse(rng, display_id):
    display = DISPLAYS[display_id]
    lut = channel_inverse_lut(display)
    XYZ = rng.uniform(0, 1, (20000, 3)) * display.white_XYZ
    XYZ[:2000] *= 0.01                                   # plenty of near-black texels
    expected = quantize_dac(display.inverse(XYZ))
    got = lut.dac(XYZ)
    assert np.abs(got - expected).max() <= 1
    assert np.mean(got == expected) >= 0.999


@dataclass(frozen=True, eq=False)
class _CrosstalkDisplay(GammaMatrixDisplay):
    """The paper's model plus a tone curve that leaks red into green: not separable."""

    def dac_from_drive(self, drive):
        drive = np.asarray(drive, dtype=float).copy()
        drive[..., 1] = np.clip(drive[..., 1] + 0.05 * drive[..., 0], 0, 1)
        return super().dac_from_drive(drive)


def test_a_non_separable_display_falls_back_to_its_own_inverse(strict_texture):
    vive = DISPLAYS["vive"]
    display = _CrosstalkDisplay(gamma=vive.gamma, matrix=vive.matrix, white=vive.white)
    assert is_channel_separable(vive) and not is_channel_separable(display)
    plan = plan_relight(strict_texture.basis, get_illuminant("cie-d65"), display)
    assert plan.inverse_lut is None
    with pytest.raises(InputError, match="separable per channel"):
        relight_texels(strict_texture, plan, kernel="numba")
    texels = relight_texels(strict_texture, plan)                   # auto → numpy
    planes = strict_texture.coefficients.reshape(strict_texture.basis.components, -1)
    XYZ = plan.XYZ_offset + planes.T.astype(float) @ plan.XYZ_matrix
    assert np.mean(texels.reshape(-1, 3) == plan.texel_table[np.arange(3),
                                                             quantize_dac(display.inverse(XYZ))]) > 0.999


def test_a_plan_for_another_basis_is_refused(small_cube, strict_texture):
    other = fit_cube_basis(small_cube, components=3)
    with pytest.raises(InputError, match="another basis"):
        relight_texels(strict_texture, plan_relight(other, get_illuminant("cie-a")))


def test_level1_texture_is_the_authored_srgb(small_cube):
    texture = authored_srgb8_cube(small_cube)
    expected = authored_srgb8(small_cube.texels(), wavelengths=small_cube.wavelengths)
    assert np.mean(texture.reshape(-1, 3) == expected) >= 0.999


def _unfilter_png_rows(raw, height, row_bytes, pixel_bytes=3):
    """Undo PNG scanline filters (ISO/IEC 15948 §9.2), independently of the writer."""
    rows = np.zeros((height, row_bytes), dtype=np.int64)
    for y in range(height):
        kind, line = raw[y, 0], raw[y, 1:].astype(np.int64)
        above = rows[y - 1] if y else np.zeros(row_bytes, dtype=np.int64)
        out = rows[y]
        for x in range(row_bytes):
            left = out[x - pixel_bytes] if x >= pixel_bytes else 0
            corner = above[x - pixel_bytes] if x >= pixel_bytes else 0
            if kind == 0:
                predictor = 0
            elif kind == 1:
                predictor = left
            elif kind == 2:
                predictor = above[x]
            elif kind == 3:
                predictor = (left + above[x]) // 2
            else:
                assert kind == 4, kind
                p = left + above[x] - corner
                pa, pb, pc = abs(p - left), abs(p - above[x]), abs(p - corner)
                predictor = left if pa <= pb and pa <= pc else above[x] if pb <= pc else corner
            out[x] = (line[x] + predictor) % 256
    return rows


def test_png_holds_exactly_the_texels(tmp_path, rng):
    import zlib

    rgb = rng.integers(0, 256, (7, 11, 3)).astype(np.uint8)
    path = write_png_rgb8(tmp_path / "t.png", rgb, {"Comment": "test"})
    chunks = dict(png_chunks(path.read_bytes()))
    width, height = np.frombuffer(chunks[b"IHDR"][:8], ">u4")
    assert (height, width) == (7, 11)
    assert chunks[b"IHDR"][8:10] == bytes([8, 2])                   # 8-bit truecolour
    assert chunks[b"tEXt"] == b"Comment\x00test"
    # No chunk a viewer would colour-manage with: the values are the sRGB texels.
    assert not {b"gAMA", b"cHRM", b"sRGB", b"iCCP"} & set(chunks)
    idat = b"".join(payload for kind, payload in png_chunks(path.read_bytes()) if kind == b"IDAT")
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(7, 1 + 33)
    assert np.all(raw[:, 0] <= 4)                                   # PNG filter types 0-4
    rows = _unfilter_png_rows(raw, 7, 33).reshape(7, 11, 3)
    np.testing.assert_array_equal(rows, rgb)
    image = pytest.importorskip("PIL.Image")
    np.testing.assert_array_equal(np.asarray(image.open(path).convert("RGB")), rgb)


def test_png_text_and_a_failed_write(tmp_path, rng, monkeypatch):
    from PIL import Image

    rgb = rng.integers(0, 256, (5, 4, 3)).astype(np.uint8)
    path = write_png_rgb8(tmp_path / "t.png", rgb, {"workbench.light_rgb8": "255,218,123",
                                                   "Description": "engine texture × light"})
    with Image.open(path) as image:
        assert image.text == {"workbench.light_rgb8": "255,218,123",
                              "Description": "engine texture × light"}
    before = path.read_bytes()

    def save_that_dies(self, handle, *args, **kwargs):
        handle.write(before[:20])
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Image.Image, "save", save_that_dies)
    with pytest.raises(OSError):
        write_png_rgb8(path, rgb[::-1])
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.png"]
    with pytest.raises(InputError, match=r"\(H, W, 3\)"):
        write_png_rgb8(tmp_path / "flat.png", rgb[..., 0])


# --- one level-2 formula, and the texels a light cannot carry ---------------------------------


def test_the_kernel_tables_are_the_level2_formula(rng):
    from workbench.colour_management import level2_albedo8, light_colour
    from workbench.hyperspectral.level2_texels import level2_texel_table, level2_unreachable_dac

    for source in ("cie-d65", "cie-a"):
        light = light_colour(get_illuminant(source).sd).linear
        dac = rng.integers(0, 256, (5000, 3))
        texels, unreachable = level2_albedo8(dac, light)
        table = level2_texel_table(light)
        np.testing.assert_array_equal(table[np.arange(3), dac], texels)
        np.testing.assert_array_equal(np.any(dac >= level2_unreachable_dac(light), axis=-1),
                                      unreachable)
    # sRGB 188 is the first level above linear 0.5, 124 the first above 0.2; a channel the
    # light does not have carries only black.
    dark = np.array([0.5, 0.2, 0.0])
    assert level2_unreachable_dac(dark).tolist() == [188, 124, 1]
    assert level2_unreachable_dac(np.ones(3)).tolist() == [256, 256, 256]
    texels, unreachable = level2_albedo8(np.array([[100, 50, 0], [100, 50, 1]]), dark)
    assert unreachable.tolist() == [False, True] and texels[1, 2] == 0


def test_level2_texture_uses_the_shared_formula(small_cube):
    from workbench.colour_management import level2_albedo8, light_colour_from_XYZ

    texture = level2_texture(small_cube.texels(), get_illuminant("cie-a").sd,
                             wavelengths=small_cube.wavelengths)
    texels, unreachable = level2_albedo8(quantize_dac(texture.target_dac), texture.light.linear)
    np.testing.assert_array_equal(texture.rgb8, texels)
    np.testing.assert_array_equal(texture.unreachable, unreachable)
    again = light_colour_from_XYZ(texture.light.XYZ, SRGBDisplay())
    assert again.rgb8.tolist() == texture.light.rgb8.tolist()
    assert again.in_gamut == texture.light.in_gamut


def _pure_samples_cube(name, rows, columns):
    from workbench.hyperspectral import PAPER_CUBE_WAVELENGTHS, ReflectanceCube
    from workbench.hyperspectral.materials import material_reflectances

    spectra = material_reflectances(name, PAPER_CUBE_WAVELENGTHS)
    return ReflectanceCube(spectra.reshape(rows, columns, -1).astype(np.float32),
                           PAPER_CUBE_WAVELENGTHS, name)


@pytest.fixture(scope="module")
def ces_samples_texture():
    cube = _pure_samples_cube("ces99", 9, 11)
    return cube, encode_cube(cube, fit_cube_basis(cube))


# Narrow red LEDs outside each display's gamut: the light colour loses a channel (sRGB: blue,
# Vive: green) and is weak in another, which some orange CIE 2017 samples need more of.
@pytest.mark.parametrize("display_id, peak, half_width, missing", [("srgb", 610, 15, 2),
                                                                   ("vive", 620, 25, 1)])
def test_the_kernels_count_texels_a_led_cannot_carry(ces_samples_texture, display_id, peak,
                                                     half_width, missing):
    import colour

    from workbench.colorimetry import WORKING_SHAPE
    from workbench.hyperspectral import relight_level2, relight_level2_full_band

    cube, texture = ces_samples_texture
    display = DISPLAYS[display_id]
    led = colour.sd_single_led(peak, half_spectral_width=half_width, shape=WORKING_SHAPE)
    plan = plan_relight(texture.basis, led, display)
    assert plan.light.rgb8[missing] == 0 and plan.unreachable_dac[missing] == 1
    reference = level2_texture(cube.texels(), led, display, wavelengths=cube.wavelengths)
    expected = int(reference.unreachable.sum())
    assert expected > 0
    fused = relight_level2(texture, plan, kernel="numba")
    generic = relight_level2(texture, plan, kernel="numpy")
    full = relight_level2_full_band(cube, led, display)
    assert fused.unreachable == generic.unreachable == full.unreachable == expected
    assert fused.source == plan.source and 0 < fused.unreachable_fraction < 1
    np.testing.assert_array_equal(relight_texels(texture, plan), fused.texels)


@pytest.mark.parametrize("display_id", sorted(DISPLAYS))
def test_no_texel_is_unreachable_for_the_colorchecker_under_d65(ces_samples_texture, display_id):
    from workbench.hyperspectral import relight_level2, relight_level2_full_band

    _, texture = ces_samples_texture
    checker = _pure_samples_cube("colorchecker", 4, 6)
    display = DISPLAYS[display_id]
    d65 = get_illuminant("cie-d65")
    plan = plan_relight(texture.basis, d65, display)
    assert relight_level2(encode_cube(checker, texture.basis), plan).unreachable == 0
    assert relight_level2_full_band(checker, d65, display).unreachable == 0
    assert not level2_texture(checker.texels(), d65.sd, display,
                              wavelengths=checker.wavelengths).unreachable.any()


# --- the compiled kernel's cells: one look-up and one comparison give the runtime's DAC --------


def _count_at_or_below(thresholds, u):
    return np.stack([np.searchsorted(thresholds[c], u[..., c], side="right") for c in range(3)],
                    axis=-1)


@pytest.mark.parametrize("display_id", sorted(DISPLAYS))
def test_dac_cells_count_the_thresholds_as_the_runtime_does(rng, display_id):
    from workbench.hyperspectral.channel_inverse import dac_cells
    from workbench.hyperspectral.level2_texels import level2_texel_table

    thresholds = channel_inverse_lut(DISPLAYS[display_id]).thresholds[:, 1:256]
    cells = dac_cells(thresholds)
    assert cells is not None and cells.cells >= 512
    reached = thresholds.T[np.isfinite(thresholds.T).all(axis=1)]
    u = np.concatenate([rng.uniform(0, 1, (50000, 3)), reached,
                        np.nextafter(reached, 0), np.nextafter(reached, 2),
                        [[0, 0, 0], [1, 1, 1]]]).astype(np.float32)
    np.testing.assert_array_equal(cells.dac(u), _count_at_or_below(thresholds, u))
    # packed for the kernel: the threshold's bits, then the texels below and at or above it
    table = level2_texel_table(light_colour_of("cie-a", DISPLAYS[display_id]))
    packed = cells.texel_cells(table)
    assert packed.dtype == np.uint64 and packed.shape == (3, cells.cells)
    np.testing.assert_array_equal((packed & 0xFFFFFFFF).astype(np.uint32).view(np.float32),
                                  cells.threshold)
    np.testing.assert_array_equal((packed >> 32) & 0xFF, table[np.arange(3)[:, None], cells.below])
    np.testing.assert_array_equal((packed >> 40) & 0xFF, table[np.arange(3)[:, None], cells.above])


def light_colour_of(source, display):
    from workbench.colour_management import light_colour

    return light_colour(get_illuminant(source).sd, display).linear


def test_dac_cells_of_tied_and_unreached_levels():
    from workbench.hyperspectral.channel_inverse import dac_cells

    # levels 1–3 start at drive 0 (a display whose black is DAC 3), levels 251–255 never come
    row = np.concatenate([[0.0, 0.0, 0.0], np.linspace(0.01, 0.99, 247), [2.0] * 5])
    thresholds = np.stack([row, row, np.sqrt(np.linspace(0, 1, 255))]).astype(np.float32)
    cells = dac_cells(thresholds)
    u = np.array([[0, 0, 0], [0.5, 0.5, 0.5], [1, 1, 1], [0.01, 0.01, 0.0]], np.float32)
    np.testing.assert_array_equal(cells.dac(u), _count_at_or_below(thresholds, u))
    assert cells.dac(u)[0, 0] == 3 and cells.dac(u)[2, 0] == 250
    assert cells.reach_limits([0, 251, 256]).tolist() == [-np.inf, np.inf, np.inf]
    assert cells.reach_limits([4, 1, 255])[0] == np.float32(0.01)
    assert dac_cells(thresholds[:, ::-1]) is None                     # not sorted
    close = thresholds.copy()
    close[2, 100] = np.nextafter(close[2, 101], np.float32(0))        # two levels 1 ulp apart
    assert dac_cells(close) is None
