// The lightbooth: grey box open at the front, a lamp under the ceiling, the ColorChecker board and
// the Ishihara plate against the back wall, and two buttons under the opening (source, level).
//
// The board, plate and walls sample one atlas texture (the bundle's `lightbooth` cube: level 1 its
// preview.png, the authored sRGB under D65; level 2 the texture re-authored on the GPU) texel for
// texel (nearest, no mipmaps) and are rendered as the engine of design §2 renders them:
// encode(decode(texel) * decode(light)), the light being lights.json's rgb8. The board and the plate
// are unlit (exactly that value); the walls are shaded per face only so that the box reads as a
// box. The lamp shows the light colour rgb8 itself. Units: metres; y up; the viewer looks along -z.
import { program, nearest, mat4, sub, dot } from './glutil.js';

const VERTEX = `#version 300 es
in vec3 position;
in vec2 uv;
uniform mat4 projection;
uniform mat4 view;
out vec2 v_uv;
void main() {
  v_uv = uv;
  gl_Position = projection * view * vec4(position, 1.0);
}`;

const FRAGMENT = `#version 300 es
precision highp float;
uniform sampler2D albedo;
uniform vec3 light_rgb8;  // the engine light colour, lights.json rgb8
uniform float shade;      // 1 on the board and plate
uniform int mode;         // 0: surface x light (engine), 1: the colour itself (lamp), 2: the texture itself (UI)
uniform vec3 colour_rgb8;
in vec2 v_uv;
out vec4 colour;
vec3 decode(vec3 c) { return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(0.04045, c)); }
vec3 encode(vec3 l) { return mix(l * 12.92, 1.055 * pow(l, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, l)); }
void main() {
  if (mode == 1) { colour = vec4(colour_rgb8 / 255.0, 1.0); return; }
  vec4 t = texture(albedo, v_uv);
  if (mode == 2) { colour = vec4(t.rgb, 1.0); return; }
  vec3 linear = decode(t.rgb) * decode(light_rgb8 / 255.0) * shade;
  colour = vec4(encode(clamp(linear, 0.0, 1.0)), 1.0);
}`;

export const BOOTH = { width: 0.8, height: 0.5, depth: 0.5, floorY: 1.15, frontZ: -0.55 };
export const BACKGROUND = [0.16, 0.16, 0.17];
const BOARD_WIDTH = 0.34;
const PLATE_SIZE = 0.22;

// A quad from its centre, right and up half-vectors; uv (0,0) bottom left.
function quad(centre, right, up) {
  const corner = (sx, sy) => [0, 1, 2].map((i) => centre[i] + sx * right[i] + sy * up[i]);
  const p = [corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, -1), corner(1, 1), corner(-1, 1)];
  const uv = [[0, 0], [1, 0], [1, 1], [0, 0], [1, 1], [0, 1]];
  return { positions: p.flat(), uvs: uv.flat(), centre, right, up };
}

export class Booth {
  constructor(gl, atlas) {
    this.gl = gl;
    this.atlas = atlas;  // {board:[x,y,w,h], plate:[...], wall:[...], size:[W,H]}, rows from the top
    this.pass = program(gl, VERTEX, FRAGMENT);
    this.items = [];
    this.buttons = [];
    const { width: W, height: H, depth: D, floorY: y0, frontZ: zf } = BOOTH;
    const zb = zf - D;
    const cx = 0;
    const zc = zf - D / 2;
    // walls (inner faces), shaded per face
    this.addSurface(quad([cx, y0, zc], [W / 2, 0, 0], [0, 0, -D / 2]), 'wall', 0.9);          // floor
    this.addSurface(quad([cx, y0 + H, zc], [W / 2, 0, 0], [0, 0, D / 2]), 'wall', 0.55);      // ceiling
    this.addSurface(quad([cx, y0 + H / 2, zb], [W / 2, 0, 0], [0, H / 2, 0]), 'wall', 1.0);   // back
    this.addSurface(quad([cx - W / 2, y0 + H / 2, zc], [0, 0, -D / 2], [0, H / 2, 0]), 'wall', 0.75);
    this.addSurface(quad([cx + W / 2, y0 + H / 2, zc], [0, 0, D / 2], [0, H / 2, 0]), 'wall', 0.75);
    // board and plate, unlit, 2 mm in front of the back wall
    const [, , bw, bh] = atlas.board;
    const boardH = BOARD_WIDTH * bh / bw;
    this.addSurface(quad([-0.14, y0 + 0.06 + boardH / 2, zb + 0.002], [BOARD_WIDTH / 2, 0, 0], [0, boardH / 2, 0]),
      'board', 1.0);
    this.addSurface(quad([0.22, y0 + 0.06 + PLATE_SIZE / 2, zb + 0.002], [PLATE_SIZE / 2, 0, 0], [0, PLATE_SIZE / 2, 0]),
      'plate', 1.0);
    // the lamp: a bar under the ceiling; its front face and underside show the light colour
    const lampY = y0 + H - 0.0125;
    const lampZ = zc + D * 0.15;
    this.lamp = quad([0, lampY, lampZ + D * 0.2], [W * 0.35, 0, 0], [0, 0.0075, 0]);
    this.items.push({ geometry: this.lamp, kind: 'lamp' });
    this.items.push({ geometry: quad([0, lampY - 0.0075, lampZ], [W * 0.35, 0, 0], [0, 0, D * 0.2]), kind: 'lamp' });
    // the buttons, under the opening, facing the viewer
    this.buttons.push(this.addButton('source', quad([-0.2, y0 - 0.08, zf + 0.02], [0.17, 0, 0], [0, 0.045, 0])));
    this.buttons.push(this.addButton('level', quad([0.2, y0 - 0.08, zf + 0.02], [0.17, 0, 0], [0, 0.045, 0])));
    this.upload();
  }

