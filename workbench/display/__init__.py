"""Display models: a registry of forward/inverse colorimetric models and one dispatcher.

``DISPLAY_MODELS`` maps a stable id to a model class; :func:`fit_display_model`
fits one from a session, :func:`display_model_from_parameters` rebuilds one
from a profile. The diagnostics add their extensions to this registry.
"""

from __future__ import annotations

from workbench.display.base import DisplayModel, as_dac, as_XYZ, check_observer, quantize_dac
from workbench.display.extended import ExtendedDisplay
from workbench.display.gamma_matrix import GammaMatrixDisplay, fit_power_law
from workbench.display.residual_lut import ResidualLUTDisplay, fit_residual_lut
from workbench.display.srgb import SRGBDisplay, srgb_decode, srgb_encode
from workbench.errors import InputError

__all__ = [
    "DISPLAY_MODELS",
    "DisplayModel",
    "ExtendedDisplay",
    "GammaMatrixDisplay",
    "ResidualLUTDisplay",
    "SRGBDisplay",
    "as_dac",
    "as_XYZ",
    "check_observer",
    "display_model_from_parameters",
    "fit_display_model",
    "fit_power_law",
    "fit_residual_lut",
    "quantize_dac",
    "srgb_decode",
    "srgb_encode",
]

DISPLAY_MODELS: dict[str, type[DisplayModel]] = {
    GammaMatrixDisplay.model_id: GammaMatrixDisplay,
    SRGBDisplay.model_id: SRGBDisplay,
    ExtendedDisplay.model_id: ExtendedDisplay,
    ResidualLUTDisplay.model_id: ResidualLUTDisplay,
}


def _model_class(method: str) -> type[DisplayModel]:
    try:
        return DISPLAY_MODELS[method]
    except KeyError:
        raise InputError(f"unknown display model {method!r}; use one of {sorted(DISPLAY_MODELS)}"
                         ) from None


def fit_display_model(session, method: str = "gamma-matrix") -> DisplayModel:
    """Fit display model ``method`` (an id of :data:`DISPLAY_MODELS`) to ``session``."""
    cls = _model_class(method)
    fit = getattr(cls, "fit", None)
    if fit is None:
        raise InputError(f"display model {method!r} is fixed and cannot be fitted to data")
    return fit(session)


def display_model_from_parameters(method: str, parameters: dict) -> DisplayModel:
    """Rebuild display model ``method`` from its JSON parameters (as in a profile)."""
    return _model_class(method).from_parameters(parameters)
