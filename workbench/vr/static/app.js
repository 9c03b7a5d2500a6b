// The VR colour workbench's headset page: patches for the calibration, the colour-managed lightbooth.
//
// Connects to the workbench over a WebSocket (vr-workbench-webxr/1, see workbench/vr/server.py),
// shows the lightbooth from the bundle in the window and, after "Enter VR", in an immersive WebXR
// session; while a measurement uses the page it shows each requested patch in the XR frames and
// acknowledges a request only once the frame that shows it has been submitted (on the next XR
// animation frame).
import { base64, mat4, normalise, sub } from './glutil.js';
import { Level2Relight } from './relight.js';
import { Booth, atlasTextureFromImage, windowCamera } from './booth.js';
import { PatchPainter, parseRequest, summarise } from './patch.js';

const PAGE_PROTOCOL = 'vr-workbench-webxr/1';
const params = new URLSearchParams(location.search);
const base = location.pathname.slice(0, location.pathname.lastIndexOf('/') + 1);
const $ = (id) => document.getElementById(id);

const state = {
  socket: null, refused: null, connection: null, patchClient: null,
  scene: { source: null, level: 1 }, bundle: null, lights: new Map(),
  session: null, refSpace: null, frame: 0, pending: null, shown: null, readback: params.get('readback') === '1',
  eyes: [], emulated: null,
};

const canvas = $('view');
const gl = canvas.getContext('webgl2', {
  antialias: false, alpha: false, depth: true, stencil: false, premultipliedAlpha: false,
  preserveDrawingBuffer: false, xrCompatible: true,
});
if (!gl) problem('this browser gives no WebGL 2 context; the page needs one');
gl.disable(gl.DITHER);
const painter = gl && new PatchPainter(gl);
let relight = null;
let booth = null;
let level1Texture = null;

function problem(text) {
  const element = $('problem');
  element.hidden = !text;
  element.textContent = text || '';
}

function log(text) { console.log(`[vr-workbench] ${text}`); }

// ----------------------------------------------------------------------------- bundle and scene
async function loadScene() {
  const response = await fetch(`${base}scene.json`, { cache: 'no-store' });
  const info = await response.json();
  state.bundle = info.bundle;
  state.scene = info.scene;
  if (!info.bundle) {
    $('device').textContent = 'No bundle: the server was started without --bundle, so no lightbooth.';
    return;
  }
  $('device').textContent = `Bundle for ${info.bundle.device || 'this headset'}`;
  for (const light of info.bundle.lights) state.lights.set(light.id, light);
  const select = $('source');
  select.replaceChildren(...info.bundle.lights.map((light) => new Option(light.name, light.id)));
  relight = new Level2Relight(gl, `${base}bundle/`, info.bundle.cube);
  await relight.load();
  const preview = await fetch(`${base}bundle/level2/${info.bundle.cube}/preview.png`, { cache: 'no-store' });
  const bitmap = await createImageBitmap(await preview.blob(),
    { colorSpaceConversion: 'none', premultiplyAlpha: 'none', imageOrientation: 'none' });
  level1Texture = atlasTextureFromImage(gl, bitmap);
  booth = new Booth(gl, info.bundle.atlas);
  $('scene-controls').disabled = false;
  applyScene(state.scene, false);
}

function applyScene(scene, fromUser) {
  if (!state.bundle) return;
  if (scene.source && state.lights.has(scene.source)) state.scene.source = scene.source;
  if (scene.level === 1 || scene.level === 2) state.scene.level = scene.level;
  const light = state.lights.get(state.scene.source);
  $('source').value = state.scene.source;
  for (const radio of document.querySelectorAll('input[name=level]')) radio.checked = Number(radio.value) === state.scene.level;
  if (booth) {
    const index = state.bundle.lights.findIndex((l) => l.id === state.scene.source) + 1;
    booth.label('source', `${light.name} (${index}/${state.bundle.lights.length}) ▶`);
    booth.label('level', `level ${state.scene.level}  ⇄  ${3 - state.scene.level}`);
    if (state.scene.level === 2) relight.texture(state.scene.source);  // relit now, not in a frame
  }
  if (fromUser) send({ event: 'scene', source: state.scene.source, level: state.scene.level });
}

function nextSource() {
  const ids = state.bundle.lights.map((l) => l.id);
  applyScene({ source: ids[(ids.indexOf(state.scene.source) + 1) % ids.length] }, true);
}

function toggleLevel() { applyScene({ level: 3 - state.scene.level }, true); }

