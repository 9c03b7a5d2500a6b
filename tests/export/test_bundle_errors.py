"""A damaged bundle gives the runtime one clear error (exit status 2), never a traceback or a wrong texture."""

import contextlib
import io
import json
import re
import shutil

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.export.test_conformance import consumer_module


@pytest.fixture
def damaged(tmp_path, simulated_bundle):
    source, _ = simulated_bundle
    copy = tmp_path / "bundle"
    shutil.copytree(source, copy)
    return copy


def _edit_json(path, change):
    document = json.loads(path.read_text())
    change(document)
    path.write_text(json.dumps(document))


def _truncate(path):
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


DAMAGES = {
    "truncated coefficients": (lambda b: _truncate(b / "level2/paint/coefficients.bin"),
                               ["texture", "paint", "--light", "cie-a"], "truncated"),
    "oversized correction table": (
        lambda b: (b / "display_drive_correction.bin").write_bytes(
            (b / "display_drive_correction.bin").read_bytes() * 2),
        ["texture", "paint", "--light", "cie-a"], "bytes where its header promises"),
    "truncated lights.json": (lambda b: _truncate(b / "lights.json"), ["light", "cie-a"],
                              "not valid JSON"),
    "NaN in a level-2 matrix": (
        lambda b: (b / "level2/paint/lights.json").write_text(
            (b / "level2/paint/lights.json").read_text().replace('"offset": [', '"offset": [NaN, ', 1)),
        ["texture", "paint", "--light", "cie-d65"], "NaN is not a JSON number"),
    "rgb8 as strings": (
        lambda b: _edit_json(b / "lights.json",
                             lambda d: d["lights"][0].update(rgb8=["240", "234", "223"])),
        ["light", "cie-d65"], "'rgb8' must be a list of 3 numbers"),
    "texel table out of range": (
        lambda b: _edit_json(b / "level2/paint/lights.json",
                             lambda d: d["lights"][0]["texel_table"].__setitem__(5, 999)),
        ["texture", "paint", "--light", "cie-d65"], "'texel_table' holds a value out of range"),
    "newer bundle version": (
        lambda b: _edit_json(b / "bundle.json", lambda d: d.update(format_version=2)),
        ["light", "cie-d65"], r"bundle format_version 2 is newer than this consumer supports \(1\)"),
    "version as a string": (
        lambda b: _edit_json(b / "bundle.json", lambda d: d.update(format_version="1")),
        ["light", "cie-d65"], "format_version must be an integer"),
    "not a bundle": (lambda b: _edit_json(b / "bundle.json", lambda d: d.update(format="zip")),
                     ["light", "cie-d65"], "not a VR colour workbench bundle"),
    "missing inverse": (lambda b: (b / "display_inverse.json").unlink(),
                        ["texture", "paint", "--light", "cie-a"], "missing from the bundle"),
    "thresholds of the wrong length": (
        lambda b: _edit_json(b / "display_inverse.json", lambda d: d["thresholds"].pop()),
        ["texture", "paint", "--light", "cie-a"], "'thresholds' must be a list of 765 numbers"),
    "layers that do not fit the channels": (
        lambda b: _edit_json(b / "level2/paint/coefficients.json", lambda d: d.update(layers=1)),
        ["texture", "paint", "--light", "cie-a"], "channels need"),
    "cubes not a list": (lambda b: _edit_json(b / "bundle.json", lambda d: d.update(cubes=3)),
                         ["texture", "paint", "--light", "cie-a"], "'cubes' must be a list"),
    "cube with a word for a number": (
        lambda b: (b / "display_inverse.cube").write_text(
            (b / "display_inverse.cube").read_text().replace("LUT_3D_SIZE 33", "LUT_3D_SIZE x")),
        ["cube", "1", "1", "1"], "not a complete .cube"),
    "cube with a row of words": (
        lambda b: (b / "display_inverse.cube").write_text(
            (b / "display_inverse.cube").read_text() + "a b c\n"),
        ["cube", "1", "1", "1"], "not a complete .cube"),
    "cube with a NaN": (
        lambda b: (b / "display_inverse.cube").write_text(
            (b / "display_inverse.cube").read_text().replace("LUT_3D_SIZE 33\n",
                                                             "LUT_3D_SIZE 33\nnan 0 0\n")
            .rsplit("\n", 2)[0] + "\n"),
        ["cube", "1", "1", "1"], "NaN or infinity"),
    "unknown light": (lambda b: None, ["light", "cie-f2"], "no light 'cie-f2'"),
    "unknown texture": (lambda b: None, ["texture", "../etc", "--light", "cie-a"],
                        "no level-2 texture '../etc'"),
}


