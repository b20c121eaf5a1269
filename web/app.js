// The editor page: the connection to the server, the commands, the toolbar and the keyboard.
// The viewport (three.js) is in viewport.js, the scene tree, properties and render dialog in
// panels.js. The server is the only source of truth: every edit goes to it, and the page redraws
// from the scene it broadcasts back.

import { Viewport } from './viewport.js';
import { Tree, Properties, RenderDialog } from './panels.js';

const params = new URLSearchParams(location.search);
const token = params.get('token') || '';
// The first request set a cookie with the token; take it out of the address bar so it does not
// end up in screenshots or shared links.
if (token) history.replaceState(null, '', location.pathname);

const $ = (id) => document.getElementById(id);

export const state = { scene: null, selection: null, frames: 0 };

// Messages ---------------------------------------------------------------------------------------
export function showMessage(text, kind = 'error') {
  const div = document.createElement('div');
  div.className = `message ${kind}`;
  div.textContent = text;
  $('messages').appendChild(div);
  setTimeout(() => div.remove(), kind === 'error' ? 8000 : 2500);
  if (kind === 'error') document.body.dataset.lastError = text;
}

// The connection ---------------------------------------------------------------------------------
let socket = null;
let nextId = 1;
const pending = new Map();

function connect() {
  socket = new WebSocket(`ws://${location.host}/ws${token ? `?token=${encodeURIComponent(token)}` : ''}`);
  socket.binaryType = 'arraybuffer';
  socket.onmessage = (event) => {
    if (typeof event.data === 'string') onText(JSON.parse(event.data));
    else onFrame(event.data);
  };
  socket.onopen = () => { viewport.sendView(true); };
  socket.onclose = () => {
    showMessage('connection to the server lost; reconnecting…');
    setTimeout(connect, 2000);
  };
}

function send(message) {
  return new Promise((resolve) => {
    if (!socket || socket.readyState !== WebSocket.OPEN) {
      showMessage('not connected to the server');
      resolve(false);
      return;
    }
    if (message.type === 'view') {
      socket.send(JSON.stringify(message));
      resolve(true);
      return;
    }
    const id = nextId++;
    pending.set(id, resolve);
    socket.send(JSON.stringify({ ...message, id }));
  });
}

function onText(msg) {
  switch (msg.type) {
    case 'scene': setScene(msg); break;
    case 'reply': {
      const resolve = pending.get(msg.id);
      pending.delete(msg.id);
      if (!msg.ok) showMessage(msg.error);
      if (resolve) resolve(msg.ok);
      break;
    }
    case 'render': renderDialog.update(msg); break;
    case 'error': showMessage(msg.message); break;
  }
}

function onFrame(buffer) {
  const view = new DataView(buffer);
  const length = view.getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, length)));
  const blob = new Blob([new Uint8Array(buffer, 4 + length)], { type: 'image/png' });
  if (header.kind === 'final') {
    renderDialog.setImage(blob, header);
    return;
  }
  state.frames += 1;
  document.body.dataset.frames = String(state.frames);
  viewport.setFrame(blob, header);
  const passes = header.passes ? `, ${header.passes} passes` : '';
  $('frame-info').textContent =
    `${header.width}×${header.height}${passes}, ${header.render_ms.toFixed(0)} ms (${header.since_change_ms.toFixed(0)} ms since the change) on ${header.device}`;
}

// Commands ---------------------------------------------------------------------------------------
export function edit(command) { return send({ type: 'edit', command }); }
export const undo = () => send({ type: 'undo' });
export const redo = () => send({ type: 'redo' });
export async function save() {
  if (await send({ type: 'save' })) showMessage(`saved ${state.scene.file}`, 'info');
}
export function sendView(view) { send({ type: 'view', view }); }

/// The edit target of a selection.
export function targetOf(sel) {
  if (!sel) return null;
  if (sel.kind === 'shape') return { shape: sel.index };
  if (sel.kind === 'light') return { light: sel.index };
  if (sel.kind === 'instance') return { instance: sel.index };
  if (sel.kind === 'material') return { material: sel.name };
  if (sel.kind === 'camera') return 'camera';
  return null;
}

export function select(sel) {
  state.selection = sel;
  document.body.dataset.selection = sel ? `${sel.kind}:${sel.index ?? sel.name ?? ''}` : '';
  viewport.setSelection(sel);
  tree.render(state.scene, sel);
  properties.render(state.scene, sel);
  updateButtons();
}

