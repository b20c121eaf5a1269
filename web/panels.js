import { keyOf } from './viewport.js';
import { KINDS } from './kinds.js';

// The scene tree, the properties panel and the final-render dialog. Every field the properties
// panel shows is the file's own (as written); a change is sent as a `set` edit, and the panel
// redraws from the scene the server sends back, so a refused value snaps back.

const COLOR_FIELDS = new Set(['reflectance', 'tint', 'emission', 'radiance', 'intensity', 'irradiance', 'color']);
const HIDDEN_FIELDS = new Set(['type', 'transform']);
// The field types (src/scene/kinds.rs) a texture may drive; all but colours are read as data
// (linear) rather than colour (sRGB).
const TEXTURED_TYPES = new Set(['color or texture', 'number or texture', 'roughness']);

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'dataset') Object.assign(e.dataset, v);
    else if (k.startsWith('on')) e[k] = v;
    else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
}

function nameOf(entry, fallback) {
  return (entry.fields && entry.fields.name) || fallback;
}

export class Tree {
  constructor(root, app) { this.root = root; this.app = app; }

  /// `sel`: the selection (a list of entries). Entries of a `group` are listed under it; a
  /// click on the group selects them all, Shift or Ctrl adds to the selection, the eye hides
  /// an entry in this tab's solid view.
  render(scene, sel) {
    if (!scene) return;
    const selected = new Set((sel || []).map(keyOf));
    const hidden = this.app.hidden();
    this.root.innerHTML = '';
    const item = (label, target, id) => {
      const key = keyOf(target);
      const li = el('li', { class: `item${selected.has(key) ? ' selected' : ''}`, id,
        onclick: (e) => this.app.pick(target, e.shiftKey || e.ctrlKey || e.metaKey) }, label);
      if (target.kind === 'shape' || target.kind === 'light' || target.kind === 'instance') {
        // The eye's glyph is CSS, so the item's text is its label alone.
        const eye = el('span', { class: `eye${hidden.has(key) ? ' off' : ''}`, id: `eye-${id}`, title: 'Hide or show in this tab\'s solid view (H / Alt+H)',
          onclick: (e) => { e.stopPropagation(); this.app.toggleHidden([target]); } });
        li.prepend(eye);
      }
      return li;
    };
    const section = (title, items, attrs = {}) => {
      const ul = el('ul');
      items.forEach((i) => ul.append(i));
      return el('li', { class: 'section', ...attrs }, title, ul);
    };
    const entries = [];
    scene.shapes.forEach((s, i) => entries.push({ entry: s, list: 'Shapes', target: { kind: 'shape', id: s.id, index: i },
      label: `${nameOf(s, `shape ${i}`)} (${s.fields.type})`, dom: `tree-shape-${i}` }));
    scene.lights.forEach((l, i) => entries.push({ entry: l, list: 'Lights', target: { kind: 'light', id: l.id, index: i },
      label: `${nameOf(l, `light ${i}`)} (${l.fields.type})`, dom: `tree-light-${i}` }));
    (scene.instances || []).forEach((inst, i) => entries.push({ entry: inst, list: 'Instances', target: { kind: 'instance', id: inst.id, index: i },
      label: `${nameOf(inst, `instance ${i}`)} (${inst.object}${inst.copies === 1 ? '' : ` ×${inst.copies}`})`, dom: `tree-instance-${i}` }));
    this.root.append(item('Camera', { kind: 'camera' }, 'tree-camera'));
    // Groups first, each a folder of its entries.
    const groups = new Map();
    for (const e of entries) {
      const g = e.entry.fields.group;
      if (typeof g === 'string') { if (!groups.has(g)) groups.set(g, []); groups.get(g).push(e); }
    }
    if (groups.size) {
      const folders = [...groups].map(([name, members]) => {
        const all = members.map((m) => m.target);
        const allSelected = all.every((t) => selected.has(keyOf(t)));
        const ul = el('ul');
        members.forEach((m) => ul.append(item(m.label, m.target, m.dom)));
        const head = el('span', { class: `item group${allSelected ? ' selected' : ''}`, id: `tree-group-${name.replace(/[^A-Za-z0-9_-]/g, '_')}`,
          title: 'Select the group (its entries move as one)',
          onclick: (e) => this.app.selectMany(all, e.shiftKey || e.ctrlKey || e.metaKey) }, `▾ ${name} (${members.length})`);
        return el('li', { class: 'folder' }, head, ul);
      });
      this.root.append(section('Groups', folders));
    }
    for (const list of ['Shapes', 'Lights', 'Instances']) {
      const items = entries.filter((e) => e.list === list && typeof e.entry.fields.group !== 'string');
      if (list === 'Instances' && !(scene.instances || []).length) continue;
      this.root.append(section(list, items.map((e) => item(e.label, e.target, e.dom))));
    }
    this.root.append(section('Materials', scene.materials.map((m) =>
      item(`${m.name} (${m.fields.type})`, { kind: 'material', name: m.name }, `tree-material-${m.name}`))));
  }
}

