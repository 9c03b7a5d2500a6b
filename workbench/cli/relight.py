"""``relight CUBE --illuminant ID (--profile P | --display srgb) --out FILE.png``: the engine texture.

Writes the 8-bit texture the engine uploads for a hyperspectral cube lit by a
source (design §2), in the cube's spatial layout:

- ``--level 1``: the cube's authored sRGB under D65 (the texture as scanned),
  unchanged; only the light colour is managed.
- ``--level 2`` (default): the recomputed texels, so that the engine's
  ``albedo ⊙ light`` gives ``DAC_t = display_inverse(XYZ_t(ρ))``, by the
  method of the runtime bundle (:mod:`workbench.export.level2_files`): the
  cube as K basis coefficients + S precision channels in float16, relit with
  the runtime's display inverse. ``--basis auto`` (default) chooses K + S as
  ``export`` does, for 8-bit texels equal to the full band's under
  ``--illuminant`` and ``--lights`` (default: D65, A, FL11 and the two-peak
  source); ``--basis K`` imposes K (and ``--split`` S, default 0);
  ``--target`` (an earlier choice) takes the smallest K whose max ΔE00 vs
  the full band on held-out texels meets it; ``--basis full`` uses every
  band (the reference the others are checked against).

Either level goes with the engine light colour (printed, and stored in the
PNG's text chunks); ``--render`` also writes what the engine then outputs.
Level 2 also reports how many texels the light cannot carry (``DAC_t`` needs
an albedo above 1, or a channel the light does not have: the engine shows
them off target; design §2).
"""

from __future__ import annotations

import json
import sys

from workbench.colorimetry import DEFAULT_K, DEFAULT_OBSERVER, OBSERVERS
from workbench.errors import InputError

__all__ = ["register"]

DISPLAYS = ("srgb",)
"""Built-in displays for ``--display`` (a measured headset comes with ``--profile``)."""

DEFAULT_LIGHTS = ("cie-d65", "cie-a", "cie-fl11", "d65-two-peak")
"""Lights K + S must hold under besides ``--illuminant`` (``--basis auto``): the sources the
accuracy goals are stated for (:data:`workbench.hyperspectral.ACCURACY_SOURCES`)."""


def _basis_choice(value: str):
    if value in ("auto", "full"):
        return value
    try:
        components = int(value)
    except ValueError:
        raise InputError(f"--basis {value!r}: give a number of components, 'auto' or 'full'"
                         ) from None
    if components < 1:
        raise InputError(f"--basis {components}: the number of components must be at least 1")
    return components


def _light_ids(value: str) -> list[str]:
    ids = [item.strip() for item in value.split(",") if item.strip()]
    if not ids:
        raise InputError(f"--lights {value!r}: give source ids separated by commas")
    return ids


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "relight", help="engine texture of a hyperspectral cube under a source (PNG)",
        description="Write the 8-bit engine texture of a reflectance cube (.hdr, .npz, .h5, "
                    ".mat) lit by a source, at level 1 (authored sRGB + managed light) or "
                    "level 2 (recomputed texels), for a headset profile or the ideal sRGB "
                    "display. Level 2 uses the runtime bundle's method: K basis coefficients "
                    "+ S precision channels in float16, K + S chosen as 'export' does for "
                    "8-bit texels identical to the full band's, and the runtime's display "
                    "inverse.")
    parser.add_argument("cube", help="reflectance cube: ENVI .hdr, .npz, .h5/.hdf5 or .mat")
    parser.add_argument("--illuminant", required=True,
                        help="source id (see 'illuminants list') or a .csv/.xml spectrum")
    target = parser.add_mutually_exclusive_group(required=True)
    target.add_argument("--profile", help="headset profile (.vrprofile.json)")
    target.add_argument("--display", choices=DISPLAYS, help="a built-in display")
    parser.add_argument("--level", type=int, choices=(1, 2), default=2,
                        help="1: authored texture, managed light; 2: recomputed texels (default)")
    parser.add_argument("--basis", default="auto",
                        help="level 2: 'auto' (default: the runtime bundle's K + S, chosen for "
                             "8-bit texels identical to the full band's under --illuminant and "
                             "--lights), a number of components K (S from --split), or 'full' "
                             "(every band)")
    parser.add_argument("--lights", type=_light_ids, default=None, metavar="ID,...",
                        help="--basis auto: the other lights K + S must hold under, as a bundle "
                             f"of them would (default {','.join(DEFAULT_LIGHTS)})")
    parser.add_argument("--split", type=int, default=None, metavar="S",
                        help="with --basis K or --target: coefficients given a precision channel "
                             "(default 0)")
    parser.add_argument("--target", type=float, default=None,
                        help="instead of the bundle's choice: the smallest K whose max ΔE00 vs "
                             "the full band on held-out texels meets this (the earlier default; "
                             "no precision channels unless --split)")
    parser.add_argument("--kernel", default="auto",
                        help="level 2 with a basis: auto (the compiled kernel where the display "
                             "inverse has no correction table), numba or numpy")
    parser.add_argument("--k", type=float, default=None,
                        help=f"scene-white factor (default: the profile's, else {DEFAULT_K})")
    parser.add_argument("--observer", choices=sorted(OBSERVERS), default=None,
                        help="default: the profile's, else cie1931-2")
    parser.add_argument("--out", required=True, help="output texture (.png)")
    parser.add_argument("--render", help="also write the engine output (texture ⊙ light) here")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.set_defaults(handler=_relight)


