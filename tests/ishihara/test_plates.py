import numpy as np
import pytest

from workbench.errors import InputError, SpectrumFileError
from workbench.ishihara import Viewing, read_plate
from workbench.ishihara.packing import DISC_RADIUS_FRACTION, pack_dots
from workbench.ishihara.plates import (
    PLATE_TYPES,
    PlateSpec,
    generate_plate,
    load_plate,
    paper_coloured_plate,
    paper_plate_set_specs,
    save_plate,
    write_plate_preview,
)

REAL_D65 = Viewing("cie-d65", "physical")

# Each plate type with digits other than the paper's, to show the type logic is general.
SPECS_BY_TYPE = [
    PlateSpec(1, "demonstration", "74", "74", "74"),
    PlateSpec(2, "transformation", "9", "4", "4"),
    PlateSpec(3, "transformation", "74", "21", "21"),
    PlateSpec(4, "vanishing", "45", "-", "-"),
    PlateSpec(5, "hidden-digit", "-", "73", "73"),
    PlateSpec(6, "classification", "42", "2", "4"),
]


@pytest.mark.parametrize("spec", SPECS_BY_TYPE, ids=lambda s: f"{s.kind}-{s.normal}")
def test_each_plate_type_is_read_as_its_type_says(spec, observers):
    plate = generate_plate(spec, size=160, seed=7)
    for name, observer in observers.items():
        assert read_plate(plate, observer, REAL_D65).answer == spec.expected(name), name


def test_every_plate_type_is_covered():
    assert {s.kind for s in SPECS_BY_TYPE} == set(PLATE_TYPES)


@pytest.mark.parametrize("spec, match", [
    (PlateSpec(1, "demonstration", "12", "12", "3"), "alike"),
    (PlateSpec(1, "transformation", "8", "3", "5"), "transformation"),
    (PlateSpec(1, "vanishing", "7", "7", "-"), "nothing"),
    (PlateSpec(1, "hidden-digit", "5", "5", "5"), "hidden-digit"),
    (PlateSpec(1, "classification", "26", "2", "2"), "two digits"),
    (PlateSpec(1, "vanishing", "123", "-", "-"), "one or two digits"),
    (PlateSpec(1, "spiral", "1", "1", "1"), "classification"),
])
def test_inconsistent_specs_are_refused_with_the_reason(spec, match):
    with pytest.raises(InputError, match=match):
        generate_plate(spec, size=96)


def test_paper_set_mirrors_table6_and_has_every_type():
    specs = paper_plate_set_specs()
    assert [s.kind for s in specs] == ["demonstration"] + ["transformation"] * 4 \
        + ["vanishing"] * 2 + ["hidden-digit"] * 2 + ["classification"]
    assert [s.normal for s in specs] == ["12", "8", "6", "5", "3", "7", "3", "-", "-", "26"]
    assert [s.deutan for s in specs][-1] == "2" and [s.protan for s in specs][-1] == "6"


def test_dots_are_packed_in_the_disc_without_overlap_and_reproducibly():
    layout = pack_dots(128, seed=3)
    again = pack_dots(128, seed=3)
    assert np.array_equal(layout.labels, again.labels)
    assert not np.array_equal(layout.labels, pack_dots(128, seed=4).labels)
    assert layout.count > 150
    assert set(np.unique(layout.labels)) == set(range(layout.count + 1))  # every dot drawn
    distance = np.hypot(*(layout.centres - 64).T) + layout.radii
    assert distance.max() <= DISC_RADIUS_FRACTION * 128 + 1
    assert len(set(map(tuple, layout.centres))) == layout.count


