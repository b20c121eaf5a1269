// The editor page: the connection to the server, the commands, the toolbar and the keyboard.
// The viewport (three.js) is in viewport.js, the scene tree, properties and render dialog in
// panels.js. The server is the only source of truth: every edit goes to it, and the page redraws
// from the scene it broadcasts back.

import { Viewport, keyOf } from './viewport.js';
import { Tree, Properties, RenderDialog, materialChoices, materialDefaults, materialFieldNames } from './panels.js';

const params = new URLSearchParams(location.search);
// The tab keeps its token (sessionStorage: this tab only, this origin only), so after a server
// restarted with the same --token it reconnects, and a reload works without the cookie.
const token = params.get('token') || sessionStorage.getItem('photonix-token') || '';
if (token) sessionStorage.setItem('photonix-token', token);
// The first request set a cookie with the token; take it out of the address bar so it does not
// end up in screenshots or shared links.
if (params.get('token')) history.replaceState(null, '', location.pathname);

const $ = (id) => document.getElementById(id);

/// `selection`: a list of entries ({kind, id, index} for shapes, lights and instances, whose
/// stable `id` survives other tabs' edits; {kind: 'material', name}; {kind: 'camera'}).
export const state = { scene: null, selection: [], frames: 0 };

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
let retries = 0;

/// The one message about the connection (not one more toast per retry).
function connectionNotice(text) {
  let div = $('connection');
  if (!text) { if (div) div.remove(); return; }
  if (!div) {
    div = document.createElement('div');
    div.id = 'connection';
    div.className = 'message error';
    $('messages').appendChild(div);
  }
  div.textContent = text;
}

function connect() {
  socket = new WebSocket(`ws://${location.host}/ws${token ? `?token=${encodeURIComponent(token)}` : ''}`);
  socket.binaryType = 'arraybuffer';
  socket.onmessage = (event) => {
    if (typeof event.data === 'string') onText(JSON.parse(event.data));
    else onFrame(event.data);
  };
  socket.onopen = () => {
    retries = 0;
    connectionNotice(null);
    document.body.dataset.connected = '1';
    document.body.dataset.connections = String(Number(document.body.dataset.connections || 0) + 1);
    // The preview renders the view last sent: a tab in the background claims it only when
    // it is looked at again.
    if (!document.hidden) viewport.sendView(true);
  };
  socket.onclose = async () => {
    document.body.dataset.connected = '0';
    for (const resolve of pending.values()) resolve({ ok: false });
    pending.clear();
    retries += 1;
    // Ask why: no answer (the server is down) or a refusal (it runs with another token).
    let why = 'the server does not answer';
    try {
      const r = await fetch('api/render/status', { headers: token ? { Authorization: `token ${token}` } : {} });
      if (r.status === 401 || r.status === 403) why = 'the server now runs with another access token';
      else if (r.ok) why = 'the server answers again';
    } catch (e) { /* down */ }
    const fix = why.includes('another access token')
      ? 'open the URL it printed, or restart it with the token this page has (photonix serve --port ' + location.port + ' --token …, the token `photonix serve` printed first)'
      : 'restart it with the same --port and --token (both printed when it started) and this page carries on; edits not saved are in the server only';
    connectionNotice(`connection to the server lost: ${why}. Retrying every 2 s (${retries}). To reconnect, ${fix}.`);
    setTimeout(connect, 2000);
  };
}

function send(message) {
  return new Promise((resolve) => {
    if (!socket || socket.readyState !== WebSocket.OPEN) {
      showMessage('not connected to the server');
      resolve({ ok: false });
      return;
    }
    if (message.type === 'view') {
      socket.send(JSON.stringify(message));
      resolve({ ok: true });
      return;
    }
    const id = nextId++;
    pending.set(id, resolve);
    socket.send(JSON.stringify({ ...message, id }));
  });
}

