// Level-2 relight on the GPU: runtime/level2_relight.frag (GLSL 4.30) in GLSL ES 3.00, line for line.
//
// Per texel: drive = matrix * channels + offset; optional drive correction (3D table, trilinear);
// u = sqrt(clamp(drive, 0, 1)); DAC = number of the channel's 255 thresholds <= u (from a per-cell
// lower bound); texel = texel_table[channel][DAC]; alpha 0 where the light cannot carry the texel.
// Rendered into an RGBA8 (UNORM) texture of the cube's size: the texels the engine uploads.
import { FULLSCREEN_VERTEX, program, nearest } from './glutil.js';

const FRAGMENT = `#version 300 es
precision highp float;
precision highp int;
precision highp sampler2D;
precision highp sampler2DArray;
precision highp sampler3D;
#define MAX_LAYERS 16

uniform sampler2DArray coefficients;   // RGBA16F, layers = ceil(C / 4), from coefficients.bin
uniform sampler2D thresholds;          // R32F, 255 x 3 (row = channel), display_inverse.json
uniform sampler2D cells;               // R32F, cells x 3: lower bound of the DAC per cell of u
uniform sampler2D texel_table;         // R32F, 256 x 3 (row = channel), values 0..255
uniform sampler3D drive_correction;    // RGB32F, size^3, display_drive_correction.bin
uniform int layers;
uniform vec4 matrix_rows[3 * MAX_LAYERS]; // [3 * layer + output channel]: 4 channels' weights
uniform vec3 drive_offset;
uniform int correction_size;           // 0: no correction table
uniform vec2 correction_domain;
uniform ivec3 unreachable_dac;

out vec4 texel;

vec3 corrected(vec3 drive) {
  float n1 = float(correction_size - 1);
  vec3 position = clamp((drive - correction_domain.x) / (correction_domain.y - correction_domain.x),
                        0.0, 1.0) * n1;
  ivec3 base = min(ivec3(floor(position)), ivec3(correction_size - 2));
  vec3 f = position - vec3(base);
  vec3 result = vec3(0.0);
  for (int db = 0; db < 2; ++db)
    for (int dg = 0; dg < 2; ++dg)
      for (int dr = 0; dr < 2; ++dr) {
        float w = (db == 1 ? f.z : 1.0 - f.z) * (dg == 1 ? f.y : 1.0 - f.y)
                * (dr == 1 ? f.x : 1.0 - f.x);
        result += w * texelFetch(drive_correction, base + ivec3(dr, dg, db), 0).rgb;
      }
  return result;
}

int dac_level(int channel, float u) {
  int cell_count = textureSize(cells, 0).x;
  int level = int(texelFetch(cells, ivec2(int(u * float(cell_count - 1)), channel), 0).r);
  while (level < 255 && texelFetch(thresholds, ivec2(level, channel), 0).r <= u) ++level;
  return level;
}

void main() {
  ivec2 xy = ivec2(gl_FragCoord.xy);
  vec3 drive = drive_offset;
  for (int layer = 0; layer < layers; ++layer) {
    vec4 c = texelFetch(coefficients, ivec3(xy, layer), 0);
    drive += vec3(dot(matrix_rows[3 * layer], c), dot(matrix_rows[3 * layer + 1], c),
                  dot(matrix_rows[3 * layer + 2], c));
  }
  if (correction_size > 0) drive = corrected(drive);
  vec3 u = sqrt(clamp(drive, 0.0, 1.0));
  ivec3 dac = ivec3(dac_level(0, u.r), dac_level(1, u.g), dac_level(2, u.b));
  vec3 value = vec3(texelFetch(texel_table, ivec2(dac.r, 0), 0).r,
                    texelFetch(texel_table, ivec2(dac.g, 1), 0).r,
                    texelFetch(texel_table, ivec2(dac.b, 2), 0).r);
  bool unreachable = any(greaterThanEqual(dac, unreachable_dac));
  texel = vec4(value / 255.0, unreachable ? 0.0 : 1.0);
}`;

async function fetchOk(url) {
  const response = await fetch(url, { cache: 'no-store' });
  if (!response.ok) throw new Error(`${url}: ${response.status} ${response.statusText}`);
  return response;
}

function floatTexture(gl, width, height, values) {
  const texture = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, texture);
  nearest(gl, gl.TEXTURE_2D);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.R32F, width, height, 0, gl.RED, gl.FLOAT, new Float32Array(values));
  return texture;
}

export class Level2Relight {
  // gl: a WebGL 2 context; base: URL of the bundle's files (".../bundle/"); cube: its level-2 cube name.
  constructor(gl, base, cube) {
    this.gl = gl;
    this.base = base;
    this.cube = cube;
    this.textures = new Map();  // light id -> RGBA8 texture of the relit cube
  }