@pytest.mark.parametrize("name", sorted(DAMAGES))
def test_damaged_bundles_give_one_clear_error(damaged, tmp_path, capsys, name):
    damage, args, message = DAMAGES[name]
    damage(damaged)
    module = consumer_module(damaged)
    out = tmp_path / "t.png"
    argv = [str(damaged), *args] + (["--out", str(out)] if args[0] == "texture" else [])
    assert module.main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1
    assert re.search(message, err), err
    assert not out.exists()


def test_an_unwritable_out_is_one_error(damaged, tmp_path, capsys):
    module = consumer_module(damaged)
    out = tmp_path / "no-such-folder" / "t.png"
    assert module.main([str(damaged), "texture", "paint", "--light", "cie-a",
                        "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "no-such-folder" in err


def test_the_undamaged_copy_works(damaged, tmp_path, capsys):
    module = consumer_module(damaged)
    assert module.main([str(damaged), "texture", "paint", "--light", "cie-a",
                        "--out", str(tmp_path / "t.png")]) == 0
    assert module.main([str(damaged), "cube", "1", "1", "1"]) == 0
    dac = json.loads(capsys.readouterr().out.splitlines()[-1])["dac"]
    assert np.all(np.array(dac) > 200)


# Hypothesis: whatever JSON a bundle file holds, the consumer answers or says "error: ..." (exit 2).
_values = st.recursive(
    st.none() | st.booleans() | st.integers(-300, 300) | st.floats(allow_nan=False, width=32)
    | st.text(max_size=6),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=5),
                                                                      children, max_size=3),
    max_leaves=10)

_FILES = ("bundle.json", "lights.json", "display_inverse.json", "level2/paint/coefficients.json",
          "level2/paint/lights.json")
_COMMANDS = (["light", "cie-a"], ["texture", "paint", "--light", "cie-a"])


def _places(value, prefix=()):
    yield prefix
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _places(item, prefix + (key,))
    elif isinstance(value, list):
        for index, item in enumerate(value[:3]):
            yield from _places(item, prefix + (index,))


@pytest.fixture(scope="module")
def fuzz_bundle(tmp_path_factory, simulated_bundle):
    source, _ = simulated_bundle
    copy = tmp_path_factory.mktemp("fuzz") / "bundle"
    shutil.copytree(source, copy)
    return copy


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_property_any_bundle_json_gives_an_answer_or_one_error(fuzz_bundle, data):
    name = data.draw(st.sampled_from(_FILES))
    path = fuzz_bundle / name
    original = path.read_text()
    document = json.loads(original)
    places = [p for p in _places(document)]
    place = data.draw(st.sampled_from(places))
    value = data.draw(_values)
    if place:
        target = document
        for key in place[:-1]:
            target = target[key]
        target[place[-1]] = value
    else:
        document = value
    command = data.draw(st.sampled_from(_COMMANDS))   # every draw before the file changes
    module = consumer_module(fuzz_bundle)
    path.write_text(json.dumps(document))
    out = fuzz_bundle.parent / "fuzz.png"
    argv = [str(fuzz_bundle), *command] + (["--out", str(out)] if command[0] == "texture" else [])
    stderr = io.StringIO()
    try:
        with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
            status = module.main(argv)
    finally:
        path.write_text(original)
    assert status in (0, 2)
    if status == 2:
        assert stderr.getvalue().startswith("error: ")
