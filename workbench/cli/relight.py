"""``relight CUBE --illuminant ID (--profile P | --display srgb) --out FILE.png``: the engine texture.

Writes the 8-bit texture the engine uploads for a hyperspectral cube lit by a
source (design §2), in the cube's spatial layout:

- ``--level 1``: the cube's authored sRGB under D65 (the texture as scanned),
  unchanged; only the light colour is managed.
- ``--level 2`` (default): the recomputed texels, so that the engine's
  ``albedo ⊙ light`` gives ``DAC_t = display_inverse(XYZ_t(ρ))``.
  ``--basis auto`` (default) compresses the cube to a spectral basis with K
  chosen for ``--target`` (max ΔE00 vs the full band on held-out texels);
  ``--basis K`` imposes K; ``--basis full`` uses every band.

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


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "relight", help="engine texture of a hyperspectral cube under a source (PNG)",
        description="Write the 8-bit engine texture of a reflectance cube (.hdr, .npz, .h5, "
                    ".mat) lit by a source, at level 1 (authored sRGB + managed light) or "
                    "level 2 (recomputed texels), for a headset profile or the ideal sRGB "
                    "display.")
    parser.add_argument("cube", help="reflectance cube: ENVI .hdr, .npz, .h5/.hdf5 or .mat")
    parser.add_argument("--illuminant", required=True,
                        help="source id (see 'illuminants list') or a .csv/.xml spectrum")
    target = parser.add_mutually_exclusive_group(required=True)
    target.add_argument("--profile", help="headset profile (.vrprofile.json)")
    target.add_argument("--display", choices=DISPLAYS, help="a built-in display")
    parser.add_argument("--level", type=int, choices=(1, 2), default=2,
                        help="1: authored texture, managed light; 2: recomputed texels (default)")
    parser.add_argument("--basis", default="auto",
                        help="level 2: 'auto' (K by --target, default), a number of components, "
                             "or 'full' (every band)")
    parser.add_argument("--target", type=float, default=None,
                        help="--basis auto: max ΔE00 vs full band on held-out texels")
    parser.add_argument("--kernel", default="auto",
                        help="level 2 with a basis: relight kernel (auto, numba, numpy)")
    parser.add_argument("--k", type=float, default=None,
                        help=f"scene-white factor (default: the profile's, else {DEFAULT_K})")
    parser.add_argument("--observer", choices=sorted(OBSERVERS), default=None,
                        help="default: the profile's, else cie1931-2")
    parser.add_argument("--out", required=True, help="output texture (.png)")
    parser.add_argument("--render", help="also write the engine output (texture ⊙ light) here")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.set_defaults(handler=_relight)


def _relight(args) -> int:
    from pathlib import Path

    from workbench.colour_management import engine_render, light_colour
    from workbench.display import SRGBDisplay
    from workbench.hyperspectral import (
        authored_srgb8_cube,
        encode_cube,
        fit_cube_basis,
        plan_relight,
        read_cube,
        relight_level2,
        relight_level2_full_band,
        write_png_rgb8,
    )
    from workbench.hyperspectral.basis import DEFAULT_TARGET_MAX_DE00
    from workbench.illuminants import get_illuminant

    for option in ("out", "render"):
        value = getattr(args, option)
        if value and Path(value).suffix.lower() != ".png":
            raise InputError(f"--{option} {value}: the texture is written as PNG; name it *.png")
    basis_choice = _basis_choice(args.basis)
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
        target = DEFAULT_TARGET_MAX_DE00 if args.target is None else args.target
        basis = fit_cube_basis(cube, components=None if basis_choice == "auto" else basis_choice,
                               target_max_dE00=target, observer=observer, k=k)
        plan = plan_relight(basis, illuminant, display, k=k)
        relit = relight_level2(encode_cube(cube, basis), plan, kernel=args.kernel)
        texture = relit.texels
        summary["texture"] = f"level 2, spectral basis K = {basis.components}"
        summary["unreachable_texels"] = relit.unreachable
        summary["basis"] = {"K": basis.components, "held_out_max_dE00": {
            source: round(value, 4) for source, value in basis.held_out.max_dE00.items()},
            "target_max_dE00": None if basis_choice != "auto" else target}
        if not basis.meets_target:
            print(f"warning: no basis met max ΔE00 ≤ {target:g} on held-out texels; "
                  f"K = {basis.components} is the most accurate tried", file=sys.stderr)
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
            worst = max(summary["basis"]["held_out_max_dE00"].values())
            print(f"basis K = {summary['basis']['K']}: max ΔE00 vs full band on held-out texels "
                  f"{worst:.3f} (CIELAB white: the perfect diffuser under each source)")
    return 0