def test_plate_dots_vary_in_lightness_and_expand_to_a_cube(paper_plates):
    plate = paper_plates[2]
    low, high = plate.dot_lightness.min(), plate.dot_lightness.max()
    assert high - low > 0.25
    cube = plate.cube()
    assert cube.shape == (plate.size, plate.size, 401) and cube.dtype == np.float32
    y, x = map(int, plate.layout.centres[0][::-1])
    np.testing.assert_allclose(cube[y, x], plate.dot_reflectances[0], rtol=1e-6)
    assert np.all(cube[0, 0] == plate.paper_reflectance.astype(np.float32))


def test_save_load_round_trip_and_preview(tmp_path, paper_plates):
    plate = paper_plates[9]
    path = save_plate(plate, tmp_path / "plate.npz")
    again = load_plate(path)
    assert again.spec == plate.spec and again.seed == plate.seed
    assert np.array_equal(again.labels, plate.labels)
    np.testing.assert_allclose(again.dot_reflectances, plate.dot_reflectances, atol=1e-7)
    assert again.dot_colours == plate.dot_colours
    png = write_plate_preview(plate, tmp_path / "plate.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_plate_files_name_the_file_and_the_problem(tmp_path, paper_plates):
    with pytest.raises(SpectrumFileError, match="no such file"):
        load_plate(tmp_path / "missing.npz")
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    with pytest.raises(SpectrumFileError, match="junk.npz"):
        load_plate(junk)
    plate = paper_plates[0]
    path = save_plate(plate, tmp_path / "p.npz")
    with np.load(path) as data:
        arrays = dict(data)
    arrays["dot_reflectances"] = arrays["dot_reflectances"] * 3.0
    bad = tmp_path / "bad.npz"
    np.savez(bad, **arrays)
    with pytest.raises(SpectrumFileError, match=r"outside \[0, 1\]"):
        load_plate(bad)
    with pytest.raises(InputError, match=".npz"):
        save_plate(plate, tmp_path / "plate.png")


def test_truncated_or_corrupted_plate_file_names_the_file(tmp_path, paper_plates):
    path = save_plate(paper_plates[0], tmp_path / "good.npz")
    raw = path.read_bytes()
    for fraction in (0.1, 0.5, 0.99):
        cut = tmp_path / f"cut_{fraction}.npz"
        cut.write_bytes(raw[:int(len(raw) * fraction)])
        with pytest.raises(SpectrumFileError, match=f"cut_{fraction}.npz.*truncated or corrupted"):
            load_plate(cut)
    corrupted = bytearray(raw)
    middle = len(corrupted) // 2
    corrupted[middle:middle + 64] = bytes(64)
    bad = tmp_path / "corrupted.npz"
    bad.write_bytes(bytes(corrupted))
    with pytest.raises(SpectrumFileError, match="corrupted.npz"):
        load_plate(bad)


def test_plate_file_missing_an_array_names_it(tmp_path, paper_plates):
    path = save_plate(paper_plates[0], tmp_path / "p.npz")
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files if k != "dot_radii"}
    partial = tmp_path / "partial.npz"
    np.savez(partial, **arrays)
    with pytest.raises(SpectrumFileError, match=r"partial.npz.*dot_radii"):
        load_plate(partial)


def test_paper_coloured_plate_keeps_the_layout_and_uses_the_ten_paper_colours(paper_plates):
    plate = paper_coloured_plate(paper_plates[2])
    assert plate.layout is paper_plates[2].layout and plate.spec == paper_plates[2].spec
    assert set(plate.colour_names) == {f"P{i}" for i in range(1, 11)}
    assert np.all(plate.dot_lightness == 1.0)
    # darker designed dots of a family get the darker paper colour
    designed = paper_plates[2]
    greens = [i for i, c in enumerate(designed.dot_colours) if c.startswith("green")]
    order = sorted(greens, key=lambda i: designed.dot_lightness[i])
    assert plate.dot_colours[order[0]] == "P1" and plate.dot_colours[order[-1]] == "P3"
    with pytest.raises(InputError, match="red-"):
        paper_coloured_plate(paper_plates[9])  # the classification plate's reds have no family
