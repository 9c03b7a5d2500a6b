"""Display profiles (``*.vrprofile.json``): what the VR runtime loads (design §4).

A profile holds the headset's display model (type, parameters, white and black
XYZ), its validation figures and diagnosis, the engine assumptions
(frame-buffer encoding, ``k``, observer), the level-1 lights, and optionally
level-2 data, a 3D-LUT sidecar (``display_inverse.cube`` of a runtime bundle,
:mod:`workbench.export`) and the runtime colour space it assumes. Where the
calibration showed patches as windows on surrounds, the ``apl-dependence``
test is recorded (``apl_test``) and, where it was found and modelled, the APL
curve (``apl``); a profile whose ``apl_test`` did not find it predicts a patch
on any frame as shown full field (:attr:`Profile.apl_tested_absent`).

Reading is strict, in this order (:func:`load_profile`): the file's size
(at most :data:`MAX_PROFILE_BYTES`), JSON without ``NaN``/``Infinity``, the
format name and major version (a newer one is refused, naming the version
this workbench supports), the JSON Schema ``profiles/vrprofile.schema.json``
(every model's parameters: shapes, types, ranges, the extended model's
component names), and finally the display model rebuilt and probed (forward and inverse give finite values). Every
failure is a :class:`ProfileError` naming the file, the place in it and the
fix; nothing from a file is ever executed. :func:`save_profile` validates the
same way and writes atomically.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import jsonschema
import numpy as np

from profiles import SCHEMA_PATH
from workbench import __version__
from workbench.colorimetry import DEFAULT_K, DEFAULT_OBSERVER
from workbench.colour_management import light_colour
from workbench.display import (
    DisplayModel,
    GammaMatrixDisplay,
    display_model_from_parameters,
)
from workbench.errors import InputError, WorkbenchError
from workbench.fileio import atomic_writer

__all__ = [
    "PROFILE_FORMAT",
    "PROFILE_FORMAT_VERSION",
    "MAX_PROFILE_BYTES",
    "RUNTIME_COLOUR_SPACE",
    "ProfileError",
    "check_apl_block",
    "check_apl_test",
    "LIGHTS_LOAD",
    "check_display_parameters",
    "parse_profile_text",
    "Profile",
    "profile_schema",
    "validate_profile_document",
    "load_profile",
    "save_profile",
    "light_entries",
    "paper_vive_profile",
    "SIMULATED_HEADSET_EFFECTS",
    "simulated_headset_profile",
    "profile_from_diagnosis",
    "apl_block",
    "apl_test_record",
    "measurement_record",
]

PROFILE_FORMAT = "vr-colour-workbench-profile"
PROFILE_FORMAT_VERSION = 1
"""The major format version this workbench reads and writes."""

MAX_PROFILE_BYTES = 16 * 1024 * 1024
"""Largest profile file read (a 33³ residual LUT profile is under 3 MB)."""

RUNTIME_COLOUR_SPACE = (
    "OpenXR XR_FB_color_space XR_COLOR_SPACE_UNMANAGED_FB (or a runtime that passes the "
    "application's 8-bit values to the panel unchanged): the application's light colours, "
    "level-2 textures and display_inverse.cube do all the colour management")
"""The runtime colour space a profile's data assume (recorded in every exported bundle)."""

_FIX = "Fix the file or export it again with 'python -m workbench diagnose SESSION --export PROFILE'"


class ProfileError(WorkbenchError, ValueError):
    """A profile file is unreadable or does not follow the schema."""


_SCHEMA: dict | None = None


def profile_schema() -> dict:
    """The profile JSON Schema (draft 2020-12)."""
    global _SCHEMA
    if _SCHEMA is None:
        _SCHEMA = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
    return json.loads(json.dumps(_SCHEMA))


_VALIDATOR: jsonschema.Draft202012Validator | None = None


def _validator() -> jsonschema.Draft202012Validator:
    global _VALIDATOR
    if _VALIDATOR is None:
        _VALIDATOR = jsonschema.Draft202012Validator(profile_schema())
    return _VALIDATOR


def _non_finite_path(value, path=()) -> tuple | None:
    """The path of the first NaN or infinite number in a JSON-like value, or None."""
    if isinstance(value, float):
        return None if math.isfinite(value) else path
    if isinstance(value, dict):
        items = value.items()
    elif isinstance(value, (list, tuple)):
        items = enumerate(value)
    else:
        return None
    for key, item in items:
        found = _non_finite_path(item, path + (key,))
        if found is not None:
            return found
    return None


def _where(path) -> str:
    return "/".join(str(p) for p in path) or "(top level)"