function setScene(scene) {
  const old = state.scene;
  state.scene = scene;
  document.body.dataset.revision = String(scene.revision);
  $('file-name').textContent = scene.file + (scene.dirty ? ' •' : '');
  viewport.setScene(scene, !old);
  // Keep the selection when it still exists.
  let sel = state.selection;
  if (sel && sel.kind === 'shape' && sel.index >= scene.shapes.length) sel = null;
  if (sel && sel.kind === 'light' && sel.index >= scene.lights.length) sel = null;
  if (sel && sel.kind === 'instance' && sel.index >= (scene.instances || []).length) sel = null;
  if (sel && sel.kind === 'material' && !scene.materials.some((m) => m.name === sel.name)) sel = null;
  select(sel);
  for (const w of scene.warnings) if (!old || !old.warnings.includes(w)) showMessage(`warning: ${w}`, 'info');
}

function updateButtons() {
  const scene = state.scene;
  $('undo').disabled = !scene || !scene.can_undo;
  $('redo').disabled = !scene || !scene.can_redo;
  const sel = state.selection;
  const deletable = sel && sel.kind !== 'camera';
  $('delete').disabled = !deletable;
  $('duplicate').disabled = !deletable;
}

export function deleteSelection() {
  const target = targetOf(state.selection);
  if (!target || target === 'camera') return;
  edit({ op: 'delete', target });
}

export function duplicateSelection() {
  const target = targetOf(state.selection);
  if (!target || target === 'camera') return;
  edit({ op: 'duplicate', target });
}

// Adding things, sized to the scene --------------------------------------------------------------
async function addThing(what) {
  const scene = state.scene;
  const [kind, type] = what.split(':');
  const lo = scene.bounds.min, hi = scene.bounds.max;
  const c = [0, 1, 2].map((i) => round((lo[i] + hi[i]) / 2));
  const extent = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 1;
  const s = round(extent * 0.08);
  const add = (v) => v.map((x, i) => round(c[i] + x));
  if (kind === 'shape' && scene.materials.length === 0) {
    if (!await edit({ op: 'add', kind: 'material', name: 'default', table: { type: 'diffuse' } })) return;
  }
  const material = scene.materials.length ? scene.materials[0].name : 'default';
  let table;
  switch (type) {
    case 'sphere': table = { name: 'sphere', type, material, center: c, radius: s }; break;
    case 'box': table = { name: 'box', type, material, min: add([-s, -s, -s]), max: add([s, s, s]) }; break;
    case 'quad': table = { name: 'quad', type, material, vertices: [add([-s, 0, -s]), add([-s, 0, s]), add([s, 0, s]), add([s, 0, -s])] }; break;
    case 'cylinder': table = { name: 'cylinder', type, material, base: c, cap: add([0, 2 * s, 0]), radius: s }; break;
    case 'torus': table = { name: 'torus', type, material, center: c, major_radius: 2 * s, minor_radius: round(s / 2) }; break;
    case 'point': table = { name: 'point light', type, position: add([0, 3 * s, 0]), intensity: round((extent * 0.3) ** 2) }; break;
    case 'spot': table = { name: 'spot light', type, position: add([0, 4 * s, 0]), point_at: c, intensity: round((extent * 0.5) ** 2), outer_angle: 30 }; break;
    case 'area': {
      const y = round(hi[1] - s * 0.1);
      table = { name: 'area light', type, shape: 'quad', radiance: 5,
        vertices: [[c[0] - s, y, c[2] - s], [c[0] + s, y, c[2] - s], [c[0] + s, y, c[2] + s], [c[0] - s, y, c[2] + s]].map((v) => v.map(round)) };
      break;
    }
    case 'distant': table = { name: 'sun', type, direction: [0.3, -1, -0.4], irradiance: 1 }; break;
    default: return;
  }
  const count = kind === 'shape' ? scene.shapes.length : scene.lights.length;
  if (await edit({ op: 'add', kind, table })) select({ kind, index: count });
}

function round(v) { return Number.parseFloat(Number(v).toPrecision(4)); }