/// sRGB-encoded [0, 1] from linear [0, 1] and back (IEC 61966-2-1's curve): the colour picker
/// shows and takes sRGB, as every colour picker does, and the file stores linear reflectance.
export function linearToSrgb(v) {
  v = Math.min(1, Math.max(0, v));
  return v <= 0.0031308 ? 12.92 * v : 1.055 * v ** (1 / 2.4) - 0.055;
}
export function srgbToLinear(v) {
  return v <= 0.04045 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4;
}

function toHex(rgb) {
  const c = (v) => Math.round(linearToSrgb(v) * 255).toString(16).padStart(2, '0');
  return `#${c(rgb[0])}${c(rgb[1])}${c(rgb[2])}`;
}

function fromHex(hex) {
  return [1, 3, 5].map((i) => Number.parseFloat(srgbToLinear(parseInt(hex.slice(i, i + 2), 16) / 255).toPrecision(4)));
}

/// Every material type's fields, as the scene format declares them (src/scene/kinds.rs, served
/// as kinds.js): `[{ name, type, default, required, shared, choices }]`.
export const MATERIAL_TYPES = Object.keys(KINDS.materials);
function materialKind(type) { return KINDS.materials[type] || []; }
/// The values a material field of the kind's list may take (a conductor's presets).
export function materialChoices(type, field) { return (materialKind(type).find((f) => f.name === field) || { choices: [] }).choices; }
/// The names of every field a material of `type` takes.
export function materialFieldNames(type) { return materialKind(type).map((f) => f.name); }
/// The fields the panel lists for a material of `type`, with their defaults: the type's own
/// first, then those every type shares; a field with no default is listed only when required
/// (`materials` of a mix) or a choice (a conductor's `preset`), or when the file writes it.
export function materialDefaults(type) {
  const kind = materialKind(type);
  const out = {};
  for (const f of [...kind.filter((f) => !f.shared), ...kind.filter((f) => f.shared)]) {
    if (f.name === 'type' || f.type === 'texture') continue;
    if (f.default !== null || f.required || f.choices.length) out[f.name] = f.default;
  }
  return out;
}

export class Properties {
  constructor(root, app) { this.root = root; this.app = app; }

  /// Redraws the panel, except while a field in it is being typed in: then the redraw waits
  /// until the field is left, so an edit from another tab neither steals the focus nor commits
  /// the half-typed value.
  render(scene, sel) {
    const active = document.activeElement;
    if (active && this.root.contains(active) && active.dataset.typed === '1') {
      this.pending = [scene, sel];
      if (!active.dataset.waits) {
        active.dataset.waits = '1';
        active.addEventListener('blur', () => {
          setTimeout(() => { if (this.pending) { const [s, l] = this.pending; this.pending = null; this.render(s, l); } }, 0);
        }, { once: true });
      }
      return;
    }
    this.pending = null;
    const focusedId = active && this.root.contains(active) ? active.id : null;
    this.draw(scene, sel);
    // A field that had the focus keeps it.
    if (focusedId) { const again = document.getElementById(focusedId); if (again) again.focus(); }
  }