def _check_version(document: dict, source: str) -> None:
    if document.get("format") != PROFILE_FORMAT:
        raise ProfileError(f"{source}: format: {document.get('format')!r} is not "
                           f"{PROFILE_FORMAT!r}; this is not a VR colour workbench profile")
    version = document.get("format_version")
    if isinstance(version, bool) or not isinstance(version, int):
        raise ProfileError(f"{source}: format_version: {version!r} must be an integer "
                           f"(this workbench reads version {PROFILE_FORMAT_VERSION}). {_FIX}")
    if version > PROFILE_FORMAT_VERSION:
        raise ProfileError(f"{source}: format_version {version} is newer than this workbench "
                           f"supports (version {PROFILE_FORMAT_VERSION}); update vr-colour-workbench "
                           "or export the profile again with this version")


def validate_profile_document(document: dict, source: str = "profile") -> None:
    """Raise :class:`ProfileError` naming the first violation and where it is.

    Checks, in order: a JSON object; no NaN or infinite number; the format
    name and a major version not newer than :data:`PROFILE_FORMAT_VERSION`;
    the JSON Schema (which describes every display model's parameters).
    """
    if not isinstance(document, dict):
        raise ProfileError(f"{source}: a profile is a JSON object, not {type(document).__name__}")
    bad = _non_finite_path(document)
    if bad is not None:
        raise ProfileError(f"{source}: {_where(bad)}: NaN or infinity where a finite number "
                           f"belongs. {_FIX}")
    _check_version(document, source)
    error = jsonschema.exceptions.best_match(_validator().iter_errors(document))
    if error is not None:
        message = error.message if len(error.message) < 300 else error.message[:300] + "…"
        raise ProfileError(f"{source}: {_where(error.absolute_path)}: {message}. {_FIX}")


_PROBE_DAC = np.array([[0, 0, 0], [255, 255, 255], [255, 0, 0], [0, 255, 0], [0, 0, 255],
                       [128, 64, 32], [16, 200, 90]], dtype=float)


def check_display_parameters(model_type: str, parameters: dict, source: str = "profile"
                             ) -> DisplayModel:
    """Rebuild the display model of a schema-valid profile and probe it; :class:`ProfileError` if unusable.

    The model must build (its constructor's own checks: e.g. a singular
    primaries matrix, a non-monotone tone curve) and forward and inverse must
    give finite values on a few probe colours. (The extended model's component
    names are checked by the schema, whose list follows
    :data:`workbench.diagnostics.extension.TERMS`.)
    """
    try:
        with np.errstate(all="ignore"):
            model = display_model_from_parameters(model_type, parameters)
            XYZ = model.forward(_PROBE_DAC)
            dac = model.inverse(XYZ) if np.all(np.isfinite(XYZ)) else XYZ
    except (WorkbenchError, KeyError, TypeError, ValueError, IndexError, ArithmeticError) as error:
        raise ProfileError(f"{source}: display_model/parameters are unusable ({error}). {_FIX}"
                           ) from None
    if not (np.all(np.isfinite(XYZ)) and np.all(np.isfinite(dac))):
        raise ProfileError(f"{source}: display_model/parameters give NaN or infinite colours "
                           f"({model.describe()}). {_FIX}")
    return model


def check_apl_block(block: dict, source: str = "profile") -> None:
    """Refuse an ``apl`` block whose curve cannot be evaluated (e.g. power shares not summing to 1)."""
    from workbench.apl.predict import apl_curve_from_json

    try:
        curve = apl_curve_from_json(block)
        gains = curve.relative_gain(np.array([[255.0, 255.0, 255.0], [128.0, 64.0, 32.0]]),
                                    np.array([0.1, 1.0]), np.zeros((2, 3)))
    except InputError as error:
        raise ProfileError(f"{source}: apl: {error}") from None
    if not np.all(np.isfinite(gains) & (gains > 0)):
        raise ProfileError(f"{source}: apl: the curve's gains are not finite and positive; "
                           "re-export the profile from its session")


def check_apl_test(record: dict, apl: dict | None, source: str = "profile") -> None:
    """Refuse an ``apl_test`` record that contradicts the profile's ``apl`` block.

    A test that did not find ``apl-dependence`` cannot come with an APL curve
    (the curve is only fitted where the test found the effect).
    """
    if not record["found"] and apl is not None:
        raise ProfileError(f"{source}: apl_test: says apl-dependence was not found, yet the "
                           f"profile has an apl curve. {_FIX}")