  atlasUv(region, geometry) {
    const [X, Y, w, h] = this.atlas[region];
    const [Wt, Ht] = this.atlas.size;
    const uvs = [];
    for (let i = 0; i < geometry.uvs.length; i += 2) {
      let u = geometry.uvs[i];
      let v = geometry.uvs[i + 1];
      if (region === 'wall') { u = 0.5; v = 0.5; }  // one flat material: its centre texel
      // texture row 0 is the cube's top row; inset half a texel so edges stay inside the region
      uvs.push((X + 0.5 + u * (w - 1)) / Wt, (Y + 0.5 + (1 - v) * (h - 1)) / Ht);
    }
    return uvs;
  }

  addSurface(geometry, region, shade) {
    this.items.push({ geometry: { ...geometry, uvs: this.atlasUv(region, geometry) }, kind: 'surface', shade });
  }

  addButton(name, geometry) {
    const canvas = document.createElement('canvas');
    canvas.width = 512;
    canvas.height = 136;
    const texture = this.gl.createTexture();
    const item = { geometry: { ...geometry, uvs: geometry.uvs.map((v, i) => (i % 2 ? 1 - v : v)) },
      kind: 'button', name, canvas, texture, text: null };
    this.items.push(item);
    return item;
  }

  label(name, text) {
    const button = this.buttons.find((b) => b.name === name);
    if (!button || button.text === text) return;
    button.text = text;
    const context = button.canvas.getContext('2d');
    context.fillStyle = '#202124';
    context.fillRect(0, 0, 512, 136);
    context.strokeStyle = '#9aa0a6';
    context.lineWidth = 6;
    context.strokeRect(3, 3, 506, 130);
    context.fillStyle = '#f1f3f4';
    context.font = '44px sans-serif';
    context.textAlign = 'center';
    context.textBaseline = 'middle';
    context.fillText(text, 256, 68, 490);
    const gl = this.gl;
    gl.bindTexture(gl.TEXTURE_2D, button.texture);
    gl.pixelStorei(gl.UNPACK_FLIP_Y_WEBGL, false);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, gl.RGBA, gl.UNSIGNED_BYTE, button.canvas);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
  }

  upload() {
    const gl = this.gl;
    const positions = [];
    const uvs = [];
    for (const item of this.items) {
      item.first = positions.length / 3;
      positions.push(...item.geometry.positions);
      uvs.push(...item.geometry.uvs);
    }
    this.vao = gl.createVertexArray();
    gl.bindVertexArray(this.vao);
    const attribute = (name, data, size) => {
      const buffer = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(data), gl.STATIC_DRAW);
      const location = gl.getAttribLocation(this.pass.prog, name);
      gl.enableVertexAttribArray(location);
      gl.vertexAttribPointer(location, size, gl.FLOAT, false, 0, 0);
    };
    attribute('position', positions, 3);
    attribute('uv', uvs, 2);
    gl.bindVertexArray(null);
  }

  // Draw into the bound framebuffer's `viewport` with these matrices; `albedo` is the atlas texture.
  draw(viewport, projection, view, albedo, lightRgb8) {
    const gl = this.gl;
    const { prog, uniforms } = this.pass;
    gl.viewport(viewport.x, viewport.y, viewport.width, viewport.height);
    gl.enable(gl.SCISSOR_TEST);
    gl.scissor(viewport.x, viewport.y, viewport.width, viewport.height);
    gl.clearColor(BACKGROUND[0], BACKGROUND[1], BACKGROUND[2], 1);
    gl.clearDepth(1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.disable(gl.SCISSOR_TEST);
    gl.enable(gl.DEPTH_TEST);
    gl.disable(gl.BLEND);
    gl.disable(gl.DITHER);
    gl.disable(gl.CULL_FACE);
    gl.useProgram(prog);
    gl.uniformMatrix4fv(uniforms.projection, false, projection);
    gl.uniformMatrix4fv(uniforms.view, false, view);
    gl.uniform3f(uniforms.light_rgb8, lightRgb8[0], lightRgb8[1], lightRgb8[2]);
    gl.uniform3f(uniforms.colour_rgb8, lightRgb8[0], lightRgb8[1], lightRgb8[2]);
    gl.uniform1i(uniforms.albedo, 0);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindVertexArray(this.vao);
    for (const item of this.items) {
      if (item.kind === 'surface') {
        gl.bindTexture(gl.TEXTURE_2D, albedo);
        gl.uniform1i(uniforms.mode, 0);
        gl.uniform1f(uniforms.shade, item.shade);
      } else if (item.kind === 'lamp') {
        gl.uniform1i(uniforms.mode, 1);
      } else {
        gl.bindTexture(gl.TEXTURE_2D, item.texture);
        gl.uniform1i(uniforms.mode, 2);
      }
      gl.drawArrays(gl.TRIANGLES, item.first, 6);
    }
    gl.bindVertexArray(null);
    gl.disable(gl.DEPTH_TEST);
  }

  // The button a ray (origin, unit direction, world space) hits first, or null.
  pick(origin, direction) {
    let best = null;
    for (const button of this.buttons) {
      const { centre, right, up } = button.geometry;
      const normal = [0, 0, 1];
      const denominator = dot(direction, normal);
      if (Math.abs(denominator) < 1e-6) continue;
      const t = dot(sub(centre, origin), normal) / denominator;
      if (t <= 0) continue;
      const hit = [0, 1, 2].map((i) => origin[i] + t * direction[i]);
      const offset = sub(hit, centre);
      const u = dot(offset, right) / dot(right, right);
      const v = dot(offset, up) / dot(up, up);
      if (Math.abs(u) <= 1 && Math.abs(v) <= 1 && (!best || t < best.t)) best = { name: button.name, t };
    }
    return best && best.name;
  }

  // Where the lamp's front face's centre lands in a viewport (pixels from its bottom left).
  lampPixel(viewport, projection, view) {
    const clip = mat4.transform(mat4.multiply(projection, view), this.lamp.centre);
    return [viewport.x + Math.floor((clip[0] / clip[3] * 0.5 + 0.5) * viewport.width),
      viewport.y + Math.floor((clip[1] / clip[3] * 0.5 + 0.5) * viewport.height)];
  }
}

