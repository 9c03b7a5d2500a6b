"""Display profiles (``*.vrprofile.json``): what the VR runtime loads (design §4).

A profile holds the headset's display model (type, parameters, white and black
XYZ), its validation figures and diagnosis, the engine assumptions
(frame-buffer encoding, ``k``, observer), the level-1 lights, and optionally
level-2 data and a 3D-LUT sidecar. :func:`load_profile` validates the file
against ``profiles/vrprofile.schema.json`` before using anything in it and
never executes anything from it; :func:`save_profile` writes atomically.
"""

from __future__ import annotations

import datetime as _dt
import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import jsonschema

from profiles import SCHEMA_PATH
from workbench import __version__
from workbench.colorimetry import DEFAULT_K, DEFAULT_OBSERVER
from workbench.colour_management import light_colour
from workbench.display import (
    DisplayModel,
    GammaMatrixDisplay,
    display_model_from_parameters,
)
from workbench.errors import WorkbenchError
from workbench.fileio import atomic_writer

__all__ = [
    "PROFILE_FORMAT",
    "PROFILE_FORMAT_VERSION",
    "ProfileError",
    "Profile",
    "profile_schema",
    "validate_profile_document",
    "load_profile",
    "save_profile",
    "light_entries",
    "paper_vive_profile",
]

PROFILE_FORMAT = "vr-colour-workbench-profile"
PROFILE_FORMAT_VERSION = 1


class ProfileError(WorkbenchError, ValueError):
    """A profile file is unreadable or does not follow the schema."""


def profile_schema() -> dict:
    """The profile JSON Schema (draft 2020-12)."""
    return json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))


def validate_profile_document(document: dict, source: str = "profile") -> None:
    """Raise :class:`ProfileError` naming the first schema violation and where it is."""
    validator = jsonschema.Draft202012Validator(profile_schema())
    errors = sorted(validator.iter_errors(document), key=lambda e: list(e.absolute_path))
    if errors:
        error = errors[0]
        where = "/".join(str(p) for p in error.absolute_path) or "(top level)"
        raise ProfileError(f"{source}: {where}: {error.message}. Fix the file or export it again "
                           f"with 'python -m workbench diagnose SESSION --export PROFILE'")


@dataclass(frozen=True, eq=False)
class Profile:
    """An in-memory profile; :meth:`to_document` gives the JSON document."""

    device: dict
    display_model_type: str
    display_parameters: dict
    white_XYZ: tuple[float, float, float]
    black_XYZ: tuple[float, float, float]
    xyz_scale: str = "absolute-cd/m2"
    instrument: dict | None = None
    validation: dict | None = None
    diagnosis: dict | None = None
    engine: dict = field(default_factory=lambda: {
        "framebuffer_encoding": "sRGB", "texture_encoding": "sRGB", "bits": 8,
        "k": DEFAULT_K, "observer": DEFAULT_OBSERVER,
        "light_model": "framebuffer_lin = albedo_lin * light_lin (Lambertian, one light)"})
    lights: tuple[dict, ...] = ()
    level2: dict | None = None
    lut3d: dict | None = None
    created: str = ""
    software: str = f"vr-colour-workbench {__version__}"

    @classmethod
    def from_display_model(cls, model: DisplayModel, device: dict, **kwargs) -> "Profile":
        return cls(device=device, display_model_type=model.model_id,
                   display_parameters=model.parameters(),
                   white_XYZ=tuple(float(v) for v in model.white_XYZ),
                   black_XYZ=tuple(float(v) for v in model.black_XYZ), **kwargs)

    def display_model(self) -> DisplayModel:
        """The display model the profile describes."""
        return display_model_from_parameters(self.display_model_type, self.display_parameters)

    @property
    def k(self) -> float:
        return float(self.engine["k"])

    @property
    def observer(self) -> str:
        return str(self.engine["observer"])

    def with_lights(self, illuminant_ids) -> "Profile":
        """A copy with level-1 light entries for these library ids."""
        return replace(self, lights=tuple(light_entries(illuminant_ids, self.display_model(),
                                                        k=self.k, observer=self.observer)))

    def to_document(self) -> dict:
        document = {
            "format": PROFILE_FORMAT,
            "format_version": PROFILE_FORMAT_VERSION,
            "created": self.created or _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "software": self.software,
            "device": dict(self.device),
            "instrument": self.instrument,
            "display_model": {
                "type": self.display_model_type,
                "parameters": self.display_parameters,
                "white_XYZ": list(self.white_XYZ),
                "black_XYZ": list(self.black_XYZ),
                "xyz_scale": self.xyz_scale,
            },
            "validation": self.validation,
            "diagnosis": self.diagnosis,
            "engine": dict(self.engine),
            "lights": [dict(light) for light in self.lights],
        }
        if self.level2 is not None:
            document["level2"] = self.level2
        if self.lut3d is not None:
            document["lut3d"] = self.lut3d
        return document

    @classmethod
    def from_document(cls, document: dict, source: str = "profile") -> "Profile":
        validate_profile_document(document, source)
        model = document["display_model"]
        return cls(
            device=document["device"], display_model_type=model["type"],
            display_parameters=model["parameters"], white_XYZ=tuple(model["white_XYZ"]),
            black_XYZ=tuple(model["black_XYZ"]), xyz_scale=model["xyz_scale"],
            instrument=document.get("instrument"), validation=document.get("validation"),
            diagnosis=document.get("diagnosis"), engine=document["engine"],
            lights=tuple(document["lights"]), level2=document.get("level2"),
            lut3d=document.get("lut3d"), created=document.get("created", ""),
            software=document["software"])