def parse_profile_text(text: str, source: str = "profile") -> "Profile":
    """Parse and fully validate a profile's JSON text (what :func:`load_profile` reads)."""
    def refuse_constant(name):
        raise ProfileError(f"{source}: {name} is not a JSON number; write a finite number. {_FIX}")

    if len(text) > MAX_PROFILE_BYTES:
        raise ProfileError(f"{source}: {len(text)} characters is more than a profile holds "
                           f"(at most {MAX_PROFILE_BYTES} bytes); is this the right file?")
    try:
        return Profile.from_document(json.loads(text, parse_constant=refuse_constant), source)
    except json.JSONDecodeError as error:
        raise ProfileError(f"{source}, line {error.lineno}: not valid JSON ({error.msg}). "
                           "Export the profile again") from None
    except RecursionError:  # in the parser or in validation
        raise ProfileError(f"{source}: nested too deeply to be a profile") from None


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
    runtime: dict | None = field(default_factory=lambda: {"colour_space": RUNTIME_COLOUR_SPACE})
    apl: dict | None = None
    apl_test: dict | None = None
    measurement: dict | None = None
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

    def apl_curve(self):
        """The profile's APL curve (:class:`~workbench.apl.curve.AplCurve`), or None.

        The display model and the light tables hold at the reference load
        (each patch full field); the curve says how a patch on another frame differs.
        """
        from workbench.apl.predict import apl_curve_from_json

        return None if self.apl is None else apl_curve_from_json(self.apl)

    @property
    def apl_tested_absent(self) -> bool:
        """Whether ``apl-dependence`` was tested (windows and surrounds measured) and not found.

        Such a profile predicts a patch on any frame as the display model's
        full-field prediction: gain 1 at every load. A profile without an
        ``apl_test`` record (its calibration showed every patch full field, or
        it predates the record) says nothing about other loads.
        """
        return self.apl is None and self.apl_test is not None and not self.apl_test["found"]

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
        if self.runtime is not None:
            document["runtime"] = self.runtime
        if self.apl is not None:
            document["apl"] = self.apl
        if self.apl_test is not None:
            document["apl_test"] = self.apl_test
        if self.measurement is not None:
            document["measurement"] = dict(self.measurement)
        return document

    @classmethod
    def from_document(cls, document: dict, source: str = "profile") -> "Profile":
        """Validate ``document`` fully (schema, then the model rebuilt and probed) and wrap it."""
        validate_profile_document(document, source)
        model = document["display_model"]
        check_display_parameters(model["type"], model["parameters"], source)
        if document.get("apl") is not None:
            check_apl_block(document["apl"], source)
        if document.get("apl_test") is not None:
            check_apl_test(document["apl_test"], document.get("apl"), source)
        return cls(
            device=document["device"], display_model_type=model["type"],
            display_parameters=model["parameters"], white_XYZ=tuple(model["white_XYZ"]),
            black_XYZ=tuple(model["black_XYZ"]), xyz_scale=model["xyz_scale"],
            instrument=document.get("instrument"), validation=document.get("validation"),
            diagnosis=document.get("diagnosis"), engine=document["engine"],
            lights=tuple(document["lights"]), level2=document.get("level2"),
            lut3d=document.get("lut3d"), runtime=document.get("runtime"),
            apl=document.get("apl"), apl_test=document.get("apl_test"),
            measurement=document.get("measurement"),
            created=document.get("created", ""),
            software=document["software"])


LIGHTS_LOAD = "light colours hold at the reference load: each patch full field"
"""At which frame load the level-1 light colours (and the display model) hold: an OLED that
limits its power (``apl-dependence``) shows a colour dimmer on a more lit frame (the profile's
``apl`` block says by how much)."""


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
        size = path.stat().st_size
        if size > MAX_PROFILE_BYTES:
            raise ProfileError(f"{path}: {size} bytes is more than a profile holds (at most "
                               f"{MAX_PROFILE_BYTES}); is this the right file?")
        data = path.read_bytes()
    except FileNotFoundError:
        raise ProfileError(f"{path}: no such profile. Export one with 'python -m workbench "
                           "diagnose SESSION --export PROFILE' or use profiles/"
                           "htc-vive-paper.vrprofile.json") from None
    except IsADirectoryError:
        raise ProfileError(f"{path}: is a directory; give the .vrprofile.json file") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise ProfileError(f"{path}: not UTF-8 text (byte {error.start}); a profile is JSON"
                           ) from None
    return parse_profile_text(text, str(path))


def save_profile(profile: Profile, path) -> Path:
    """Validate and write ``profile`` atomically (temporary file, fsync, rename)."""
    path = Path(path)
    document = profile.to_document()
    Profile.from_document(document, str(path))
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


