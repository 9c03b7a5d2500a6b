"""Runs a bundle's level-2 relight shader off-screen (moderngl, EGL, Mesa llvmpipe) for the tests."""

import json
from pathlib import Path

import numpy as np

MAX_LAYERS = 16


def gl_context():
    """A standalone OpenGL 4.3+ context, or None with the reason."""
    try:
        import moderngl
    except ImportError as error:
        return None, f"moderngl is not installed ({error}); pip install moderngl"
    try:
        return moderngl.create_standalone_context(backend="egl", require=430), ""
    except Exception as error:  # no EGL, no GL 4.3 driver
        return None, (f"no OpenGL 4.3 EGL context ({error}); install the Debian packages "
                      "libegl1 libgl1-mesa-dri libegl-mesa0")


def level2_inputs(bundle: Path, cube: str, light_id: str) -> dict:
    """The arrays the shader binds, read from the bundle's files."""
    folder = bundle / "level2" / cube
    header = json.loads((folder / "coefficients.json").read_text())
    record = next(light for light in json.loads((folder / "lights.json").read_text())["lights"]
                  if light["id"] == light_id)
    inverse = json.loads((bundle / "display_inverse.json").read_text())
    channels, layers = header["channels"], header["layers"]
    matrix = np.zeros((3, layers * 4), dtype=np.float32)
    matrix[:, :channels] = np.asarray(record["matrix"], dtype=np.float32).reshape(3, channels)
    rows = np.zeros((3 * MAX_LAYERS, 4), dtype=np.float32)
    for layer in range(layers):
        for output in range(3):
            rows[3 * layer + output] = matrix[output, 4 * layer:4 * layer + 4]
    correction = inverse["correction"]
    table = None
    if correction["size"]:
        table = (bundle / correction["file"]).read_bytes()
    return {"width": header["width"], "height": header["height"], "layers": layers,
            "coefficients": (folder / header["file"]).read_bytes(),
            "rows": rows, "offset": tuple(float(v) for v in record["offset"]),
            "thresholds": np.asarray(inverse["thresholds"], dtype=np.float32).tobytes(),
            "cells": np.asarray(inverse["cells"], dtype=np.float32).tobytes(),
            "cell_count": len(inverse["cells"]) // 3,
            "texel_table": np.asarray(record["texel_table"], dtype=np.float32).tobytes(),
            "unreachable": tuple(int(v) for v in record["unreachable_dac"]),
            "correction_size": correction["size"], "correction_domain": tuple(correction["domain"]),
            "correction": table}


def _textures(ctx, inputs):
    coefficients = ctx.texture_array((inputs["width"], inputs["height"], inputs["layers"]), 4,
                                     inputs["coefficients"], dtype="f2")
    thresholds = ctx.texture((255, 3), 1, inputs["thresholds"], dtype="f4")
    texel_table = ctx.texture((256, 3), 1, inputs["texel_table"], dtype="f4")
    size = inputs["correction_size"]
    correction = (ctx.texture3d((size, size, size), 3, inputs["correction"], dtype="f4") if size
                  else ctx.texture3d((1, 1, 1), 3, np.zeros(3, np.float32).tobytes(), dtype="f4"))
    cells = ctx.texture((inputs["cell_count"], 3), 1, inputs["cells"], dtype="f4")
    for texture in (coefficients, thresholds, texel_table, correction, cells):
        import moderngl
        texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return coefficients, thresholds, texel_table, correction, cells


def _draw(ctx, program, inputs, bind):
    import moderngl

    framebuffer = ctx.simple_framebuffer((inputs["width"], inputs["height"]), components=4)
    framebuffer.use()
    bind()
    ctx.vertex_array(program, []).render(mode=moderngl.TRIANGLES, vertices=3)
    ctx.finish()
    data = np.frombuffer(framebuffer.read(components=4), dtype=np.uint8)
    return data.reshape(inputs["height"], inputs["width"], 4)


def run_glsl(ctx, vertex: str, fragment: str, inputs: dict) -> np.ndarray:
    """(H, W, 4) uint8: the GLSL shader's output, rows in the coefficient file's order."""
    program = ctx.program(vertex_shader=vertex, fragment_shader=fragment)
    textures = _textures(ctx, inputs)

    def bind():
        for unit, (name, texture) in enumerate(zip(
                ("coefficients", "thresholds", "texel_table", "drive_correction", "cells"),
                textures)):
            texture.use(location=unit)
            program[name].value = unit
        program["layers"].value = inputs["layers"]
        program["matrix_rows"].write(inputs["rows"].tobytes())
        program["drive_offset"].value = inputs["offset"]
        program["correction_size"].value = inputs["correction_size"]
        program["correction_domain"].value = inputs["correction_domain"]
        program["unreachable_dac"].value = inputs["unreachable"]

    return _draw(ctx, program, inputs, bind)


def run_spirv_cross_glsl(ctx, vertex: str, fragment: str, inputs: dict) -> np.ndarray:
    """(H, W, 4) uint8 from the HLSL shader turned into GLSL by spirv-cross (cbuffer as a UBO)."""
    program = ctx.program(vertex_shader=vertex, fragment_shader=fragment)
    textures = _textures(ctx, inputs)
    block = bytearray()
    block += inputs["rows"].tobytes()                                       # float4[48]
    block += np.array(list(inputs["offset"]) + [0.0], np.float32).tobytes()   # _VrDriveOffset
    block += np.array(list(inputs["correction_domain"]) + [0.0, 0.0], np.float32).tobytes()
    block += np.array([inputs["layers"], inputs["correction_size"], 0, 0], np.int32).tobytes()
    block += np.array(list(inputs["unreachable"]) + [0], np.int32).tobytes()
    buffer = ctx.buffer(bytes(block))
    names = {"coefficients": "_VrCoefficients", "thresholds": "_VrThresholds",
             "texel_table": "_VrTexelTable", "drive_correction": "_VrDriveCorrection",
             "cells": "_VrCells"}

    def bind():
        for unit, (key, texture) in enumerate(zip(names, textures)):
            texture.use(location=unit)
            sampler = next(name for name in program if names[key] in name)
            program[sampler].value = unit
        block_name = next(name for name in program if "VrLevel2" in name)
        program[block_name].binding = 0
        buffer.bind_to_uniform_block(0)

    return _draw(ctx, program, inputs, bind)


def main(argv=None) -> int:
    """Run in its own process (an EGL context in the pytest process upsets VTK's later ones):
    ``glsl_runner.py BUNDLE CUBE OUT.npz --mode glsl|spirv --fragment F --vertex V --lights A,B``.
    Exit status 3 and the reason on stderr when there is no OpenGL 4.3 context."""
    import argparse
    import sys

    parser = argparse.ArgumentParser()
    parser.add_argument("bundle", type=Path)
    parser.add_argument("cube")
    parser.add_argument("out")
    parser.add_argument("--mode", choices=("glsl", "spirv"), required=True)
    parser.add_argument("--fragment", type=Path, required=True)
    parser.add_argument("--vertex", type=Path, required=True)
    parser.add_argument("--lights", required=True)
    args = parser.parse_args(argv)
    context, why = gl_context()
    if context is None:
        print(why, file=sys.stderr)
        return 3
    run = run_glsl if args.mode == "glsl" else run_spirv_cross_glsl
    vertex, fragment = args.vertex.read_text(), args.fragment.read_text()
    results = {light: run(context, vertex, fragment, level2_inputs(args.bundle, args.cube, light))
               for light in args.lights.split(",")}
    np.savez(args.out, **results)
    context.release()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