function onText(msg) {
  switch (msg.type) {
    case 'scene': receiveScene(msg); break;
    case 'hello': state.session = msg.session; setDenoise(msg); updateButtons(); break;
    case 'reply': {
      const resolve = pending.get(msg.id);
      pending.delete(msg.id);
      // A save that would replace a file is asked about, not shown as an error.
      if (!msg.ok && !msg.replace_needed) showMessage(msg.error);
      if (resolve) resolve(msg);
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
  state.frameOwner = header.owner;
  document.body.dataset.frames = String(state.frames);
  viewport.setFrame(blob, header);
  // In Solid shading the frame is not shown, and neither is its line (no repaint for it).
  if (!viewport.rendered) return;
  const passes = header.passes ? `, ${header.passes} passes` : '';
  const denoised = header.denoised ? `, denoised in ${(header.stages.denoise || 0).toFixed(0)} ms` : '';
  $('frame-info').textContent =
    `${header.width}×${header.height}${passes}${denoised}, ${header.render_ms.toFixed(0)} ms (${header.since_change_ms.toFixed(0)} ms since the change) on ${header.device}`;
}

// The preview's denoising toggle: on by default; disabled, saying why, without the library.
function setDenoise(hello) {
  const box = $('denoise');
  box.checked = Boolean(hello.denoise);
  box.disabled = Boolean(hello.denoiser_missing);
  $('denoise-label').title = hello.denoiser_missing
    ? `Not available: ${hello.denoiser_missing}`
    : 'Denoise the rendered preview with Open Image Denoise';
}
$('denoise').onchange = (e) => socket.send(JSON.stringify({ type: 'denoise', on: e.target.checked }));

// Commands ---------------------------------------------------------------------------------------
/// Sends an edit; resolves to true once the server applied it and the page has the scene of
/// that revision (so what follows sees the change), false when refused.
export async function edit(command) {
  const reply = await send({ type: 'edit', command });
  if (reply.ok && reply.revision !== undefined) await sceneAt(reply.revision);
  return reply.ok;
}
export const undo = () => send({ type: 'undo' });
export const redo = () => send({ type: 'redo' });
/// Saves; where the save would replace a file the editor did not open or last write (a .toml
/// beside the .pov, or a file changed on disk since), asks first and replaces only when told.
export async function save() {
  let reply = await send({ type: 'save' });
  if (!reply.ok && reply.replace_needed) {
    if (!await askReplace(reply.error)) { showMessage(`not saved: ${state.scene.file} kept as it is`, 'info'); return; }
    reply = await send({ type: 'save', replace: true });
  }
  if (reply.ok) showMessage(`saved ${state.scene.file}`, 'info');
}

/// The question of a save that would replace a file: resolves true for "Replace it".
function askReplace(message) {
  const dialog = $('replace-dialog');
  $('replace-text').textContent = message;
  document.body.dataset.asking = 'replace';
  return new Promise((resolve) => {
    const done = (yes) => {
      $('replace-yes').onclick = $('replace-no').onclick = dialog.oncancel = null;
      dialog.close();
      document.body.dataset.asking = '';
      resolve(yes);
    };
    $('replace-yes').onclick = () => done(true);
    $('replace-no').onclick = () => done(false);
    dialog.oncancel = () => done(false);
    dialog.showModal();
  });
}

/// What the server opened in place of the file named (the .toml saved beside a .pov), said
/// until closed.
function showNotice(text) {
  $('notice').hidden = !text;
  $('notice-text').textContent = text || '';
  document.body.dataset.notice = text || '';
}
$('notice-close').onclick = () => showNotice(null);
export function sendView(view) { send({ type: 'view', view }); }

const waiting = [];
/// Resolves when the page has the scene of `revision` or later.
function sceneAt(revision) {
  if (state.scene && state.scene.revision >= revision) return Promise.resolve();
  // A scene that never comes (the server restarted, its revisions anew) waits at most 5 s.
  return new Promise((resolve) => { waiting.push({ revision, resolve }); setTimeout(resolve, 5000); });
}

/// The edit target of a selection entry: by stable id, so another tab's delete cannot move it.
export function targetOf(sel) {
  if (!sel) return null;
  if (sel.kind === 'shape') return { shape_id: sel.id };
  if (sel.kind === 'light') return { light_id: sel.id };
  if (sel.kind === 'instance') return { instance_id: sel.id };
  if (sel.kind === 'material') return { material: sel.name };
  if (sel.kind === 'camera') return 'camera';
  return null;
}

function listOf(kind, scene = state.scene) {
  if (!scene) return [];
  return kind === 'shape' ? scene.shapes : kind === 'light' ? scene.lights : kind === 'instance' ? scene.instances || [] : [];
}

/// The scene's entry a selection entry names (null when it is gone).
export function entryOf(sel) {
  return listOf(sel.kind).find((e) => e.id === sel.id) || null;
}

/// The selection entries still in `scene`, their indices brought up to date. After a restart of
/// the server (every id new), an entry is kept where the scene has, at its index, an entry
/// whose fields are the same as written (its `label`): the same entry of the same file, not
/// another one moved into its place.
let restarted = false;
const labelOf = (entry) => JSON.stringify(entry.fields);
function refreshed(list, scene) {
  const out = [];
  for (const sel of list) {
    if (sel.kind === 'camera') out.push(sel);
    else if (sel.kind === 'material') { if (scene.materials.some((m) => m.name === sel.name)) out.push(sel); }
    else {
      const entries = listOf(sel.kind, scene);
      let index = entries.findIndex((e) => e.id === sel.id);
      if (index < 0 && restarted && sel.label !== undefined && entries[sel.index] && labelOf(entries[sel.index]) === sel.label) index = sel.index;
      if (index >= 0) out.push({ kind: sel.kind, id: entries[index].id, index, label: labelOf(entries[index]) });
    }
  }
  return out;
}

export function select(sel) {
  const list = refreshed(Array.isArray(sel) ? sel : sel ? [sel] : [], state.scene || { shapes: [], lights: [], materials: [] });
  state.selection = list;
  document.body.dataset.selection = list.map((s) => `${s.kind}:${s.index ?? s.name ?? ''}`).join(',');
  document.body.dataset.selectionIds = list.map(keyOf).join(',');
  viewport.setSelection(list);
  tree.render(state.scene, list);
  properties.render(state.scene, list);
  updateButtons();
}

/// The entries selected together with `sel`: its whole group when it has one (a click in the
/// viewport picks the group, as in 3ds Max; the tree picks one entry).
function withGroup(sel) {
  const entry = sel.id !== undefined ? entryOf(sel) : null;
  const group = entry && entry.fields.group;
  if (typeof group !== 'string') return [sel];
  const all = [];
  for (const kind of ['shape', 'light', 'instance']) {
    listOf(kind).forEach((e, index) => { if (e.fields.group === group) all.push({ kind, id: e.id, index }); });
  }
  return all;
}

/// A click on `sel`: selects it alone, or with `additive` (Shift or Ctrl) adds it to the
/// selection or takes it out. From the viewport a grouped entry brings its group.
export function pick(sel, additive, fromViewport = false) {
  const picked = fromViewport ? withGroup(sel) : [sel];
  if (!additive) { select(picked); return; }
  const keys = new Set(picked.map(keyOf));
  const already = picked.every((p) => state.selection.some((s) => keyOf(s) === keyOf(p)));
  const rest = state.selection.filter((s) => !keys.has(keyOf(s)) && s.kind !== 'camera' && s.kind !== 'material');
  select(already ? rest : [...rest, ...picked.filter((p) => p.kind !== 'camera' && p.kind !== 'material')]);
}

export function selectMany(list, additive) {
  if (!additive) { select(list); return; }
  const keys = new Set(state.selection.map(keyOf));
  select([...state.selection, ...list.filter((s) => !keys.has(keyOf(s)))]);
}

/// A scene from the server. One broadcast after an edit (`delta`) leaves out the triangles of
/// the entries whose geometry this page has (the same `geometry` key): they come from the scene
/// before. Any missing (a message missed), the whole scene is fetched.
async function receiveScene(scene) {
  if (scene.delta) {
    const known = new Map();
    for (const list of ['shapes', 'lights', 'instances']) {
      for (const e of (state.scene && state.scene[list]) || []) if (e.positions) known.set(e.geometry, e.positions);
    }
    let missing = false;
    for (const list of ['shapes', 'lights', 'instances']) {
      for (const e of scene[list] || []) {
        if (e.positions) continue;
        if (known.has(e.geometry)) e.positions = known.get(e.geometry); else missing = true;
      }
    }
    if (missing) {
      const response = await fetch('api/scene', { headers: token ? { Authorization: `token ${token}` } : {} });
      if (!response.ok) { showMessage(`cannot fetch the scene (${response.status})`); return; }
      scene = await response.json();
      if (state.scene && scene.revision < state.scene.revision) return;
    }
  }
  setScene(scene);
}

function setScene(scene) {
  const old = state.scene;
  state.scene = scene;
  document.body.dataset.revision = String(scene.revision);
  $('file-name').textContent = scene.file + (scene.dirty ? ' •' : '');
  if (!old || old.notice !== scene.notice) showNotice(scene.notice);
  viewport.setScene(scene, !old);
  // Keep the selection where its entries still exist (by id: another tab's delete of an
  // entry before it does not move it). A restarted server has new ids for every entry.
  const ids = (sc) => new Set(['shapes', 'lights', 'instances'].flatMap((l) => (sc[l] || []).map((e) => e.id)));
  const before = old ? ids(old) : new Set();
  restarted = Boolean(old) && ![...ids(scene)].some((id) => before.has(id));
  select(state.selection);
  restarted = false;
  // A warning is new when its text is, whatever line it names now (an edit above it moves it).
  const bare = (w) => w.replace(/^[^:]*:\d+(:\d+)?: /, '');
  const known = new Set(old ? old.warnings.map(bare) : []);
  for (const w of scene.warnings) if (!known.has(bare(w))) showMessage(`warning: ${w}`, 'info');
  for (let i = waiting.length - 1; i >= 0; i--) {
    if (scene.revision >= waiting[i].revision) { waiting[i].resolve(); waiting.splice(i, 1); }
  }
}

function updateButtons() {
  const scene = state.scene;
  $('undo').disabled = !scene || !scene.can_undo;
  $('redo').disabled = !scene || !scene.can_redo;
  // Undo is the scene's, shared by every tab: say whose step it would take back.
  const whose = (author) => (author === null || author === undefined ? '' : author === state.session ? 'yours' : author === 0 ? 'an API call\'s' : 'another tab\'s');
  const undoWhose = scene ? whose(scene.undo_author) : '';
  $('undo').title = `Undo (Ctrl+Z)${undoWhose ? `: the last edit, ${undoWhose}` : ''}`;
  $('redo').title = `Redo (Ctrl+Shift+Z / Ctrl+Y)${scene && whose(scene.redo_author) ? `: ${whose(scene.redo_author)}` : ''}`;
  $('undo-author').textContent = undoWhose === 'yours' || !undoWhose ? '' : `(${undoWhose})`;
  document.body.dataset.undoAuthor = undoWhose === 'yours' ? 'mine' : undoWhose ? 'other' : '';
  const deletable = state.selection.length && state.selection.every((s) => s.kind !== 'camera');
  $('delete').disabled = !deletable;
  $('duplicate').disabled = !deletable;
}

/// Deletes the selection (one undo step) and selects nothing, so a second press deletes
/// nothing more.
export async function deleteSelection() {
  const list = state.selection.filter((s) => s.kind !== 'camera');
  if (!list.length) return;
  // Highest index first, so each delete leaves the others where they were.
  const sorted = [...list].sort((a, b) => (b.index ?? 0) - (a.index ?? 0));
  const commands = sorted.map((s) => ({ op: 'delete', target: targetOf(s) }));
  select([]);
  await edit(commands.length === 1 ? commands[0] : { op: 'batch', commands });
}

/// Duplicates the selection, each copy moved aside (by its width along x and a tenth more) and
/// selected in place of the originals.
export async function duplicateSelection() {
  const list = state.selection.filter((s) => s.kind !== 'camera');
  if (!list.length) return;
  const before = new Map(['shape', 'light', 'instance'].map((k) => [k, new Set(listOf(k).map((e) => e.id))]));
  const beforeMaterials = new Set(state.scene.materials.map((m) => m.name));
  const commands = list.map((s) => {
    const command = { op: 'duplicate', target: targetOf(s) };
    if (s.kind !== 'material') command.offset = viewport.duplicateOffset(list);
    return command;
  });
  if (!await edit(commands.length === 1 ? commands[0] : { op: 'batch', commands })) return;
  const copies = [];
  for (const [kind, ids] of before) listOf(kind).forEach((e, index) => { if (!ids.has(e.id)) copies.push({ kind, id: e.id, index }); });
  for (const m of state.scene.materials) if (!beforeMaterials.has(m.name)) copies.push({ kind: 'material', name: m.name });
  select(copies);
}

/// Puts the selection in group `name` (null: out of any group), one undo step.
export async function setGroup(list, name) {
  const entries = list.filter((s) => ['shape', 'light', 'instance'].includes(s.kind));
  if (!entries.length) return;
  const value = name === null ? null : String(name).trim();
  if (value === '') { showMessage('a group needs a name'); return; }
  await edit({ op: 'batch', commands: entries.map((s) => ({ op: 'set', target: targetOf(s), field: 'group', value })) });
}

/// A new diffuse material, selected.
export async function newMaterial() {
  const names = new Set(state.scene.materials.map((m) => m.name));
  let n = 1;
  while (names.has(`material_${n}`)) n += 1;
  const name = `material_${n}`;
  if (await edit({ op: 'add', kind: 'material', name, table: { type: 'diffuse', reflectance: materialDefaults('diffuse').reflectance } })) select({ kind: 'material', name });
}

/// The fields a type switch took out of each material (this tab), by material name: switching
/// back (diffuse to conductor to diffuse) gives them back, so the colour is not lost.
const setAside = new Map();

/// A constant colour (three numbers), not a texture.
const isColour = (v) => Array.isArray(v) && v.length === 3 && v.every((x) => typeof x === 'number');

/// Switches a material's type in one step: fields the new type does not take are set aside
/// (and given back by a later switch to a type that takes them), those it needs come with
/// their defaults (a conductor's preset), the colour goes over to the new type's colour field
/// (reflectance or tint), and a mix gets two materials: the first two others, or, where there
/// are not two, a copy of this material's look (and a diffuse one), added in the same step.
export async function switchMaterialType(material, type) {
  if (type === material.fields.type) return;
  const takes = new Set(materialFieldNames(type));
  const fields = { type };
  const aside = { ...(setAside.get(material.name) || {}) };
  for (const [field, value] of Object.entries(material.fields)) {
    if (field !== 'type' && !takes.has(field)) { fields[field] = null; aside[field] = value; }
  }
  // Given back: what an earlier switch set aside and this type takes.
  for (const [field, value] of Object.entries(aside)) {
    if (takes.has(field) && material.fields[field] === undefined && field !== 'type') { fields[field] = value; delete aside[field]; }
  }
  // The colour, whichever field holds it.
  const colour = [material.fields.reflectance, material.fields.tint].find(isColour);
  for (const field of ['reflectance', 'tint']) {
    if (takes.has(field) && material.fields[field] === undefined && fields[field] === undefined && colour) fields[field] = colour;
  }
  if (type === 'conductor' && !material.fields.preset && !material.fields.eta && !fields.eta && !fields.preset) [fields.preset] = materialChoices('conductor', 'preset');
  const commands = [];
  if (type === 'mix' && !material.fields.materials && !fields.materials) {
    const names = new Set(state.scene.materials.map((m) => m.name));
    const fresh = (base) => { let n = base, k = 2; while (names.has(n)) n = `${base}_${k++}`; names.add(n); return n; };
    const others = state.scene.materials.filter((m) => m.name !== material.name && m.fields.type !== 'null' && m.fields.type !== 'mix').map((m) => m.name);
    const parts = others.slice(0, 2);
    if (parts.length < 2 && material.fields.type !== 'null') {
      // This material's own look, so the mix starts from it.
      const look = Object.fromEntries(Object.entries(material.fields).filter(([, v]) => v !== null));
      const name = fresh(`${material.name}_base`);
      commands.push({ op: 'add', kind: 'material', name, table: look });
      parts.unshift(name);
    }
    while (parts.length < 2) {
      const name = fresh(`${material.name}_mixed`);
      commands.push({ op: 'add', kind: 'material', name, table: { type: 'diffuse', reflectance: materialDefaults('diffuse').reflectance } });
      parts.push(name);
    }
    fields.materials = parts;
  }
  commands.push({ op: 'set_fields', target: { material: material.name }, fields });
  if (await edit(commands.length === 1 ? commands[0] : { op: 'batch', commands })) setAside.set(material.name, aside);
  else select(state.selection);
}

/// Hides or shows entries in this tab's solid view.
export function toggleHidden(list) {
  const hidden = new Set(viewport.hidden);
  const keys = list.filter((s) => ['shape', 'light', 'instance'].includes(s.kind)).map(keyOf);
  const hide = keys.some((k) => !hidden.has(k));
  for (const k of keys) { if (hide) hidden.add(k); else hidden.delete(k); }
  viewport.setHidden([...hidden]);
  document.body.dataset.hidden = [...hidden].join(',');
  tree.render(state.scene, state.selection);
}

// Adding things, in front of the view --------------------------------------------------------------
async function addThing(what) {
  const scene = state.scene;
  const [kind, type] = what.split(':');
  const lo = scene.bounds.min, hi = scene.bounds.max;
  const extent = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 1;
  const s = round(extent * 0.08);
  // Where the view's centre meets the floor (standing on it), or in front of the view; beside
  // what is there already.
  const { point: c, floor } = viewport.placement(s);
  // How far above the point the thing's centre goes for it to stand there.
  const standing = { sphere: s, box: s, cylinder: s, torus: round(s / 2), quad: round(s * 0.01) }[type];
  if (floor && kind === 'shape' && standing) c[1] = round(c[1] + standing);
  const add = (v) => v.map((x, i) => round(c[i] + x));
  if (kind === 'shape' && scene.materials.length === 0) {
    if (!await edit({ op: 'add', kind: 'material', name: 'default', table: { type: 'diffuse' } })) return;
  }
  const material = state.scene.materials.length ? state.scene.materials[0].name : 'default';
  let table;
  switch (type) {
    case 'sphere': table = { name: 'sphere', type, material, center: c, radius: s }; break;
    case 'box': table = { name: 'box', type, material, min: add([-s, -s, -s]), max: add([s, s, s]) }; break;
    case 'quad': table = { name: 'quad', type, material, vertices: [add([-s, 0, -s]), add([-s, 0, s]), add([s, 0, s]), add([s, 0, -s])] }; break;
    case 'cylinder': table = { name: 'cylinder', type, material, base: add([0, -s, 0]), cap: add([0, s, 0]), radius: s }; break;
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
  const before = new Set(listOf(kind).map((e) => e.id));
  if (await edit({ op: 'add', kind, table })) {
    const index = listOf(kind).findIndex((e) => !before.has(e.id));
    if (index >= 0) select({ kind, id: listOf(kind)[index].id, index });
  }
}

function round(v) { return Number.parseFloat(Number(v).toPrecision(4)); }

/// Imports a model (any format the renderer reads: OBJ, glTF/.glb, PLY, 3DS, IFS, .bpt) into the
/// scene's folder; its materials are the file's (or a default diffuse one), its centre in front
/// of the view.
export async function importModel(file) {
  const name = file.name.replace(/[^A-Za-z0-9._-]/g, '_').replace(/^\.+/, '');
  const lo = state.scene.bounds.min, hi = state.scene.bounds.max;
  const extent = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 1;
  // Standing on the floor at the view's centre (the server puts the bottom of its box there),
  // about a quarter of the scene across unless it is within 4 times of that already.
  const { point, floor } = viewport.placement(extent * 0.08);
  const size = round(extent * 0.25);
  const before = new Set(state.scene.shapes.map((e) => e.id));
  const query = `name=${encodeURIComponent(name)}&at=${encodeURIComponent(point.join(','))}&size=${size}${floor ? '&floor=true' : ''}`;
  const response = await fetch(`api/import?${query}`, {
    method: 'POST', body: file, headers: token ? { Authorization: `token ${token}` } : {},
  });
  const reply = await response.json().catch(() => ({ ok: false, error: `import failed (${response.status})` }));
  if (!reply.ok) { showMessage(reply.error || `import failed (${response.status})`); return; }
  showMessage(`imported ${reply.file}`, 'info');
  await sceneAt(reply.revision);
  const index = state.scene.shapes.findIndex((e) => !before.has(e.id));
  if (index >= 0) select({ kind: 'shape', id: state.scene.shapes[index].id, index });
}

// Start ------------------------------------------------------------------------------------------
const viewport = new Viewport($('canvas'), $('view-labels'), {
  select,
  pick: (sel, additive) => pick(sel, additive, true),
  selectMany: (list, additive) => selectMany(list, additive),
  edit,
  sendView,
  state,
});
const tree = new Tree($('tree'), { select, pick, selectMany, toggleHidden, hidden: () => viewport.hidden });
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

const properties = new Properties($('properties'), {
  edit, state, showMessage, images, entryOf, setGroup, newMaterial, switchMaterialType,
  typedTransform: (sel, part, values) => viewport.typedTransform(sel, part, values),
});
const renderDialog = new RenderDialog($('render-dialog'), { showMessage, token });

$('undo').onclick = undo;
$('redo').onclick = redo;
$('delete').onclick = deleteSelection;
$('duplicate').onclick = duplicateSelection;
$('save').onclick = save;
$('add').onchange = (e) => { const v = e.target.value; e.target.value = ''; if (v) addThing(v); };
$('import').onchange = (e) => { const f = e.target.files[0]; e.target.value = ''; if (f) importModel(f); };
$('frame').onclick = () => viewport.frameSelected();
$('wireframe').onclick = () => setWireframe(!viewport.wireframe);
$('navigation').onchange = (e) => { viewport.setNavigation(e.target.value); localStorage.setItem('photonix-navigation', e.target.value); };
$('navigation').value = localStorage.getItem('photonix-navigation') === 'blender' ? 'blender' : 'default';
viewport.setNavigation($('navigation').value);

function setWireframe(on) {
  viewport.setWireframe(on);
  $('wireframe').classList.toggle('active', on);
  if (on && viewport.rendered) setShading(false);
}
for (const mode of ['translate', 'rotate', 'scale']) $(`mode-${mode}`).onclick = () => setMode(mode);
$('snap').onchange = (e) => viewport.setSnap(e.target.checked);
$('shading').onclick = () => setShading(!viewport.rendered);
$('layout').onclick = () => { viewport.setQuad(!viewport.quad); $('layout').classList.toggle('active', viewport.quad); };
$('view-camera').onclick = () => viewport.viewThroughCamera();
$('camera-to-view').onclick = () => viewport.cameraToView();
$('render-open').onclick = () => renderDialog.open();
$('help-open').onclick = () => $('help-dialog').showModal();
$('help-close').onclick = () => $('help-dialog').close();

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
  // Blender's G / R / S under way: Enter confirms, Escape cancels.
  if (viewport.modal) {
    if (key === 'enter') viewport.endModal(true);
    else if (key === 'escape') viewport.endModal(false);
    e.preventDefault();
    return;
  }
  const modal = { g: 'translate', r: 'rotate', s: 'scale' }[key];
  if (!ctrl && !e.altKey && modal && viewport.navigation === 'blender' && viewport.pointer) {
    setMode(modal);
    if (viewport.startModal(modal, viewport.pointer.x, viewport.pointer.y)) { e.preventDefault(); return; }
  }
  if (ctrl && key === 'z' && !e.shiftKey) undo();
  else if (ctrl && (key === 'y' || (key === 'z' && e.shiftKey))) redo();
  else if (ctrl && key === 's') save();
  else if (ctrl && e.altKey && e.code === 'Numpad0') viewport.cameraToView();
  else if (ctrl && e.altKey && key === 'q') $('layout').click();
  else if (ctrl && ['Numpad1', 'Numpad3', 'Numpad7'].includes(e.code)) viewport.axisView(Number(e.code.slice(-1)), true);
  else if (ctrl) handled = false;
  else if (key === 'delete' || key === 'x' || key === 'backspace') deleteSelection();
  else if (key === 'h' && e.altKey) { viewport.setHidden([]); document.body.dataset.hidden = ''; tree.render(state.scene, state.selection); }
  else if (key === 'h') toggleHidden(state.selection);
  else if (key === 'f' || e.code === 'NumpadDecimal') viewport.frameSelected();
  else if (key === 'd' && e.shiftKey) duplicateSelection();
  else if (key === 'g' || key === 'w') setMode('translate');
  else if (key === 'r' || key === 'e') setMode('rotate');
  else if (key === 's') setMode('scale');
  else if (key === 'z' && e.shiftKey) setWireframe(!viewport.wireframe);
  else if (key === 'z') setShading(!viewport.rendered);
  else if (['Numpad1', 'Numpad3', 'Numpad7'].includes(e.code)) viewport.axisView(Number(e.code.slice(-1)), e.ctrlKey);
  else if (e.code === 'Numpad0') viewport.viewThroughCamera();
  else if (key === 'escape') { viewport.cancelBoxSelect(); select([]); }
  else if (key === 'b') viewport.startBoxSelect();
  else if (key === 'f12') renderDialog.open();
  else if (e.key === '?') $('help-dialog').showModal();
  else handled = false;
  if (handled) e.preventDefault();
});

// A tab in front takes the renderer back for its own view (each tab gets only its own frames).
window.addEventListener('focus', () => viewport.sendView(true));
document.addEventListener('visibilitychange', () => { if (!document.hidden) viewport.sendView(true); });
$('canvas').addEventListener('pointerdown', () => viewport.sendView(true));

setShading(true);
connect();
// For the browser test and for debugging from the console.
window.photonixEditor = { state, viewport, select, pick, edit, entryOf };