export function atlasTextureFromImage(gl, bitmap) {
  const texture = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, texture);
  nearest(gl, gl.TEXTURE_2D);
  gl.pixelStorei(gl.UNPACK_COLORSPACE_CONVERSION_WEBGL, gl.NONE);
  gl.pixelStorei(gl.UNPACK_PREMULTIPLY_ALPHA_WEBGL, false);
  gl.pixelStorei(gl.UNPACK_FLIP_Y_WEBGL, false);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, gl.RGBA, gl.UNSIGNED_BYTE, bitmap);
  return texture;
}

// The window's camera: in front of the opening, the whole booth and its buttons in view.
export function windowCamera(aspect) {
  const { height: H, depth: D, floorY: y0, frontZ: zf, width: W } = BOOTH;
  const fovy = 40 * Math.PI / 180;
  const half = Math.tan(fovy / 2);
  const centreZ = zf - D / 2;
  const distance = Math.max(D * 3, D / 2 + 0.65 * W / (half * aspect));
  const eye = [0, y0 + H * 0.55, centreZ + distance];
  return {
    projection: mat4.perspective(fovy, aspect, 0.05, 20),
    view: mat4.lookAt(eye, [0, y0 + H * 0.32, centreZ], [0, 1, 0]),
    eye,
  };
}