  draw(scene, sel) {
    this.root.innerHTML = '';
    const list = sel || [];
    if (!scene || !list.length) {
      this.root.append(el('p', { class: 'hint' }, 'Select an object in the viewport or the tree (Shift or Ctrl to add).'));
      this.root.append(el('button', { id: 'new-material', onclick: () => this.app.newMaterial() }, 'New material'));
      return;
    }
    if (list.length > 1) {
      const groups = new Set(list.map((s) => this.app.entryOf(s)).filter(Boolean).map((e) => e.fields.group));
      const group = groups.size === 1 ? [...groups][0] : undefined;
      const fs = el('fieldset', {}, el('legend', {}, `${list.length} selected`));
      fs.append(el('p', { class: 'hint', id: 'multi-note' }, typeof group === 'string'
        ? `Group "${group}": the gizmo moves, turns and scales its entries as one.`
        : 'The gizmo moves, turns and scales them as one, about their common centre.'));
      const name = el('input', { id: 'group-name', type: 'text', value: typeof group === 'string' ? group : 'group' });
      fs.append(el('div', { class: 'row' }, el('label', {}, 'group'), name,
        el('button', { id: 'group-set', onclick: () => this.app.setGroup(list, name.value) }, 'Group'),
        el('button', { id: 'group-clear', onclick: () => this.app.setGroup(list, null) }, 'Ungroup')));
      this.root.append(fs);
      return;
    }
    const one = list[0];
    if (one.kind === 'shape' || one.kind === 'light' || one.kind === 'instance') {
      const entry = this.app.entryOf(one);
      if (!entry) return;
      const index = one.index;
      const target = { [`${one.kind}_id`]: one.id };
      const title = one.kind === 'instance'
        ? `${nameOf(entry, `instance ${index}`)}: object "${entry.object}"`
        : `${nameOf(entry, `${one.kind} ${index}`)}: ${entry.fields.type}`;
      this.root.append(this.fieldset(title, target, entry.fields, scene, 'obj'));
      if (one.kind === 'instance') this.root.append(this.instanceNote(entry));
      const hasTransform = one.kind !== 'light' || entry.fields.type === 'area';
      if (hasTransform) this.root.append(this.transform(target, entry.fields.transform || {}, one));
      const material = entry.fields.material && scene.materials.find((m) => m.name === entry.fields.material);
      if (material) this.root.append(this.material(material, scene));
    } else if (one.kind === 'material') {
      const material = scene.materials.find((m) => m.name === one.name);
      if (material) this.root.append(this.material(material, scene));
    } else if (one.kind === 'camera') {
      this.root.append(this.fieldset('Camera', 'camera', scene.camera.fields, scene, 'cam'));
      if (scene.render) this.root.append(this.fieldset('Render', 'render', scene.render, scene, 'render'));
      if (scene.photons) this.root.append(this.fieldset('Photons', 'photons', scene.photons, scene, 'photons'));
    }
  }

  /// How many copies the entry places and how the solid view draws them.
  instanceNote(entry) {
    const drawn = {
      triangles: 'drawn whole',
      boxes: 'too many triangles to draw: each copy is drawn as its object\'s bounding box',
      bounds: 'too many copies to draw: one box around them all',
    }[entry.drawn] || '';
    const grid = entry.fields.count ? '; the grid\'s offsets (count × spacing) follow the transform, along the world axes' : '';
    return el('p', { class: 'hint', id: 'instance-note' },
      `${entry.copies} ${entry.copies === 1 ? 'copy' : 'copies'} of object "${entry.object}", ${drawn}${grid}. ` +
      'The object\'s own shapes are edited in the scene file.');
  }

  /// The material's type (switchable), every field its type takes (those not in the file show
  /// their default, greyed, and typing one writes it), and a texture picker.
  material(material, scene) {
    const type = material.fields.type;
    const target = { material: material.name };
    const fs = el('fieldset', { id: 'material-panel' }, el('legend', {}, `Material "${material.name}"`));
    const kind = el('select', { id: 'mat-type', title: 'The material\'s type: a switch keeps the fields the new type takes' });
    for (const t of MATERIAL_TYPES) kind.append(el('option', t === type ? { value: t, selected: '' } : { value: t }, t));
    kind.onchange = () => this.app.switchMaterialType(material, kind.value);
    fs.append(el('div', { class: 'row' }, el('label', {}, 'type'), kind,
      el('button', { id: 'new-material', title: 'A new diffuse material', onclick: () => this.app.newMaterial() }, 'New')));
    const defaults = materialDefaults(type);
    const shown = { ...defaults };
    for (const [k, v] of Object.entries(material.fields)) shown[k] = v;
    const written = new Set(Object.keys(material.fields));
    for (const [field, value] of Object.entries(shown)) {
      if (field === 'type') continue;
      if (field === 'preset' && type === 'conductor') {
        const select = el('select', { id: 'mat-preset', onchange: (e) => this.set(target, 'preset', e.target.value || null) });
        select.append(el('option', { value: '' }, 'none (eta and k)'));
        for (const p of materialChoices('conductor', 'preset')) select.append(el('option', p === value && written.has('preset') ? { value: p, selected: '' } : { value: p }, p));
        if (!written.has('preset')) select.value = '';
        fs.append(el('div', { class: 'row' }, el('label', {}, 'preset'), select));
        continue;
      }
      if (field === 'materials' && value === null) {
        fs.append(this.rows(target, { materials: [] }, scene, 'mat', written));
        continue;
      }
      fs.append(this.rows(target, { [field]: value }, scene, 'mat', written));
    }
    if (type !== 'null') fs.append(this.texturePicker(material));
    return fs;
  }

