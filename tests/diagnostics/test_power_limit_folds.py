"""An identified power limit is refitted on every cross-validation fold of a sparse sweep.

The adaptive plan's core sweeps each channel at ten levels below full drive; where its whites
interleave the sweeps (a white every eight patches), the folds, dealt out in row order, can hold
out three of one channel's ten levels. Identifying a power limit needs eight levels per channel
(:data:`~workbench.diagnostics.power_limit.MIN_SWEEP_LEVELS`), but a fold's refit of the one the
whole session identified must not fail for want of them: a candidate that cannot be fitted in a
fold scores ``inf`` and the identified cause loses the model choice to a flexible model.
"""

import numpy as np
import pytest

from tests.diagnostics.independent_generator import generate_session
from workbench.diagnostics.cross_validation import FOLDS, cross_validated_errors_of, fold_of_rows
from workbench.diagnostics.detectors import build_context
from workbench.diagnostics.model_choice import fit_candidate
from workbench.diagnostics.power_limit import MIN_SWEEP_LEVELS, fit_power_limit, tone_bend_explained
from workbench.session import Session

LEVELS = (32, 64, 96, 128, 160, 192, 208, 224, 236, 246)  # the adaptive core's
GREYS = (8, 16, 24, 32, 40, 48) + tuple(range(64, 241, 16))


def _interleaved_rows():
    rows = [("white", (255, 255, 255)), ("black", (0, 0, 0))]
    for c, kind in enumerate(("ramp-r", "ramp-g", "ramp-b")):
        for level in (255, *LEVELS):
            rgb = [0, 0, 0]
            rgb[c] = level
            rows.append((kind, tuple(rgb)))
    rows += [("grey", (v, v, v)) for v in GREYS]
    out, since = [], 0
    for kind, rgb in rows:  # a white after every eight patches
        if since == 8 and kind != "white":
            out.append(("white", (255, 255, 255)))
            since = 0
        out.append((kind, rgb))
        since = 0 if kind == "white" else since + 1
    return out + [("white", (255, 255, 255))]


def _session(seed):
    display = generate_session({"channel-interaction": "knee"}, seed=seed).display
    rows = _interleaved_rows()
    rgb = np.array([r for _, r in rows], dtype=float)
    rng = np.random.default_rng(seed)
    XYZ = display.light(rgb) * (1 + 0.0005 * rng.standard_normal((len(rows), 1)))
    return Session(kind=np.array([k for k, _ in rows], dtype=object), rgb=rgb, XYZ=XYZ,
                   t_s=np.arange(len(rows), dtype=float) * 5.0, source=f"interleaved knee {seed}",
                   metadata={})


@pytest.mark.parametrize("seed", [0, 1])
def test_an_identified_power_limit_is_refitted_on_every_fold(seed):
    context = build_context(_session(seed), drift_found=False)
    explained, why, _ = tone_bend_explained(context)
    assert explained, why  # the whole session identifies the power limit
    fold = fold_of_rows(context, FOLDS)
    rgb = context.raw.rgb
    held_most = 0
    for c in range(3):
        own = ((rgb > 0).sum(axis=1) == 1) & (rgb[:, c] > 0) & (rgb[:, c] < 255)
        held_most = max(held_most, max(int(np.sum(fold[own] == k)) for k in range(FOLDS)))
    assert 10 - held_most < MIN_SWEEP_LEVELS  # a fold's training rows are too few to identify it
    errors = cross_validated_errors_of(
        context, lambda fold_context, _baseline: fit_candidate("power-limit", fold_context), drift=False)
    assert errors is not None and np.all(np.isfinite(errors[0]))
    # identification itself still needs MIN_SWEEP_LEVELS
    sparse = context.raw.subset(~np.isin(context.raw.rgb.max(axis=1), LEVELS[:4]) |
                                ((context.raw.rgb > 0).sum(axis=1) != 1))
    assert fit_power_limit(build_context(sparse, drift_found=False)) is None