def light_entries(illuminant_ids, display: DisplayModel, *, k: float = DEFAULT_K,
                  observer: str = DEFAULT_OBSERVER) -> list[dict]:
    """Level-1 light records (id, name, XYZ, rgb8, Rf, CCT) for a display."""
    from workbench.illuminants import get_illuminant
    from workbench.illuminants.metrics import CCT_Duv, fidelity_Rf_Rg

    entries = []
    for illuminant_id in illuminant_ids:
        illuminant = get_illuminant(illuminant_id)
        light = light_colour(illuminant.sd, display, k=k, observer=observer)
        entries.append({
            "id": illuminant.id, "name": illuminant.name,
            "XYZ": [round(float(v), 6) for v in light.XYZ],
            "rgb8": [int(v) for v in light.rgb8], "in_gamut": light.in_gamut,
            "Rf": round(fidelity_Rf_Rg(illuminant)[0], 3),
            "CCT": round(CCT_Duv(illuminant)[0], 2),
        })
    return entries


def load_profile(path) -> Profile:
    """Read and validate a profile; errors name the file and the fix."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ProfileError(f"{path}: no such profile. Export one with 'python -m workbench "
                           "diagnose SESSION --export PROFILE' or use profiles/"
                           "htc-vive-paper.vrprofile.json") from None
    try:
        document = json.loads(text)
    except json.JSONDecodeError as error:
        raise ProfileError(f"{path}, line {error.lineno}: not valid JSON ({error.msg}). "
                           "Export the profile again") from None
    if not isinstance(document, dict):
        raise ProfileError(f"{path}: a profile is a JSON object, not {type(document).__name__}")
    profile = Profile.from_document(document, str(path))
    try:
        profile.display_model()
    except (KeyError, TypeError, ValueError) as error:
        raise ProfileError(f"{path}: display_model parameters are unusable ({error}). "
                           "Export the profile again") from None
    return profile


def save_profile(profile: Profile, path) -> Path:
    """Validate and write ``profile`` atomically (temporary file, fsync, rename)."""
    path = Path(path)
    document = profile.to_document()
    validate_profile_document(document, str(path))
    with atomic_writer(path) as handle:
        json.dump(document, handle, indent=1)
        handle.write("\n")
    return path


PAPER_VIVE_TABLE1 = {
    "white": (0.299, 0.315, 100.0),
    "red": (0.667, 0.332, 30.3),
    "green": (0.217, 0.710, 75.4),
    "blue": (0.139, 0.051, 7.8),
    "black": (0.311, 0.307, 0.4),
    "gamma": (2.43, 2.38, 2.38),
}
"""Table 1 of Díaz-Barrancas et al. (2020): HTC Vive through the lens (xy, relative Y; gammas)."""


def paper_vive_profile() -> Profile:
    """The paper's HTC Vive (Table 1) as a gamma-matrix profile, with the four paper lights.

    Luminances are relative (white Y = 100). Note that the primaries sum to
    113.5 % of the white: the channels are not additive (see the diagnostics).
    """
    from workbench.illuminants import PAPER_SOURCES

    table = PAPER_VIVE_TABLE1
    model = GammaMatrixDisplay.from_primaries_xyY(
        [table["red"], table["green"], table["blue"]], table["white"], table["gamma"],
        black_xyY=table["black"])
    profile = Profile.from_display_model(
        model,
        device={"name": "HTC Vive (Díaz-Barrancas et al. 2020)",
                "description": "OLED HMD measured through the lens with a CS-2000; Table 1 of the "
                               "paper: primaries' xy and relative Y, gammas, black",
                "source": "Sensors 2020, 20(19), 5658, Table 1"},
        xyz_scale="relative-white-100",
        instrument={"name": "Konica Minolta CS-2000", "model": "CS-2000", "serial": ""},
        validation={"mean_dE00": 1.8, "n": 50,
                    "protocol": "as published: mean CIEDE2000 of 50 random colours "
                                "(p95 and max not published)"},
        created="2020-09-27T00:00:00+00:00",
    )
    return profile.with_lights(PAPER_SOURCES)