function drawScene(viewport, projection, view) {
  if (!booth) {
    gl.viewport(viewport.x, viewport.y, viewport.width, viewport.height);
    gl.enable(gl.SCISSOR_TEST);
    gl.scissor(viewport.x, viewport.y, viewport.width, viewport.height);
    gl.clearColor(0.16, 0.16, 0.17, 1);
    gl.clear(gl.COLOR_BUFFER_BIT);
    gl.disable(gl.SCISSOR_TEST);
    return;
  }
  const albedo = state.scene.level === 2 ? relight.texture(state.scene.source) : level1Texture;
  booth.draw(viewport, projection, view, albedo, state.lights.get(state.scene.source).rgb8);
}

// ----------------------------------------------------------------------------- the WebSocket
function send(message) {
  if (state.socket && state.socket.readyState === WebSocket.OPEN) state.socket.send(JSON.stringify(message));
}

function connect() {
  const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
  const socket = new WebSocket(`${scheme}//${location.host}${base}ws`);
  state.socket = socket;
  socket.onopen = () => {
    send({ event: 'hello', page: PAGE_PROTOCOL, user_agent: navigator.userAgent,
      xr: navigator.xr ? 'webxr' : 'none', emulated: state.emulated });
    if (state.session) reportState();
  };
  socket.onmessage = (event) => onMessage(JSON.parse(event.data));
  socket.onclose = () => {
    if (state.socket !== socket) return;
    state.socket = null;
    if (state.pending) state.pending = null;
    if (state.refused) return;
    $('connection').textContent = 'The workbench is not reachable; trying again every 2 s…';
    setTimeout(connect, 2000);
  };
}

function onMessage(message) {
  if (message.event === 'welcome') {
    state.connection = message.connection;
    $('connection').textContent = `Connected to ${message.server}.`;
    problem('');
    state.patchClient = message.patches;
    showPatchState();
    applyScene(message.scene || {}, false);
    reportState();
  } else if (message.event === 'refused') {
    state.refused = message.reason;
    $('connection').textContent = 'Refused by the workbench.';
    problem(message.reason);
  } else if (message.event === 'scene') {
    applyScene(message, false);
  } else if (message.event === 'patches') {
    state.patchClient = message.client;
    if (!message.client) { state.shown = null; state.pending = null; }
    showPatchState();
  } else if (message.cmd === 'show' || message.cmd === 'target') {
    onRequest(message);
  } else if (message.cmd !== undefined) {
    send({ ok: false, id: message.id ?? null, error: `unknown cmd ${JSON.stringify(message.cmd)}; this page knows show, target` });
  }
}

function showPatchState() {
  const element = $('patches');
  element.hidden = !state.patchClient;
  element.textContent = state.patchClient
    ? (state.session ? `Showing calibration patches for ${state.patchClient}.`
      : `A calibration (${state.patchClient}) is waiting: press Enter VR and keep the headset on the instrument.`)
    : '';
}

function onRequest(message) {
  const parsed = parseRequest(message);
  if (parsed.error) { send({ ok: false, id: message.id, error: parsed.error }); return; }
  if (!state.session) {
    send({ ok: false, id: message.id, error: 'the page is not in VR (no immersive session): press Enter VR on the page' });
    return;
  }
  if (parsed.eye !== 'both' && !state.eyes.includes(parsed.eye)) {
    send({ ok: false, id: message.id,
      error: `this device shows ${state.eyes.length} view(s) (eyes ${state.eyes.join(', ')}); it cannot show a patch to the ${parsed.eye} eye alone` });
    return;
  }
  if (state.pending) send({ ok: false, id: state.pending.id, error: 'superseded by a newer request before it was shown' });
  state.pending = { id: message.id, spec: parsed, received: performance.now(), drawnFrame: null };
}