  async load() {
    const gl = this.gl;
    const folder = `${this.base}level2/${this.cube}/`;
    const [header, records, inverse] = await Promise.all([
      fetchOk(`${folder}coefficients.json`).then((r) => r.json()),
      fetchOk(`${folder}lights.json`).then((r) => r.json()),
      fetchOk(`${this.base}display_inverse.json`).then((r) => r.json()),
    ]);
    this.width = header.width;
    this.height = header.height;
    this.channels = header.channels;
    this.layers = header.layers;
    if (this.layers > 16) throw new Error(`the cube has ${this.layers} layers; the shader takes 16`);
    const planes = new Uint16Array(await (await fetchOk(`${folder}coefficients.bin`)).arrayBuffer());
    const expected = this.layers * this.height * this.width * 4;
    if (planes.length !== expected) {
      throw new Error(`coefficients.bin holds ${planes.length} values where its header promises ${expected}`);
    }
    this.records = new Map(records.lights.map((record) => [record.id, record]));

    this.coefficients = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D_ARRAY, this.coefficients);
    nearest(gl, gl.TEXTURE_2D_ARRAY);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA16F, this.width, this.height, this.layers, 0,
      gl.RGBA, gl.HALF_FLOAT, planes);

    const cellCount = inverse.cells.length / 3;
    this.thresholds = floatTexture(gl, 255, 3, inverse.thresholds);
    this.cells = floatTexture(gl, cellCount, 3, inverse.cells);
    const correction = inverse.correction || { size: 0 };
    this.correctionSize = correction.size || 0;
    this.correctionDomain = correction.domain || [0, 1];
    this.correction = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_3D, this.correction);
    nearest(gl, gl.TEXTURE_3D);
    if (this.correctionSize > 0) {
      const table = new Float32Array(await (await fetchOk(`${this.base}${correction.file}`)).arrayBuffer());
      const n = this.correctionSize;
      if (table.length !== n * n * n * 3) throw new Error(`${correction.file} does not hold ${n}^3 x 3 floats`);
      gl.texImage3D(gl.TEXTURE_3D, 0, gl.RGB32F, n, n, n, 0, gl.RGB, gl.FLOAT, table);
    } else {
      gl.texImage3D(gl.TEXTURE_3D, 0, gl.RGB32F, 1, 1, 1, 0, gl.RGB, gl.FLOAT, new Float32Array(3));
    }
    this.pass = program(gl, FULLSCREEN_VERTEX, FRAGMENT);
    this.vao = gl.createVertexArray();
    this.framebuffer = gl.createFramebuffer();
  }

  lightIds() { return [...this.records.keys()]; }

  // The relit texture for light `id` (made on first use, then kept).
  texture(id) {
    if (!this.textures.has(id)) this.textures.set(id, this.render(id));
    return this.textures.get(id);
  }

  render(id) {
    const gl = this.gl;
    const record = this.records.get(id);
    if (!record) throw new Error(`the bundle's level-2 cube has no light ${id}`);
    const target = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, target);
    nearest(gl, gl.TEXTURE_2D);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, this.width, this.height, 0, gl.RGBA, gl.UNSIGNED_BYTE, null);
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.framebuffer);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
    gl.viewport(0, 0, this.width, this.height);
    gl.disable(gl.DEPTH_TEST);
    gl.disable(gl.BLEND);
    gl.disable(gl.DITHER);
    gl.disable(gl.SCISSOR_TEST);
    const { prog, uniforms } = this.pass;
    gl.useProgram(prog);
    const units = [[gl.TEXTURE_2D_ARRAY, this.coefficients, 'coefficients'],
      [gl.TEXTURE_2D, this.thresholds, 'thresholds'], [gl.TEXTURE_2D, this.cells, 'cells'],
      [gl.TEXTURE_2D, null, 'texel_table'], [gl.TEXTURE_3D, this.correction, 'drive_correction']];
    const table = floatTexture(gl, 256, 3, record.texel_table);
    units[3][1] = table;
    units.forEach(([kind, texture, name], unit) => {
      gl.activeTexture(gl.TEXTURE0 + unit);
      gl.bindTexture(kind, texture);
      gl.uniform1i(uniforms[name], unit);
    });
    const rows = new Float32Array(3 * 16 * 4);
    for (let layer = 0; layer < this.layers; layer++) {
      for (let out = 0; out < 3; out++) {
        for (let k = 0; k < 4; k++) {
          const channel = 4 * layer + k;
          rows[(3 * layer + out) * 4 + k] = channel < this.channels ? record.matrix[out * this.channels + channel] : 0;
        }
      }
    }
    gl.uniform4fv(uniforms.matrix_rows, rows);
    gl.uniform1i(uniforms.layers, this.layers);
    gl.uniform3fv(uniforms.drive_offset, new Float32Array(record.offset));
    gl.uniform1i(uniforms.correction_size, this.correctionSize);
    gl.uniform2fv(uniforms.correction_domain, new Float32Array(this.correctionDomain));
    gl.uniform3iv(uniforms.unreachable_dac, new Int32Array(record.unreachable_dac));
    gl.bindVertexArray(this.vao);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    gl.bindVertexArray(null);
    gl.deleteTexture(table);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    return target;
  }

  // The relit texels of light `id`, RGBA, rows from the cube's first (top) row.
  read(id) {
    const gl = this.gl;
    const texture = this.texture(id);
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.framebuffer);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, texture, 0);
    const pixels = new Uint8Array(this.width * this.height * 4);
    gl.readPixels(0, 0, this.width, this.height, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    return pixels;
  }
}