def _check_options(args, basis_choice) -> None:
    """Refuse options that do not go together before any work is done."""
    from workbench.export.level2_files import RUNTIME_KERNELS

    if args.kernel not in (*RUNTIME_KERNELS, "auto"):
        raise InputError(f"--kernel {args.kernel!r}: unknown relight kernel; use one of "
                         f"{', '.join(RUNTIME_KERNELS)} or auto")
    if args.split is not None:
        if basis_choice == "auto" and args.target is None:
            raise InputError("--split goes with --basis K or --target; --basis auto chooses S")
        if basis_choice == "full":
            raise InputError("--split goes with --basis K or --target, not --basis full")
        limit = basis_choice if isinstance(basis_choice, int) else None
        if args.split < 0 or (limit is not None and args.split > limit):
            raise InputError(f"--split {args.split}: between 0 and K"
                             + (f" = {limit}" if limit is not None else "")
                             + " coefficients get a precision channel")
    if args.lights is not None and (basis_choice != "auto" or args.target is not None):
        raise InputError("--lights goes with --basis auto (the lights K + S are chosen under)")


def _runtime_basis(args, basis_choice, cube, illuminant, display, k, observer):
    """(texture, summary's "basis" entry) of the runtime's method (module doc)."""
    from workbench.export.level2_files import resolve_runtime_kernel, runtime_texture
    from workbench.export.runtime_inverse import runtime_display_inverse
    from workbench.hyperspectral import fit_cube_basis
    from workbench.illuminants import get_illuminant

    inverse = runtime_display_inverse(display)
    entry = {"kernel": resolve_runtime_kernel(inverse, args.kernel)}   # refused before any work
    if basis_choice == "auto" and args.target is None:
        ids = list(dict.fromkeys([illuminant.id, *(args.lights or DEFAULT_LIGHTS)]))
        lights = [illuminant] + [get_illuminant(light_id) for light_id in ids[1:]]
        texture = runtime_texture(cube, display, lights, inverse, k=k, observer=observer)
        choice = texture.choice
        entry = {"method": "bundle: K + S for 8-bit texels identical to the full band's",
                 "lights": ids, **{key: value for key, value in choice.to_json().items()
                                   if key not in ("tried", "criterion")}}
    else:
        if basis_choice == "auto":
            components = fit_cube_basis(cube, target_max_dE00=args.target, observer=observer,
                                        k=k).components
            entry["method"] = f"K for max ΔE00 ≤ {args.target:g} on held-out texels"
            entry["target_max_dE00"] = args.target
        else:
            components = basis_choice
            entry["method"] = "K imposed"
        split = 0 if args.split is None else args.split
        texture = runtime_texture(cube, display, [], inverse, k=k, observer=observer,
                                  components=components, split=split)
    entry.update({"K": texture.components, "split": texture.split,
                  "channels": texture.components + texture.split,
                  "held_out_max_dE00": {source: round(value, 4) for source, value
                                        in texture.basis.held_out.max_dE00.items()}})
    return texture, inverse, entry


