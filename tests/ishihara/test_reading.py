import numpy as np

from workbench.ishihara.reading import LEGIBILITY_THRESHOLD_JND, read_dots, split_in_two
from workbench.ishihara.plates import PlateSpec, generate_plate


def test_split_finds_the_dominant_difference_not_the_weaker_one(rng):
    # two strong groups along x, a weaker split along y inside each
    x = np.concatenate([rng.normal(0, 0.3, 200), rng.normal(20, 0.3, 100)])
    y = np.where(rng.random(300) < 0.5, 0.0, 8.0)
    groups, gap = split_in_two(np.column_stack([x, y]), np.ones(300))
    assert np.array_equal(groups, x > 10) or np.array_equal(groups, x < 10)
    assert 19 < gap < 21


def test_uniform_colours_have_no_split():
    groups, gap = split_in_two(np.ones((50, 2)), np.ones(50))
    assert gap == 0.0 and not groups.any()


def test_reading_needs_both_colour_contrast_and_a_digit_shape():
    plate = generate_plate(PlateSpec(1, "vanishing", "7", "-", "-"), size=128, seed=11)
    layout = plate.layout
    figure = np.array([c == "ochre" for c in plate.dot_colours])
    strong = np.where(figure, 3 * LEGIBILITY_THRESHOLD_JND, 0.0)[:, None]
    assert read_dots(layout, strong).answer == "7"
    weak = np.where(figure, 0.5 * LEGIBILITY_THRESHOLD_JND, 0.0)[:, None]
    reading = read_dots(layout, weak)
    assert reading.answer == "-" and reading.reason == "no colour contrast"
    assert reading.best_guess == "7"
    shuffled = np.random.default_rng(0).permutation(strong[:, 0])[:, None]
    assert read_dots(layout, shuffled).reason == "no digit shape"
