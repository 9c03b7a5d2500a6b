// Calibration patches and the centring target, written straight into the XR framebuffer.
//
// A patch is written with gl.clear inside a scissor rectangle: the clear colour v/255 becomes the
// 8-bit value v exactly in the RGBA8 framebuffer (no shader, no blending, no dithering, no
// tone mapping, no colour conversion). Each view's viewport is one eye's field; the patch fills
// it (window 1) or a centred rectangle of its aspect ratio, sides sqrt(window) of the field's,
// on the surround; the other eye is black when `eye` names one.
import { FULLSCREEN_VERTEX, program } from './glutil.js';

// Black field; white rings at 10, 20, 30 and 40 % of the field's smaller side in radius, 2-pixel
// lines, and a cross through the centre.
const TARGET_FRAGMENT = `#version 300 es
precision highp float;
uniform vec4 field;   // x, y, width, height of the eye's viewport (framebuffer pixels)
out vec4 colour;
void main() {
  vec2 centre = field.xy + 0.5 * field.zw;
  vec2 d = gl_FragCoord.xy - centre;
  float side = min(field.z, field.w);
  float r = length(d);
  bool ring = false;
  for (int i = 1; i <= 4; ++i) ring = ring || abs(r - 0.1 * float(i) * side) < 1.0;
  bool cross = abs(d.x) < 1.0 || abs(d.y) < 1.0;
  colour = (ring || cross) ? vec4(1.0) : vec4(0.0, 0.0, 0.0, 1.0);
}`;

export const SHOW_FIELDS = ['cmd', 'id', 'rgb', 'window', 'surround', 'eye'];
export const TARGET_FIELDS = ['cmd', 'id', 'eye'];

function isDac(value) {
  return Array.isArray(value) && value.length === 3 &&
    value.every((v) => Number.isInteger(v) && v >= 0 && v <= 255);
}

// The request's patch, or {error} naming what is wrong (the patch protocol's wording).
export function parseRequest(message) {
  const known = message.cmd === 'show' ? SHOW_FIELDS : TARGET_FIELDS;
  for (const key of Object.keys(message)) {
    if (!known.includes(key)) {
      return { error: `unknown field '${key}' in ${message.cmd}; this server knows ${known.join(', ')}` };
    }
  }
  const eye = message.eye === undefined ? 'both' : message.eye;
  if (!['both', 'left', 'right'].includes(eye)) {
    return { error: `eye ${JSON.stringify(message.eye)} must be "left", "right" or "both"` };
  }
  if (message.cmd === 'target') return { kind: 'target', eye };
  if (!isDac(message.rgb)) return { error: `rgb ${JSON.stringify(message.rgb)} must be three integers 0..255` };
  const window = message.window === undefined ? 1 : message.window;
  if (typeof window !== 'number' || !Number.isFinite(window) || !(window > 0 && window <= 1)) {
    return { error: `window ${JSON.stringify(message.window)} must be a number in (0, 1]` };
  }
  const surround = message.surround === undefined ? [0, 0, 0] : message.surround;
  if (!isDac(surround)) {
    return { error: `surround ${JSON.stringify(message.surround)} must be three integers 0..255` };
  }
  return { kind: 'patch', rgb: message.rgb, window, surround, eye };
}

// The window's rectangle in a viewport: centred, sides round(sqrt(window) * side), at least 1 pixel.
export function windowRect(viewport, window) {
  const scale = Math.sqrt(window);
  const width = Math.max(1, Math.round(viewport.width * scale));
  const height = Math.max(1, Math.round(viewport.height * scale));
  return {
    x: viewport.x + Math.round((viewport.width - width) / 2),
    y: viewport.y + Math.round((viewport.height - height) / 2),
    width, height,
  };
}

export class PatchPainter {
  constructor(gl) {
    this.gl = gl;
    this.target = program(gl, FULLSCREEN_VERTEX, TARGET_FRAGMENT);
    this.vao = gl.createVertexArray();
  }

  clearRect(rect, rgb) {
    const gl = this.gl;
    gl.scissor(rect.x, rect.y, rect.width, rect.height);
    gl.clearColor(rgb[0] / 255, rgb[1] / 255, rgb[2] / 255, 1);
    gl.clear(gl.COLOR_BUFFER_BIT);
  }

  // Draw `shown` (a parsed patch or target) into one view: `eye` is the XRView's eye.
  draw(shown, viewport, eye) {
    const gl = this.gl;
    gl.disable(gl.DITHER);
    gl.disable(gl.BLEND);
    gl.disable(gl.DEPTH_TEST);
    gl.colorMask(true, true, true, true);
    gl.enable(gl.SCISSOR_TEST);
    gl.viewport(viewport.x, viewport.y, viewport.width, viewport.height);
    const lit = shown.eye === 'both' || shown.eye === eye;
    if (!lit) {
      this.clearRect(viewport, [0, 0, 0]);
    } else if (shown.kind === 'target') {
      gl.scissor(viewport.x, viewport.y, viewport.width, viewport.height);
      gl.useProgram(this.target.prog);
      gl.uniform4f(this.target.uniforms.field, viewport.x, viewport.y, viewport.width, viewport.height);
      gl.bindVertexArray(this.vao);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      gl.bindVertexArray(null);
    } else if (shown.window >= 1) {
      this.clearRect(viewport, shown.rgb);
    } else {
      this.clearRect(viewport, shown.surround);
      this.clearRect(windowRect(viewport, shown.window), shown.rgb);
    }
    gl.disable(gl.SCISSOR_TEST);
  }
}

// What a view holds now, read back from the bound framebuffer: each distinct colour with its pixel
// count and bounding box [x0, y0, x1, y1] (inclusive, relative to the viewport).
export function summarise(gl, viewport) {
  const { x, y, width, height } = viewport;
  const pixels = new Uint8Array(width * height * 4);
  gl.readPixels(x, y, width, height, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
  const colours = new Map();
  for (let row = 0; row < height; row++) {
    for (let column = 0; column < width; column++) {
      const i = 4 * (row * width + column);
      const key = (pixels[i] << 16) | (pixels[i + 1] << 8) | pixels[i + 2];
      let entry = colours.get(key);
      if (!entry) {
        entry = { rgb: [pixels[i], pixels[i + 1], pixels[i + 2]], count: 0, box: [column, row, column, row] };
        colours.set(key, entry);
      }
      entry.count++;
      const box = entry.box;
      if (column < box[0]) box[0] = column;
      if (row < box[1]) box[1] = row;
      if (column > box[2]) box[2] = column;
      if (row > box[3]) box[3] = row;
    }
  }
  return [...colours.values()];
}