def _relight(args) -> int:
    from pathlib import Path

    from workbench.colour_management import engine_render, light_colour
    from workbench.display import SRGBDisplay
    from workbench.export.level2_files import relight_runtime_texture
    from workbench.hyperspectral import (
        authored_srgb8_cube,
        read_cube,
        relight_level2_full_band,
        write_png_rgb8,
    )
    from workbench.illuminants import get_illuminant

    for option in ("out", "render"):
        value = getattr(args, option)
        if value and Path(value).suffix.lower() != ".png":
            raise InputError(f"--{option} {value}: the texture is written as PNG; name it *.png")
    basis_choice = _basis_choice(args.basis)
    if args.level == 2:
        _check_options(args, basis_choice)
    if args.profile:
        from workbench.profile import load_profile

        profile = load_profile(args.profile)
        display, display_name = profile.display_model(), f"profile {args.profile}"
        k = profile.k if args.k is None else args.k
        observer = args.observer or profile.observer
    else:
        display, display_name = SRGBDisplay(), "ideal sRGB"
        k = DEFAULT_K if args.k is None else args.k
        observer = args.observer or DEFAULT_OBSERVER
    illuminant = get_illuminant(args.illuminant)
    cube = read_cube(args.cube)
    light = light_colour(illuminant.sd, display, k=k, observer=observer)
    summary = {"cube": cube.source, "shape": list(cube.shape), "illuminant": illuminant.id,
               "display": display_name, "level": args.level,
               "light_rgb8": [int(v) for v in light.rgb8], "light_in_gamut": light.in_gamut}
    if args.level == 1:
        texture = authored_srgb8_cube(cube)
        summary["texture"] = "authored sRGB under D65 (as scanned)"
    elif basis_choice == "full":
        relit = relight_level2_full_band(cube, illuminant, display, k=k, observer=observer)
        texture = relit.texels
        summary["texture"] = "level 2, full band"
        summary["unreachable_texels"] = relit.unreachable
    else:
        runtime, inverse, summary["basis"] = _runtime_basis(args, basis_choice, cube, illuminant,
                                                            display, k, observer)
        relit = relight_runtime_texture(runtime, illuminant, display, inverse, k=k,
                                        kernel=args.kernel)
        texture = relit.texels
        summary["texture"] = (f"level 2, runtime method: K = {runtime.components} basis "
                              f"coefficients + S = {runtime.split} precision channels, float16")
        summary["unreachable_texels"] = relit.unreachable
        choice = runtime.choice
        if choice is not None and not choice.meets_target:
            print(f"warning: no K + S up to the largest tried met the bundle's target; "
                  f"K + S = {choice.components} + {choice.split} is the closest: 8-bit texels "
                  f"identical to the full band's on {100 * min(choice.basis_identical.values()):.2f} % "
                  f"of held-out texels (target {100 * choice.target_share:.1f} %) and "
                  f"{100 * min(choice.probe_identical.values()):.2f} % of the library's "
                  f"materials (target {100 * choice.probe_share:.1f} %)", file=sys.stderr)
    text = {"Software": "vr-colour-workbench relight",
            "Description": f"engine texture, level {args.level}, {illuminant.id}, {display_name}",
            "workbench.light_rgb8": ",".join(str(int(v)) for v in light.rgb8),
            "workbench.summary": json.dumps(summary, ensure_ascii=True)}
    write_png_rgb8(args.out, texture, text)
    summary["out"] = str(args.out)
    if args.render:
        rendered = engine_render(texture.reshape(-1, 3), light.rgb8).reshape(texture.shape)
        write_png_rgb8(args.render, rendered, {**text, "Description": "engine output (texture × "
                                               f"light), level {args.level}, {illuminant.id}"})
        summary["render"] = str(args.render)
    if args.json:
        json.dump(summary, sys.stdout, indent=1)
        print()
    else:
        print(f"{summary['out']}: {cube.height}×{cube.width} texels, {summary['texture']}, "
              f"{illuminant.id} on {display_name}")
        print(f"engine light colour (sRGB 8-bit): {', '.join(str(v) for v in summary['light_rgb8'])}"
              + ("" if light.in_gamut else "  (the source's white is outside the display gamut: "
                                           "clipped)"))
        if "unreachable_texels" in summary:
            print(f"unreachable texels: {summary['unreachable_texels']} of "
                  f"{cube.height * cube.width} (the light cannot carry their DAC_t: albedo "
                  "clipped at 1, or a channel the light does not have)")
        if "basis" in summary:
            basis = summary["basis"]
            line = f"basis K = {basis['K']} + S = {basis['split']} ({basis['method']}"
            if "basis_identical_share" in basis:
                shares = basis["basis_identical_share"]
                line += (", under " + ", ".join(shares) + ": identical on "
                         f"{100 * min(shares.values()):.2f}–{100 * max(shares.values()):.2f} % of "
                         f"{basis['held_out_texels']} held-out texels")
            print(line + ")")
    return 0
