"""The noise model's absolute floor ``b``, read from the sweeps' dark points.

A dark point's leave-one-out residual has variance ``a² Y² + b²``: where the relative part
dominates the dark points (sweeps whose darkest levels are still a few per cent of white),
taking it out of each square before a robust mean left differences with a negative median, and
the floor fell to its clamp, a tenth of the instrument default. The independent generator's
floor is drawn per session (``_noise_floor``), so the estimate can be checked against it.
"""

import numpy as np
import pytest

from tests.diagnostics.independent_generator import _noise_floor, generate_session
from tests.diagnostics.peer_bench import scenarios
from workbench.diagnostics.detectors import build_context
from workbench.diagnostics.noise import floor_from_dark


def test_the_floor_is_recovered_where_the_relative_part_dominates():
    rng = np.random.default_rng(7)
    Y = rng.uniform(0.2, 3.5, 400)  # dark points: below 2 % of a white of 176
    a, b = 0.004, 0.0035
    relative = a ** 2 * Y ** 2  # up to 14× the floor's variance
    squares = (relative + b ** 2) * rng.standard_t(6, Y.size) ** 2 / 1.5
    estimate = np.sqrt(floor_from_dark(squares, relative, (2e-5 * 176) ** 2))
    assert 0.6 * b < estimate < 1.5 * b, estimate
    # taking the relative part out before the robust mean gives a negative variance
    differences = squares - relative
    capped = np.minimum(differences, 16 * np.median(differences) / 0.455)
    assert np.mean(capped) < 0


def test_a_floor_alone_is_its_robust_variance():
    rng = np.random.default_rng(3)
    squares = (0.002 ** 2) * rng.standard_normal(300) ** 2
    estimate = np.sqrt(floor_from_dark(squares, np.zeros(300), 1e-6))
    assert 0.002 * 0.85 < estimate < 0.002 * 1.15, estimate


@pytest.mark.parametrize("seed", [45001, 45006])
def test_the_generators_floor_is_read_within_a_factor_of_three(seed):
    """Knees on the paper plan whose floor had read 0.0003 (the clamp) for 0.0035 and 0.0055."""
    generated = generate_session(scenarios(True)["channel-interaction/knee"], seed=seed,
                                 plan="paper")
    floor = build_context(generated.session.without("validation")).noise.floor
    truth = _noise_floor(generated)
    assert truth / 3 < floor < 3 * truth, (floor, truth)