  /// A texture for one of the material's fields: an image file of the scene's folder (the
  /// server adds the `[textures.*]` table and checks the path).
  texturePicker(material) {
    const kind = materialKind(material.fields.type);
    // The type's own fields first (the first is the one picked), then the shared ones.
    const fields = [...kind.filter((f) => !f.shared), ...kind.filter((f) => f.shared)]
      .filter((f) => TEXTURED_TYPES.has(f.type)).map((f) => f.name);
    const linear = new Set(kind.filter((f) => f.type !== 'color or texture').map((f) => f.name));
    const field = el('select', { id: 'tex-field', title: 'The field the texture drives' });
    for (const f of fields) field.append(el('option', { value: f }, f));
    const file = el('select', { id: 'tex-file', title: 'An image in the scene\'s folder' }, el('option', { value: '' }, 'image…'));
    this.app.images().then((images) => {
      for (const f of images) file.append(el('option', { value: f }, f));
      if (!images.length) file.firstChild.textContent = 'no images in the folder';
      file.dataset.loaded = String(images.length);
    });
    file.onchange = () => {
      if (!file.value) return;
      this.app.edit({ op: 'set_texture', material: material.name, field: field.value, file: file.value, linear: linear.has(field.value) });
    };
    return el('div', { class: 'row texture' }, el('label', {}, 'texture'), field, file);
  }

  set(target, field, value) {
    this.app.edit({ op: 'set', target, field, value });
  }

  fieldset(title, target, fields, scene, prefix) {
    const fs = el('fieldset', {}, el('legend', {}, title));
    fs.append(this.rows(target, fields, scene, prefix, null));
    return fs;
  }

  /// One row per field of `fields`, each input named `prefix-field[-axis]`; with `written`,
  /// a field not in it is a default (drawn greyed, written when changed).
  rows(target, fields, scene, prefix, written) {
    const out = document.createDocumentFragment();
    for (const [field, value] of Object.entries(fields || {})) {
      if (HIDDEN_FIELDS.has(field)) continue;
      const isDefault = written && !written.has(field);
      const row = el('div', { class: `row${isDefault ? ' default' : ''}` }, el('label', {}, isDefault ? `${field} (default)` : field));
      const id = `${prefix}-${field}`;
      if (field === 'material' && typeof value === 'string') {
        const select = el('select', { id, onchange: (e) => this.set(target, field, e.target.value) });
        for (const m of scene.materials) select.append(el('option', m.name === value ? { value: m.name, selected: '' } : { value: m.name }, m.name));
        row.append(select);
      } else if (typeof value === 'number') {
        row.append(this.number(id, value, (v) => this.set(target, field, v)));
      } else if (typeof value === 'boolean') {
        const box = el('input', { id, type: 'checkbox', onchange: (e) => this.set(target, field, e.target.checked) });
        box.checked = value;
        row.append(box);
      } else if (typeof value === 'string') {
        row.append(this.text(id, value, (v) => this.set(target, field, v)));
      } else if (Array.isArray(value) && value.length === 3 && value.every((v) => typeof v === 'number')) {
        const current = [...value];
        value.forEach((v, axis) => row.append(this.number(`${id}-${axis}`, v, (x) => { current[axis] = x; this.set(target, field, [...current]); })));
        if (COLOR_FIELDS.has(field)) {
          // The picker shows sRGB; values above 1 (emission) are scaled into it and back.
          const max = Math.max(...value, 1e-9);
          const scale = max > 1 ? max : 1;
          row.append(el('input', { id: `${id}-color`, type: 'color', value: toHex(value.map((v) => v / scale)), title: 'sRGB colour; the file stores linear values',
            onchange: (e) => this.set(target, field, fromHex(e.target.value).map((v) => Number.parseFloat((v * scale).toPrecision(4)))) }));
        }
      } else {
        // Vertices, textures, colour maps: edited as JSON.
        row.append(this.text(id, JSON.stringify(value), (text) => {
          try { this.set(target, field, JSON.parse(text)); } catch (err) { this.app.showMessage(`${field}: not valid JSON (${err.message})`); }
        }));
      }
      out.append(row);
    }
    return out;
  }

