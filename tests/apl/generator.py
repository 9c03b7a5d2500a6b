"""An independent generator of sessions with APL limiting, for the hidden-effect tests.

It shares no code and no functional form with ``instruments/headset.py`` (a hard
knee and a power law of a current-weighted load) or ``workbench.apl.curve`` (a
soft power cap of a power-weighted load): here the display is an sRGB-like
additive panel (sRGB primaries, per-channel gamma 2.2), the load is the frame's
relative *luminance* (the Rec. 709 weighting of linear drive), and the
limiter is a saturating exponential, ``g(L) = 1 − m (1 − exp(−L/λ)) / (1 − exp(−1/λ))``
(so a full-field white loses exactly ``m``). Measurements get a relative
Gaussian noise.
"""

import numpy as np

from workbench.session import Session

SRGB_TO_XYZ = np.array([[0.4124, 0.3576, 0.1805],
                        [0.2126, 0.7152, 0.0722],
                        [0.0193, 0.1192, 0.9505]])
WHITE_CD_M2 = 150.0
WINDOWS = (0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0)
SURROUNDS = (0, 64, 128, 192, 255)


def limiter_gain(load, loss, scale=0.3):
    """The generator's own limiter: a saturating exponential of the luminance load."""
    load = np.asarray(load, dtype=float)
    return 1.0 - loss * (1.0 - np.exp(-load / scale)) / (1.0 - np.exp(-1.0 / scale))


def frames():
    """(kind, rgb, window, surround) of an APL plan: white and grey windows, a small white on surrounds,
    colours at three windows, full-field whites between."""
    rows = []
    for window in WINDOWS:
        rows.append(("white" if window == 1 else "grey", (255, 255, 255), window, (0, 0, 0)))
        rows.append(("grey", (128, 128, 128), window, (0, 0, 0)))
    for level in SURROUNDS:
        rows.append(("grey", (255, 255, 255), 0.05, (level,) * 3))
        rows.append(("white", (255, 255, 255), 1.0, (0, 0, 0)))
    for colour in ((255, 0, 0), (0, 255, 0), (40, 90, 230), (230, 200, 30)):
        for window in (0.05, 0.4, 1.0):
            rows.append(("mixture", colour, window, (0, 0, 0)))
    return rows


def generate_session(loss, seed, relative_noise=0.002):
    """A session of :func:`frames` measured on the generator's display with limiter ``loss``."""
    rng = np.random.default_rng(seed)
    kinds, rgb, window, surround = zip(*frames())
    rgb = np.array(rgb, dtype=float)
    window = np.array(window)
    surround = np.array(surround, dtype=float)
    shares = SRGB_TO_XYZ[1]  # luminance weighting of the load
    linear = (rgb / 255.0) ** 2.2
    load = (window[:, None] * linear + (1 - window[:, None]) * (surround / 255.0) ** 2.2) @ shares
    XYZ = WHITE_CD_M2 * (linear @ SRGB_TO_XYZ.T) * limiter_gain(load, loss)[:, None]
    XYZ *= 1.0 + relative_noise * rng.standard_normal((len(XYZ), 1))
    return Session(kind=np.array(kinds, dtype=object), rgb=rgb, XYZ=XYZ, window=window, surround=surround,
                   source=f"generated APL session (loss {loss:.3f}, seed {seed})")


RAMP_LEVELS = (16, 32, 48, 64, 96, 128, 160, 192, 224, 255)
"""Levels of the full-field single-channel ramps and greys of :func:`generate_paper_apl_session`."""


def truth_XYZ(rgb, window, surround, loss):
    """The generator's noiseless display: XYZ of ``rgb`` as ``window`` on ``surround``."""
    rgb = np.asarray(rgb, dtype=float).reshape(-1, 3)
    window = np.asarray(window, dtype=float).reshape(-1)
    surround = np.asarray(surround, dtype=float).reshape(-1, 3)
    linear = (rgb / 255.0) ** 2.2
    load = (window[:, None] * linear + (1 - window[:, None]) * (surround / 255.0) ** 2.2) @ SRGB_TO_XYZ[1]
    return WHITE_CD_M2 * (linear @ SRGB_TO_XYZ.T) * limiter_gain(load, loss)[:, None]


def generate_paper_apl_session(loss, seed, relative_noise=0.002, validation=40):
    """A full-field calibration (black, white references, ramps, greys, validation colours) and the
    APL frames of :func:`frames`, measured on the generator's display with limiter ``loss``.

    The full-field patches are at their own reference load, so a model fitted on them is exact
    there; the APL frames show the same patches at other loads.
    """
    rng = np.random.default_rng([seed, 31])
    rows = [("black", (0, 0, 0), 1.0, (0, 0, 0))] * 3
    for c, kind in enumerate(("ramp-r", "ramp-g", "ramp-b")):
        for level in RAMP_LEVELS:
            dac = [0, 0, 0]
            dac[c] = level
            rows.append((kind, tuple(dac), 1.0, (0, 0, 0)))
        rows.append(("white", (255, 255, 255), 1.0, (0, 0, 0)))
    rows += [("grey", (level,) * 3, 1.0, (0, 0, 0)) for level in RAMP_LEVELS[:-1]]
    rows += [("validation", tuple(v), 1.0, (0, 0, 0))
             for v in rng.integers(0, 256, size=(validation, 3))]
    rows += frames()
    kinds, rgb, window, surround = zip(*rows)
    rgb = np.array(rgb, dtype=float)
    window = np.array(window)
    surround = np.array(surround, dtype=float)
    XYZ = truth_XYZ(rgb, window, surround, loss)
    XYZ = XYZ * (1.0 + relative_noise * rng.standard_normal((len(XYZ), 1))) \
        + 1e-4 * rng.standard_normal(XYZ.shape)
    return Session(kind=np.array(kinds, dtype=object), rgb=rgb, XYZ=XYZ, window=window,
                   surround=surround, t_s=4.0 * np.arange(1, len(rgb) + 1),
                   source=f"generated paper+APL session (loss {loss:.3f}, seed {seed})")
