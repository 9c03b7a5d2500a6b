"""Measurement plans: the paper's sequence, the quick one, the authors' own, and plan files."""

import pytest

from workbench.cli import main
from workbench.errors import InputError, SpectrumFileError
from workbench.measurement.plans import (
    AUTHORS_2024_LEVELS,
    DRIFT_REFERENCE_INTERVAL,
    MEASUREMENT_PLANS,
    Patch,
    measurement_plan,
    read_plan_file,
)
from workbench.session import read_session_csv


def _gaps_between_whites(plan):
    gaps, since = [], 0
    for patch in plan.patches:
        if patch.kind == "white":
            gaps.append(since)
            since = 0
        else:
            since += 1
    return gaps, since


def test_paper_plan_counts():
    plan = measurement_plan("paper", seed=1)
    counts = plan.counts()
    assert counts["black"] == 1
    assert counts["ramp-r"] == counts["ramp-g"] == counts["ramp-b"] == 51
    assert counts["validation"] == 50
    # 1 white + a drift reference after every 25 patches (8) + a closing one
    assert counts["white"] == 1 + (153 + 50) // DRIFT_REFERENCE_INTERVAL + 1
    assert len(plan) == 1 + 1 + 153 + 50 + 9 == 214


def test_paper_plan_order_and_levels():
    plan = measurement_plan("paper", seed=1)
    assert plan.patches[0] == Patch("black", (0, 0, 0))
    assert plan.patches[1] == Patch("white", (255, 255, 255))
    assert plan.patches[-1] == Patch("white", (255, 255, 255))
    for channel, kind in enumerate(("ramp-r", "ramp-g", "ramp-b")):
        ramp = [p.rgb for p in plan.patches if p.kind == kind]
        assert [rgb[channel] for rgb in ramp] == list(range(5, 256, 5))
        assert all(v == 0 for rgb in ramp for i, v in enumerate(rgb) if i != channel)
    kinds = [p.kind for p in plan.patches if p.kind != "white"]
    assert kinds.index("validation") > max(i for i, k in enumerate(kinds) if k.startswith("ramp"))


@pytest.mark.parametrize("name", sorted(MEASUREMENT_PLANS))
def test_white_is_remeasured_at_least_every_25_patches(name):
    gaps, tail = _gaps_between_whites(measurement_plan(name, seed=3))
    assert max(gaps) <= DRIFT_REFERENCE_INTERVAL and tail == 0


def test_validation_colours_are_seeded():
    a, b, c = (measurement_plan("paper", seed=s) for s in (7, 7, 8))
    assert a == b and a.seed == 7
    assert [p for p in a.patches if p.kind == "validation"] != [p for p in c.patches if p.kind == "validation"]
    values = [v for p in a.patches if p.kind == "validation" for v in p.rgb]
    assert all(isinstance(v, int) and 0 <= v <= 255 for v in values)


def test_quick_plan_has_fewer_levels():
    plan = measurement_plan("quick", seed=1)
    counts = plan.counts()
    assert counts["ramp-r"] == 5 and counts["validation"] == 10
    assert len(plan) == 28 < len(measurement_plan("paper", seed=1))


def test_the_authors_2024_plan_counts_and_kinds():
    plan = measurement_plan("authors-2024", seed=1)
    assert plan.name == "authors-2024" and plan.seed == 1
    assert plan.counts() == {"black": 1, "white": 12, "ramp-r": 51, "ramp-g": 51, "ramp-b": 51,
                             "grey": 50, "validation": 50}
    assert len(plan) == 266
    assert plan.patches[:2] == (Patch("black", (0, 0, 0)), Patch("white", (255, 255, 255)))
    assert plan.patches[-1] == Patch("white", (255, 255, 255))
    assert not any(p.is_apl for p in plan.patches)
    # the order: black, white, red, green, blue, validation, greys, the grey ramp's white last
    kinds = [p.kind for p in plan.patches if p.kind != "white"]
    assert kinds == ["black"] + ["ramp-r"] * 51 + ["ramp-g"] * 51 + ["ramp-b"] * 51 \
        + ["validation"] * 50 + ["grey"] * 50
    assert plan.patches[-2] == Patch("grey", (250, 250, 250))


