"""Prediction for patches shown as a window on a surround (``predict``'s optional columns).

``predict`` reads CSV ``r,g,b`` and, optionally, ``window`` (the patch's
fraction of the field, default 1) and ``sr,sg,sb`` (the surround's DAC values,
default 0), by header name (any order, any case) or, without a header, by
position: ``r,g,b[,window[,sr,sg,sb]]``. A display model predicts the patch
shown full field (the reference load); the APL curve scales that by
``gain(L) / gain(L_ref)`` (:meth:`AplCurve.relative_gain`). A profile whose
diagnosis tested ``apl-dependence`` and did not find it has no curve and
predicts every frame as full field (gain 1 at every load); a profile that was
never tested refuses windows and surrounds.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass

import numpy as np

from workbench.apl.curve import AplCurve
from workbench.apl.load import channel_transfer
from workbench.errors import InputError

__all__ = ["PredictRows", "read_predict_rows", "predict_XYZ_on_surround", "apl_curve_from_json"]

_POSITIONAL = ("r", "g", "b", "window", "sr", "sg", "sb")


@dataclass(frozen=True)
class PredictRows:
    """Patches to predict.

    Attributes
    ----------
    rgb : ndarray, shape (N, 3)
    window : ndarray, shape (N,)
    surround : ndarray, shape (N, 3)
    """

    rgb: np.ndarray
    window: np.ndarray
    surround: np.ndarray

    @property
    def full_field(self) -> bool:
        """Whether every patch is full field (nothing for an APL curve to do)."""
        return bool(np.all(self.window >= 1))


def _is_header(cells) -> bool:
    try:
        [float(c) for c in cells]
    except ValueError:
        return True
    return False


def read_predict_rows(text: str) -> PredictRows:
    """Parse ``predict``'s CSV input (see the module notes).

    Raises
    ------
    InputError
        Naming the line and what to write instead.
    """
    rows = [[c.strip() for c in row] for row in csv.reader(io.StringIO(text))]
    numbered = [(n, row) for n, row in enumerate(rows, start=1) if row and any(row)]
    if not numbered:
        raise InputError("no r,g,b rows on standard input; e.g. echo 255,128,0 | python -m workbench predict PROFILE")
    columns = {name: i for i, name in enumerate(_POSITIONAL)}
    if _is_header(numbered[0][1]):
        header = [c.lower() for c in numbered[0][1]]
        columns = {name: header.index(name) for name in _POSITIONAL if name in header}
        missing = [c for c in "rgb" if c not in columns]
        surround = [c for c in ("sr", "sg", "sb") if c in columns]
        if missing or len(surround) not in (0, 3):
            raise InputError(f"stdin line {numbered[0][0]}: header {numbered[0][1]} needs r,g,b and "
                             "optionally window and all of sr,sg,sb")
        numbered = numbered[1:]
    rgb, window, surround = [], [], []
    for number, row in numbered:
        try:
            values = {name: float(row[i]) for name, i in columns.items() if i < len(row) and row[i] != ""}
        except ValueError:
            raise InputError(f"stdin line {number}: {row!r} is not numbers; give r,g,b[,window[,sr,sg,sb]] "
                             "with DAC values 0..255 and window in (0, 1]") from None
        if any(c not in values for c in "rgb") or (any(c in values for c in ("sr", "sg", "sb"))
                                                   and not all(c in values for c in ("sr", "sg", "sb"))):
            raise InputError(f"stdin line {number}: need r,g,b (and all of sr,sg,sb if any), got {row!r}")
        dac = [values[c] for c in "rgb"]
        back = [values.get(c, 0.0) for c in ("sr", "sg", "sb")]
        fraction = values.get("window", 1.0)
        if any(not 0 <= v <= 255 for v in dac + back):
            raise InputError(f"stdin line {number}: DAC values {dac + back} outside 0..255")
        if not 0 < fraction <= 1:
            raise InputError(f"stdin line {number}: window {fraction:g} outside (0, 1]; it is the patch's "
                             "fraction of the field, 1 = full field")
        rgb.append(dac)
        window.append(fraction)
        surround.append(back)
    if not rgb:
        raise InputError("only a header on standard input; add one row per patch")
    return PredictRows(np.array(rgb), np.array(window), np.array(surround))


def predict_XYZ_on_surround(forward, rows: PredictRows, curve: AplCurve | None = None, *,
                            load_independent: bool = False) -> np.ndarray:
    """XYZ of each patch as shown: the display model's full-field prediction times the APL gain.

    Parameters
    ----------
    forward : callable
        The display model's ``RGB → XYZ`` for full-field patches.
    rows : PredictRows
    curve : AplCurve, optional
        The profile's APL curve; without one (and without
        ``load_independent``), only full-field patches can be predicted.
    load_independent : bool
        The display was tested for ``apl-dependence`` and it was not found
        (:attr:`workbench.profile.Profile.apl_tested_absent`): with no curve,
        every patch is predicted as shown full field (gain 1 at every load).

    Raises
    ------
    InputError
        For windows or surrounds without an APL curve on a display not tested for one.
    """
    XYZ = np.asarray(forward(rows.rgb), dtype=float)
    if curve is None:
        if not rows.full_field and not load_independent:
            raise InputError("the profile has no APL curve, so it predicts full-field patches only; drop the "
                             "window/sr,sg,sb columns or export a profile from a session measured with the "
                             "'apl' plan")
        return XYZ
    return XYZ * curve.relative_gain(rows.rgb, rows.window, rows.surround)[:, None]


def apl_curve_from_json(data: dict) -> AplCurve:
    """The :class:`AplCurve` of :meth:`AplCurve.to_json` (a profile's or a bundle's APL block)."""
    try:
        transfer = data["transfer"]
        method, gammas = str(transfer["method"]), tuple(float(g) for g in transfer["gammas"])
        peak = float(transfer["peak_cd_m2"])
        curve = (float(data["knee"]), float(data["sharpness"]), float(data["exponent"]))
        shares = tuple(float(s) for s in data["power_shares"])
    except (KeyError, TypeError, ValueError) as error:
        raise InputError(f"APL curve block is incomplete ({error}); it needs knee, sharpness, exponent, "
                         "power_shares and transfer {method, gammas, peak_cd_m2}") from None
    if len(gammas) != 3 or len(shares) != 3:
        raise InputError(f"APL curve block gives {len(gammas)} transfer gammas and {len(shares)} power "
                         "shares; give one of each per channel (3)")
    return AplCurve(*curve, channel_transfer(method, gammas=gammas, peak_cd_m2=peak), shares,
                    str(data.get("fitted_on", "")))
