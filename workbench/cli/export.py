"""``export PROFILE --bundle DIR``: the runtime bundle a VR application loads (``workbench.export``)."""

from __future__ import annotations

import json
import sys

from workbench.errors import InputError

__all__ = ["register"]


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "export", help="write the runtime bundle of a profile (3D LUT, lights, level-2 textures, "
                       "shaders, Unity loader)",
        description="Write the runtime bundle of a headset profile: the profile, "
                    "display_inverse.cube (engine sRGB output → HMD DAC/255), lights.json "
                    "(level 1), for each --cube the level-2 coefficient textures and per-light "
                    "matrices, the reference consumer, the Unity C# loader, the HLSL and GLSL "
                    "shaders and a README.")
    parser.add_argument("profile", help="a .vrprofile.json")
    parser.add_argument("--bundle", required=True, metavar="DIR",
                        help="output folder (new, empty, or an earlier bundle, replaced whole)")
    parser.add_argument("--lights", metavar="ID,...",
                        help="source ids, comma-separated (default: the profile's lights)")
    parser.add_argument("--cube", action="append", default=[], metavar="CUBE",
                        help="hyperspectral cube for level 2 (.hdr, .npz, .h5, .mat); repeatable")
    parser.add_argument("--lightbooth", action="store_true",
                        help="add the Lightbooth sample's two level-2 cubes, 'colorchecker' and "
                             "'ishihara' (the workbench's own booth surfaces, 101 bands)")
    parser.add_argument("--lut-size", type=int, default=33, metavar="N",
                        help="nodes per axis of display_inverse.cube (default 33)")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.set_defaults(handler=_export)


def _export(args) -> int:
    from workbench.export import write_bundle
    from workbench.profile import load_profile

    profile = load_profile(args.profile)
    lights = None
    if args.lights:
        lights = [item.strip() for item in args.lights.split(",") if item.strip()]
        if not lights:
            raise InputError(f"--lights {args.lights!r}: give source ids separated by commas")
    cubes = list(args.cube)
    if args.lightbooth:
        from workbench.export.bundle import lightbooth_cubes

        cubes += lightbooth_cubes()
    summary = write_bundle(profile, args.bundle, light_ids=lights, cubes=cubes,
                           lut_size=args.lut_size)
    if args.json:
        json.dump(summary.to_json(), sys.stdout, indent=1)
        print()
        return 0
    accuracy = summary.cube_accuracy
    print(f"bundle {summary.directory}: {len(summary.lights)} light(s), "
          f"{len(summary.cubes)} level-2 cube(s)")
    print(f"display_inverse.cube {accuracy.size}³: trilinear vs exact inverse on "
          f"{accuracy.samples} in-gamut colours, ΔE00 mean {accuracy.mean_dE00:.3f}, "
          f"p95 {accuracy.p95_dE00:.3f}, max {accuracy.max_dE00:.3f}")
    inverse = summary.inverse_accuracy
    print(f"runtime display inverse: integer DAC equal to the model's on {100 * inverse.identical:.2f} "
          f"% of {inverse.samples} colours (largest difference {inverse.max_counts} count(s))"
          + ("" if inverse.identical >= 0.99 else
             "  [warning: this model's inverse is not smooth enough for the runtime's "
             "correction table; level-2 texels will differ from the workbench's]"))
    for cube in summary.cubes:
        choice = cube["choice"]
        worst = min(choice["identical_share"].values())
        print(f"level2/{cube['name']}: K = {cube['components']} + {cube['split']} precision "
              f"channel(s), {cube['layers']} RGBA16F layer(s); runtime texel identical to the "
              f"full band on {100 * worst:.2f} % of held-out texels (worst light)"
              + ("" if choice["meets_target"] else
                 f"  [below target: runtime-inverse texels identical on "
                 f"{100 * min(choice['basis_identical_share'].values()):.2f} % of held-out texels "
                 f"(target {100 * choice['target_basis_identical_share']:.1f} %) and "
                 f"{100 * min(choice['probe_identical_share'].values()):.2f} % of the probe "
                 f"materials (target {100 * choice['target_probe_identical_share']:.1f} %)]"))
    return 0