async function importMesh(file) {
  if (!state.scene.materials.length) {
    if (!await edit({ op: 'add', kind: 'material', name: 'default', table: { type: 'diffuse' } })) return;
  }
  const material = state.scene.materials[0].name;
  const name = file.name.replace(/[^A-Za-z0-9._-]/g, '_').replace(/^\.+/, '');
  const response = await fetch(`api/import?name=${encodeURIComponent(name)}&material=${encodeURIComponent(material)}`, {
    method: 'POST', body: file, headers: token ? { Authorization: `token ${token}` } : {},
  });
  const reply = await response.json().catch(() => ({ ok: false, error: `import failed (${response.status})` }));
  if (!reply.ok) showMessage(reply.error || `import failed (${response.status})`);
  else showMessage(`imported ${reply.file}`, 'info');
}

// Start ------------------------------------------------------------------------------------------
const viewport = new Viewport($('canvas'), $('view-labels'), {
  select,
  edit,
  sendView,
  state,
});
const tree = new Tree($('tree'), { select });
/// The image files in the scene's folder, for the texture picker.
async function images() {
  const response = await fetch('api/images', { headers: token ? { Authorization: `token ${token}` } : {} });
  const reply = await response.json().catch(() => ({}));
  if (!response.ok || !Array.isArray(reply.images)) {
    showMessage(reply.error || `cannot list the folder's images (${response.status})`);
    return [];
  }
  return reply.images;
}

const properties = new Properties($('properties'), { edit, state, showMessage, images });
const renderDialog = new RenderDialog($('render-dialog'), { showMessage, token });

$('undo').onclick = undo;
$('redo').onclick = redo;
$('delete').onclick = deleteSelection;
$('duplicate').onclick = duplicateSelection;
$('save').onclick = save;
$('add').onchange = (e) => { const v = e.target.value; e.target.value = ''; if (v) addThing(v); };
$('import').onchange = (e) => { const f = e.target.files[0]; e.target.value = ''; if (f) importMesh(f); };
for (const mode of ['translate', 'rotate', 'scale']) $(`mode-${mode}`).onclick = () => setMode(mode);
$('snap').onchange = (e) => viewport.setSnap(e.target.checked);
$('shading').onclick = () => setShading(!viewport.rendered);
$('layout').onclick = () => { viewport.setQuad(!viewport.quad); $('layout').classList.toggle('active', viewport.quad); };
$('view-camera').onclick = () => viewport.viewThroughCamera();
$('camera-to-view').onclick = () => viewport.cameraToView();
$('render-open').onclick = () => renderDialog.open();

function setMode(mode) {
  viewport.setMode(mode);
  for (const m of ['translate', 'rotate', 'scale']) $(`mode-${m}`).classList.toggle('active', m === mode);
}

function setShading(rendered) {
  viewport.setRendered(rendered);
  $('shading').classList.toggle('active', rendered);
  $('shading').textContent = rendered ? 'Rendered' : 'Solid';
}

window.addEventListener('keydown', (e) => {
  const tag = (e.target.tagName || '').toLowerCase();
  if (tag === 'input' || tag === 'select' || tag === 'textarea') return;
  const ctrl = e.ctrlKey || e.metaKey;
  const key = e.key.toLowerCase();
  let handled = true;
  if (ctrl && key === 'z' && !e.shiftKey) undo();
  else if (ctrl && (key === 'y' || (key === 'z' && e.shiftKey))) redo();
  else if (ctrl && key === 's') save();
  else if (ctrl && e.altKey && e.code === 'Numpad0') viewport.cameraToView();
  else if (ctrl && e.altKey && key === 'q') $('layout').click();
  else if (ctrl) handled = false;
  else if (key === 'delete' || key === 'x' || key === 'backspace') deleteSelection();
  else if (key === 'd' && e.shiftKey) duplicateSelection();
  else if (key === 'g' || key === 'w') setMode('translate');
  else if (key === 'r' || key === 'e') setMode('rotate');
  else if (key === 's') setMode('scale');
  else if (key === 'z') setShading(!viewport.rendered);
  else if (e.code === 'Numpad0') viewport.viewThroughCamera();
  else if (key === 'escape') select(null);
  else if (key === 'f12') renderDialog.open();
  else handled = false;
  if (handled) e.preventDefault();
});

setShading(true);
connect();
// For the browser test and for debugging from the console.
window.photonixEditor = { state, viewport, select, edit };