  /// Marks a field as typed in from the first key (so a redraw waits for it), and clears the
  /// mark when the value is sent.
  typed(input) {
    input.addEventListener('input', () => { input.dataset.typed = '1'; });
    return input;
  }

  text(id, value, onChange) {
    const input = this.typed(el('input', { id, type: 'text', value }));
    input.onchange = () => { delete input.dataset.typed; onChange(input.value); };
    return input;
  }

  number(id, value, onChange) {
    const input = this.typed(el('input', { id, type: 'number', step: 'any', value: String(value) }));
    input.onchange = () => {
      delete input.dataset.typed;
      // Cleared while typing: keep the old value, say nothing.
      if (input.value.trim() === '') { input.value = String(value); return; }
      const v = Number.parseFloat(input.value);
      if (Number.isFinite(v)) onChange(v); else this.app.showMessage('not a number');
    };
    return input;
  }

  /// `sel`: the selection entry, whose typed rotate and scale turn about its own centre.
  transform(target, t, sel) {
    const fs = el('fieldset', {}, el('legend', {}, 'Transform'));
    const translate = t.translate ? [...t.translate] : [0, 0, 0];
    const rotate = t.rotate ? [...t.rotate] : [0, 0, 0];
    const scale = t.scale === undefined ? [1, 1, 1] : Array.isArray(t.scale) ? [...t.scale] : [t.scale, t.scale, t.scale];
    const parts = { translate, rotate, scale };
    for (const [part, values] of Object.entries(parts)) {
      const row = el('div', { class: 'row' }, el('label', {}, part === 'rotate' ? 'rotate (degrees, X then Y then Z)' : part));
      values.forEach((v, axis) => row.append(this.number(`tf-${part}-${axis}`, v, (x) => {
        values[axis] = x;
        this.app.edit(this.app.typedTransform(sel, part, values));
      })));
      fs.append(row);
    }
    return fs;
  }
}

export class RenderDialog {
  constructor(dialog, app) {
    this.dialog = dialog;
    this.app = app;
    const $ = (id) => document.getElementById(id);
    this.status = $('render-status');
    this.progress = $('render-progress');
    this.image = $('render-image');
    $('render-close').onclick = () => dialog.close();
    $('render-start').onclick = () => this.start();
    $('render-cancel').onclick = () => this.post('api/render/cancel');
    this.passes = $('render-passes');
    this.seconds = $('render-seconds');
  }

  open() { this.dialog.showModal(); }

  async post(url, body) {
    const headers = { 'Content-Type': 'application/json' };
    if (this.app.token) headers.Authorization = `token ${this.app.token}`;
    const response = await fetch(url, { method: 'POST', headers, body: body ? JSON.stringify(body) : undefined });
    const reply = await response.json().catch(() => ({ ok: false, error: `request failed (${response.status})` }));
    if (!reply.ok) this.app.showMessage(reply.error);
    return reply.ok;
  }

  start() {
    const request = {};
    const passes = Number.parseInt(this.passes.value, 10);
    const seconds = Number.parseFloat(this.seconds.value);
    if (Number.isFinite(passes)) request.passes = passes;
    if (Number.isFinite(seconds)) request.seconds = seconds;
    this.post('api/render', request);
  }

  update(s) {
    const time = (t) => (t === null || t === undefined ? '–' : t < 60 ? `${t.toFixed(1)} s` : `${Math.floor(t / 60)} min ${Math.round(t % 60)} s`);
    const error = s.error_estimate === null || s.error_estimate === undefined ? 'needs 4 passes' : s.error_estimate.toExponential(2);
    if (s.state === 'idle') { this.status.textContent = 'idle'; return; }
    const total = s.seconds ? `${s.total_passes > 100000 ? '' : `/${s.total_passes}`} (${s.seconds} s budget)` : `/${s.total_passes}`;
    this.status.textContent = `${s.state}: pass ${s.passes}${total}, elapsed ${time(s.elapsed)}, remaining ${time(s.remaining)}, error estimate ${error}` +
      (s.message ? ` — ${s.message}` : '');
    document.body.dataset.renderState = s.state;
    let fraction = 0;
    if (s.state === 'done' || s.state === 'cancelled') fraction = 1;
    else if (s.remaining !== null && s.remaining !== undefined && s.elapsed) fraction = s.elapsed / (s.elapsed + s.remaining);
    this.progress.value = fraction;
  }

  setImage(blob) {
    const url = URL.createObjectURL(blob);
    this.image.onload = () => URL.revokeObjectURL(url);
    this.image.src = url;
  }
}