def profile_from_diagnosis(diagnosis) -> Profile:
    """The profile of a diagnosis: what ``diagnose SESSION --export PROFILE`` writes.

    The extended model (the baseline's when nothing was found), its held-out
    validation figures, the findings, the ``apl-dependence`` test where the
    session could test it, the APL curve where it is in the model, and level-1
    lights for the paper's sources.

    Parameters
    ----------
    diagnosis : workbench.diagnostics.Diagnosis
        A session's diagnosis.
    """
    from workbench.illuminants import PAPER_SOURCES

    score = diagnosis.extended_score
    return Profile.from_display_model(
        diagnosis.extended,
        device={"name": Path(diagnosis.session.source).stem or "display",
                "source": diagnosis.session.source},
        validation=None if score is None else {**score.to_json(), "protocol": diagnosis.protocol},
        diagnosis={"findings": [{"effect": f.effect, "evidence": f.evidence, "score": f.score}
                                for f in diagnosis.findings]},
        apl=apl_block(diagnosis),
        apl_test=apl_test_record(diagnosis),
        measurement=measurement_record(diagnosis.session),
    ).with_lights(PAPER_SOURCES)


def measurement_record(session) -> dict | None:
    """The profile's ``measurement`` block: which panel (``eye``) and with which instrument sync
    (``sync``) the session was measured, where its metadata says (a session measured by ``measure``
    since they are recorded); None where it says neither."""
    from workbench.session import MEASUREMENT_METADATA

    metadata = getattr(session, "metadata", None) or {}
    record = {key: str(metadata[key]) for key in MEASUREMENT_METADATA if metadata.get(key)}
    return record or None


def apl_block(diagnosis) -> dict | None:
    """The profile's ``apl`` block: the APL curve and its held-out scores, where it is in the model."""
    if getattr(diagnosis, "apl", None) is None or diagnosis.apl.curve is None:
        return None
    return {**diagnosis.apl.curve.to_json(),
            "held_out": [{"by": h.by, "luminance_error_pct": h.luminance_error_pct,
                          "mean_dE00": h.dE00,
                          "without_load_term": {"luminance_error_pct": h.luminance_error_pct_without,
                                                "mean_dE00": h.dE00_without}}
                         for h in diagnosis.apl.holdouts]}


def apl_test_record(diagnosis) -> dict | None:
    """The profile's ``apl_test`` record: the diagnosis's ``apl-dependence`` test, where it was testable.

    None where the session showed every patch full field (nothing was tested).
    ``found`` false with no ``apl`` curve means the display's output does not
    depend on the frame's load beyond noise (or by less than the materiality
    floor): the profile then predicts a patch on any frame as full field.

    Parameters
    ----------
    diagnosis : workbench.diagnostics.Diagnosis
        A session's diagnosis (its ``results`` hold the APL detector's test).
    """
    context = getattr(diagnosis, "context", None)
    if context is not None and not context.apl_testable:
        return None
    result = next((r for r in getattr(diagnosis, "results", ()) if r.effect == "apl-dependence"),
                  None)
    if result is None or not result.testable:
        return None

    def number(value):
        value = None if value is None else float(value)
        return value if value is not None and math.isfinite(value) else None

    return {"found": bool(result.found), "significant": bool(result.significant),
            "z": number(result.z), "critical_z": number(result.critical_z),
            "p_value": float(result.p_value), "impact_dE00": number(result.impact_dE00),
            "evidence": str(result.evidence)}


SIMULATED_HEADSET_EFFECTS = {"channel-interaction": 0.1, "black-offset": 0.006}
"""The effects hidden in the simulated headset of ``make demo`` and the shipped simulated profile."""


def simulated_headset_profile(seed: int = 1) -> Profile:
    """The simulated headset of ``make demo``, calibrated and diagnosed: an extended-model profile.

    The paper's measurement plan on the simulated headset with
    :data:`SIMULATED_HEADSET_EFFECTS` hidden in it (instrument noise seeded
    with ``seed``), diagnosed, and exported as ``diagnose --export`` does;
    ``profiles/simulated-headset.vrprofile.json`` is this profile.
    """
    import tempfile

    from workbench.diagnostics import diagnose
    from workbench.simulated_sessions import simulate_session

    diagnosis = diagnose(simulate_session(dict(SIMULATED_HEADSET_EFFECTS), seed=seed))
    with tempfile.TemporaryDirectory() as folder:  # written and read back, as a user's export is
        profile = load_profile(save_profile(profile_from_diagnosis(diagnosis),
                                            Path(folder) / "p.vrprofile.json"))
    effects = ", ".join(f"{name} {value:g}" for name, value in SIMULATED_HEADSET_EFFECTS.items())
    return replace(profile, device={
        "name": "Simulated headset (make demo)",
        "description": f"the workbench's simulated OLED headset with {effects}, measured with the "
                       f"paper's plan through the CS-2000 model (seed {seed}) and diagnosed",
        "source": "workbench.profile.simulated_headset_profile"},
        created="2026-01-01T00:00:00+00:00")