def test_the_authors_2024_plan_levels():
    plan = measurement_plan("authors-2024", seed=1)
    assert AUTHORS_2024_LEVELS == tuple(range(5, 256, 5))
    for channel, kind in enumerate(("ramp-r", "ramp-g", "ramp-b")):
        ramp = [p.rgb for p in plan.patches if p.kind == kind]
        assert [rgb[channel] for rgb in ramp] == list(range(5, 256, 5))
        assert all(v == 0 for rgb in ramp for i, v in enumerate(rgb) if i != channel)
    greys = [p.rgb for p in plan.patches if p.kind == "grey"]
    assert greys == [(level,) * 3 for level in range(5, 251, 5)]
    # the grey ramp's 255 level is a white, right after its last grey
    last_grey = max(i for i, p in enumerate(plan.patches) if p.kind == "grey")
    assert plan.patches[last_grey + 1] == Patch("white", (255, 255, 255))


@pytest.mark.parametrize("seed", [0, 7, 123])
def test_the_authors_2024_validation_colours_are_the_paper_plans(seed):
    def validation(name):
        return [p for p in measurement_plan(name, seed=seed).patches if p.kind == "validation"]

    assert len(validation("authors-2024")) == 50
    assert validation("authors-2024") == validation("paper")


def test_the_authors_2024_plan_is_offered_by_measure(tmp_path, capsys):
    plan = measurement_plan("authors-2024", seed=4)
    assert main(["measure", "--simulate", "--plan", "authors-2024", "--seed", "4", "--time-scale", "0",
                 "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out.startswith(
        f"measure: finished: {len(plan)} of {len(plan)} patches measured, 0 failed")
    session = read_session_csv(tmp_path / "session.csv")
    assert list(session.kind) == [p.kind for p in plan.patches]
    assert session.rgb.tolist() == [list(p.rgb) for p in plan.patches]
    grey_Y = session.select("grey").XYZ[:, 1]
    assert (grey_Y[1:] > grey_Y[:-1]).all()  # the ramp rises
    assert grey_Y[-1] < session.select("white").XYZ[:, 1].min()


def test_an_unknown_plan_lists_the_valid_ones():
    with pytest.raises(InputError, match="unknown measurement plan 'full'; use one of paper, quick"):
        measurement_plan("full", seed=1)


def test_read_plan_file(tmp_path):
    path = tmp_path / "plan.csv"
    path.write_text("R,G,B,Kind\n0,0,0,black\n255,255,255,WHITE\n\n10,20,30,mixture\n")
    plan = read_plan_file(path)
    assert plan.patches == (Patch("black", (0, 0, 0)), Patch("white", (255, 255, 255)),
                            Patch("mixture", (10, 20, 30)))
    assert plan.name == str(path) and plan.seed is None


@pytest.mark.parametrize("text, line, message", [
    ("kind,r,g\nblack,0,0\n", 1, "lacks column"),
    ("kind,r,g,b\nblack,0,0,0\nsparkle,1,2,3\n", 3, "unknown kind 'sparkle'.*use one of black"),
    ("kind,r,g,b\nramp-r,256,0,0\n", 2, "column 'r' holds '256'.*integer DAC value 0..255"),
    ("kind,r,g,b\nramp-r,12.5,0,0\n", 2, "column 'r' holds '12.5'"),
    ("kind,r,g,b\nramp-r,12\n", 2, "the row has 2 fields"),
    ("", 1, "empty"),
])
def test_plan_file_errors_name_file_line_and_fix(tmp_path, text, line, message):
    path = tmp_path / "plan.csv"
    path.write_text(text)
    with pytest.raises(SpectrumFileError, match=message) as error:
        read_plan_file(path)
    assert error.value.line == line and error.value.path == str(path) and error.value.fix


def test_a_missing_plan_file_says_so(tmp_path):
    with pytest.raises(SpectrumFileError, match="no such plan file.*--plan-file"):
        read_plan_file(tmp_path / "nope.csv")