// ----------------------------------------------------------------------------- WebXR
async function enterVR() {
  if (state.session) { state.session.end(); return; }
  try {
    const session = await navigator.xr.requestSession('immersive-vr', { optionalFeatures: ['local-floor'] });
    await gl.makeXRCompatible();
    const layer = new XRWebGLLayer(session, gl, { antialias: false, alpha: false, depth: true, framebufferScaleFactor: 1.0 });
    if ('fixedFoveation' in layer) layer.fixedFoveation = 0;  // full resolution everywhere
    session.updateRenderState({ baseLayer: layer, depthNear: 0.05, depthFar: 50 });
    let space;
    try {
      space = await session.requestReferenceSpace('local-floor');
    } catch (error) {
      // 'local': the origin at the head; lower the world so the booth stands at the same height
      space = (await session.requestReferenceSpace('local')).getOffsetReferenceSpace(
        new XRRigidTransform({ x: 0, y: 1.6, z: 0 }));
    }
    state.session = session;
    document.body.classList.add('immersive');  // the mirror of both eyes takes the whole window
    state.refSpace = space;
    state.eyes = [];
    session.addEventListener('end', () => {
      state.session = null;
      document.body.classList.remove('immersive');
      state.eyes = [];
      if (state.pending) { send({ ok: false, id: state.pending.id, error: 'the immersive session ended before the patch was shown' }); state.pending = null; }
      $('enter-vr').textContent = 'Enter VR';
      showPatchState();
      reportState();
      requestAnimationFrame(onWindowFrame);
    });
    session.addEventListener('select', onSelect);
    $('enter-vr').textContent = 'Exit VR';
    showPatchState();
    session.requestAnimationFrame(onXRFrame);
  } catch (error) {
    problem(`Cannot start VR: ${error.message}`);
  }
}

function reportState() {
  const layer = state.session && state.session.renderState.baseLayer;
  send({
    event: 'state', immersive: Boolean(state.session), views: state.eyes.length, eyes: state.eyes,
    framebuffer: layer ? [layer.framebufferWidth, layer.framebufferHeight] : [],
    display: state.session ? `WebXR immersive-vr${state.emulated ? ` (emulated ${state.emulated})` : ''}, ${state.eyes.length} view(s)` : '',
  });
}

function onXRFrame(time, frame) {
  const session = frame.session;
  session.requestAnimationFrame(onXRFrame);
  state.frame++;
  const pending = state.pending;
  if (pending && pending.drawnFrame !== null) {
    // The frame that showed it has been submitted: acknowledge.
    const reply = { ok: true, id: pending.id, frame: pending.drawnFrame, ack_frame: state.frame,
      page_ms: performance.now() - pending.received };
    if (pending.readback) reply.readback = pending.readback;
    send(reply);
    state.pending = null;
  }
  const pose = frame.getViewerPose(state.refSpace);
  if (!pose) return;
  const layer = session.renderState.baseLayer;
  const eyes = pose.views.map((view) => view.eye);
  if (eyes.join() !== state.eyes.join()) { state.eyes = eyes; reportState(); }
  gl.bindFramebuffer(gl.FRAMEBUFFER, layer.framebuffer);
  const drawing = state.pending && state.pending.drawnFrame === null ? state.pending : null;
  if (drawing) state.shown = drawing.spec;
  const patches = Boolean(state.shown);  // cleared when the measurement ends
  const readback = [];
  for (const view of pose.views) {
    const viewport = layer.getViewport(view);
    if (!viewport.width || !viewport.height) continue;
    if (patches) {
      painter.draw(state.shown, viewport, view.eye);
      if (drawing && state.readback) readback.push({ eye: view.eye, viewport: [viewport.x, viewport.y, viewport.width, viewport.height], colours: summarise(gl, viewport) });
    } else {
      drawScene(viewport, view.projectionMatrix, view.transform.inverse.matrix);
    }
  }
  if (drawing) {
    drawing.drawnFrame = state.frame;
    if (state.readback) drawing.readback = readback;
  }
}

function onSelect(event) {
  if (!booth || state.patchClient) return;
  const pose = event.frame.getPose(event.inputSource.targetRaySpace, state.refSpace);
  if (!pose) return;
  const m = pose.transform.matrix;
  const hit = booth.pick([m[12], m[13], m[14]], normalise([-m[8], -m[9], -m[10]]));
  if (hit === 'source') nextSource();
  if (hit === 'level') toggleLevel();
}

// ----------------------------------------------------------------------------- the window
function resize() {
  const ratio = window.devicePixelRatio || 1;
  const width = Math.round(canvas.clientWidth * ratio);
  const height = Math.round(canvas.clientHeight * ratio);
  if (canvas.width !== width || canvas.height !== height) { canvas.width = width; canvas.height = height; }
}

function windowView() {
  resize();
  const camera = windowCamera(canvas.width / canvas.height);
  return { viewport: { x: 0, y: 0, width: canvas.width, height: canvas.height }, ...camera };
}

function onWindowFrame() {
  if (state.session) return;  // the XR frames draw; this loop resumes when the session ends
  requestAnimationFrame(onWindowFrame);
  const { viewport, projection, view } = windowView();
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  drawScene(viewport, projection, view);
}

