"""The additivity tests carry a drift that the drift test did not name.

A warm-up too slow or too noisy for the drift test still moves every reading: primaries read
early (dim) and whites read later sum to less than the whites, and the white-against-R+G+B test
read that as a channel interaction. Where ``temporal-drift`` is not found, the whites' scatter
beyond noise is carried as a gain on each reading
(:func:`~workbench.diagnostics.detectors.unexplained_gain_variance`); a real interaction on a
steady display is still found.
"""

import numpy as np
import pytest

from tests.diagnostics.independent_generator import generate_session
from workbench.diagnostics.detectors import (
    build_context,
    detect_channel_interaction,
    unexplained_gain_variance,
)
from workbench.diagnostics.noise import estimate_noise
from workbench.session import Session

WHITE = (255, 255, 255)


def _session(seed, warm_up: float, white_gain: float = 1.0):
    """Black, then each channel's sweep every 5 DAC, a white after every 25 patches; the display's
    output rises linearly by ``warm_up`` over the session; the whites dimmed by ``white_gain``."""
    display = generate_session({}, seed=seed).display
    rows = [("white", WHITE), ("black", (0, 0, 0))]
    for c, kind in enumerate(("ramp-r", "ramp-g", "ramp-b")):
        for level in range(5, 256, 5):
            rgb = [0, 0, 0]
            rgb[c] = level
            rows.append((kind, tuple(rgb)))
            if len(rows) % 25 == 0:
                rows.append(("white", WHITE))
    rows.append(("white", WHITE))
    kind = np.array([k for k, _ in rows], dtype=object)
    rgb = np.array([r for _, r in rows], dtype=float)
    t = np.arange(len(rows), dtype=float) * 10.0
    gain = 1.0 - warm_up + warm_up * t / t[-1]
    rng = np.random.default_rng(seed)
    XYZ = display.light(rgb) * gain[:, None] * (1 + 0.001 * rng.standard_normal((len(rows), 1)))
    XYZ[kind == "white"] *= white_gain
    return Session(kind=kind, rgb=rgb, XYZ=XYZ, t_s=t, source=f"warm-up {warm_up} seed {seed}", metadata={})


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_drift_left_unnamed_is_not_read_as_an_interaction(seed):
    session = _session(seed, warm_up=0.02)
    context = build_context(session, drift_found=False, noise=estimate_noise(session))
    assert unexplained_gain_variance(context) > 0  # the whites scatter beyond their noise
    result = detect_channel_interaction(context)
    assert result.p_value > 0.01, result.evidence


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_real_interaction_on_a_steady_display_is_still_found(seed):
    session = _session(seed, warm_up=0.0, white_gain=0.97)
    context = build_context(session, drift_found=False, noise=estimate_noise(session))
    assert unexplained_gain_variance(context) == pytest.approx(0.0, abs=1e-6)
    assert detect_channel_interaction(context).p_value < 1e-6