canvas.addEventListener('click', (event) => {
  if (!booth || state.session) return;
  const { projection, view, eye } = windowView();
  const box = canvas.getBoundingClientRect();  // the canvas sits beside the panel on wide windows
  const x = ((event.clientX - box.left) / box.width) * 2 - 1;
  const y = 1 - ((event.clientY - box.top) / box.height) * 2;
  const inverse = mat4.invert(mat4.multiply(projection, view));
  const far = mat4.transform(inverse, [x, y, 1]);
  const point = [far[0] / far[3], far[1] / far[3], far[2] / far[3]];
  const hit = booth.pick(eye, normalise(sub(point, eye)));
  if (hit === 'source') nextSource();
  if (hit === 'level') toggleLevel();
});
window.addEventListener('keydown', (event) => {
  if (!booth) return;
  if (event.key === 's' || event.key === 'S') nextSource();
  if (event.key === 'l' || event.key === 'L') toggleLevel();
});
$('source').addEventListener('change', () => applyScene({ source: $('source').value }, true));
for (const radio of document.querySelectorAll('input[name=level]')) {
  radio.addEventListener('change', () => applyScene({ level: Number(radio.value) }, true));
}
$('enter-vr').addEventListener('click', enterVR);

// ----------------------------------------------------------------------------- start
async function installEmulator(name) {
  // An emulated headset (Meta's IWER), for tests and a desktop dry run: ?emulate=quest3
  const IWER = await import('./vendor/iwer/iwer.module.min.js');
  const configs = { quest3: IWER.metaQuest3, quest2: IWER.metaQuest2, questpro: IWER.metaQuestPro };
  if (!configs[name]) throw new Error(`?emulate=${name}: known are ${Object.keys(configs).join(', ')}`);
  const device = new IWER.XRDevice(configs[name]);
  device.stereoEnabled = true;
  device.installRuntime({ forceInstall: true });
  state.emulated = name;
  window.vrWorkbench.emulator = device;
}

async function start() {
  window.vrWorkbench = testApi();
  if (params.get('emulate')) await installEmulator(params.get('emulate'));
  const supported = navigator.xr && await navigator.xr.isSessionSupported('immersive-vr').catch(() => false);
  $('enter-vr').disabled = !supported;
  if (!supported) {
    $('xr-note').hidden = false;
    $('xr-note').textContent = (window.isSecureContext
      ? 'This browser offers no immersive VR session here (no headset, or WebXR is off): the lightbooth shows in this window only.'
      : 'WebXR needs a secure context: open the page as http://localhost:PORT (adb reverse for a Quest on USB) or over HTTPS (vr serve --tls); see docs/vr/webxr.md.');
  }
  try {
    await loadScene();
  } catch (error) {
    problem(`The bundle could not be loaded: ${error.message}`);
  }
  connect();
  requestAnimationFrame(onWindowFrame);
  window.vrWorkbench.ready = true;
}

// What the tests (and a curious user, in the console) can ask of the page.
function testApi() {
  return {
    ready: false,
    state: () => ({ connected: Boolean(state.socket && state.connection), refused: state.refused,
      immersive: Boolean(state.session), eyes: state.eyes, patches: state.patchClient,
      scene: { ...state.scene }, frame: state.frame, problem: $('problem').hidden ? '' : $('problem').textContent,
      xrNote: $('xr-note').hidden ? '' : $('xr-note').textContent }),
    lights: () => state.bundle ? state.bundle.lights : [],
    // The level-2 texels of the lightbooth cube under light `id`, RGBA, base64, top row first.
    level2Texels: (id) => ({ width: relight.width, height: relight.height, rgba: base64(relight.read(id)) }),
    // Draw the scene in the window now and read back the lamp's pixel (not while in VR).
    lampPixel: () => {
      const { viewport, projection, view } = windowView();
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      drawScene(viewport, projection, view);
      const [x, y] = booth.lampPixel(viewport, projection, view);
      const pixel = new Uint8Array(4);
      gl.readPixels(x, y, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
      return { rgb: [pixel[0], pixel[1], pixel[2]], at: [x, y], scene: { ...state.scene } };
    },
    setScene: (scene) => applyScene(scene, true),
    exitVR: () => state.session && state.session.end(),
    buttons: () => Object.fromEntries(booth.buttons.map((b) => [b.name, b.geometry.centre])),
    nextSource, toggleLevel,
  };
}

start();
