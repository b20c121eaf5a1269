// The scene tree, the properties panel and the final-render dialog. Every field the properties
// panel shows is the file's own (as written); a change is sent as a `set` edit, and the panel
// redraws from the scene the server sends back, so a refused value snaps back.

const COLOR_FIELDS = new Set(['reflectance', 'tint', 'emission', 'radiance', 'intensity', 'irradiance', 'color']);
const HIDDEN_FIELDS = new Set(['type', 'transform']);
// The fields of each material type that a texture may drive (besides `opacity` and `emission`),
// and those read as data (linear) rather than colour (sRGB).
const TEXTURE_FIELDS = {
  diffuse: ['reflectance'], plastic: ['reflectance', 'roughness'], mirror: ['tint'],
  conductor: ['roughness'], dielectric: ['roughness'], mix: ['weight'],
};
const DATA_FIELDS = new Set(['roughness', 'opacity', 'weight']);

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

  render(scene, sel) {
    if (!scene) return;
    this.root.innerHTML = '';
    const item = (label, target, id) => {
      const selected = sel && sel.kind === target.kind && (sel.index === target.index && sel.name === target.name);
      return el('li', { class: `item${selected ? ' selected' : ''}`, id, onclick: () => this.app.select(target) }, label);
    };
    const section = (title, items) => {
      const ul = el('ul');
      items.forEach((i) => ul.append(i));
      return el('li', { class: 'section' }, title, ul);
    };
    this.root.append(item('Camera', { kind: 'camera' }, 'tree-camera'));
    this.root.append(section('Shapes', scene.shapes.map((s, i) =>
      item(`${nameOf(s, `shape ${i}`)} (${s.fields.type})`, { kind: 'shape', index: i }, `tree-shape-${i}`))));
    this.root.append(section('Lights', scene.lights.map((l, i) =>
      item(`${nameOf(l, `light ${i}`)} (${l.fields.type})`, { kind: 'light', index: i }, `tree-light-${i}`))));
    const instances = scene.instances || [];
    if (instances.length) {
      this.root.append(section('Instances', instances.map((inst, i) =>
        item(`${nameOf(inst, `instance ${i}`)} (${inst.object}${inst.copies === 1 ? '' : ` ×${inst.copies}`})`,
          { kind: 'instance', index: i }, `tree-instance-${i}`))));
    }
    this.root.append(section('Materials', scene.materials.map((m) =>
      item(`${m.name} (${m.fields.type})`, { kind: 'material', name: m.name }, `tree-material-${m.name}`))));
  }
}

function toHex(rgb) {
  const c = (v) => Math.round(Math.min(1, Math.max(0, v)) * 255).toString(16).padStart(2, '0');
  return `#${c(rgb[0])}${c(rgb[1])}${c(rgb[2])}`;
}

function fromHex(hex) {
  return [1, 3, 5].map((i) => Number.parseFloat((parseInt(hex.slice(i, i + 2), 16) / 255).toPrecision(4)));
}

export class Properties {
  constructor(root, app) { this.root = root; this.app = app; }

  render(scene, sel) {
    this.root.innerHTML = '';
    if (!scene || !sel) {
      this.root.append(el('p', { class: 'hint' }, 'Select an object in the viewport or the tree.'));
      return;
    }
    if (sel.kind === 'shape' || sel.kind === 'light' || sel.kind === 'instance') {
      const list = sel.kind === 'shape' ? scene.shapes : sel.kind === 'light' ? scene.lights : scene.instances || [];
      const entry = list[sel.index];
      if (!entry) return;
      const target = { [sel.kind]: sel.index };
      const title = sel.kind === 'instance'
        ? `${nameOf(entry, `instance ${sel.index}`)}: object "${entry.object}"`
        : `${nameOf(entry, `${sel.kind} ${sel.index}`)}: ${entry.fields.type}`;
      this.root.append(this.fieldset(title, target, entry.fields, scene, 'obj'));
      if (sel.kind === 'instance') this.root.append(this.instanceNote(entry));
      const hasTransform = sel.kind !== 'light' || entry.fields.type === 'area';
      if (hasTransform) this.root.append(this.transform(target, entry.fields.transform || {}));
      const material = entry.fields.material && scene.materials.find((m) => m.name === entry.fields.material);
      if (material) this.root.append(this.material(material, scene));
    } else if (sel.kind === 'material') {
      const material = scene.materials.find((m) => m.name === sel.name);
      if (material) this.root.append(this.material(material, scene));
    } else if (sel.kind === 'camera') {
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

  material(material, scene) {
    const fs = this.fieldset(`Material "${material.name}": ${material.fields.type}`, { material: material.name }, material.fields, scene, 'mat');
    if (material.fields.type !== 'null') fs.append(this.texturePicker(material));
    return fs;
  }

  /// A texture for one of the material's fields: an image file of the scene's folder (the
  /// server adds the `[textures.*]` table and checks the path).
  texturePicker(material) {
    const fields = [...(TEXTURE_FIELDS[material.fields.type] || []), 'opacity', 'emission'];
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
      this.app.edit({ op: 'set_texture', material: material.name, field: field.value, file: file.value, linear: DATA_FIELDS.has(field.value) });
    };
    return el('div', { class: 'row texture' }, el('label', {}, 'texture'), field, file);
  }

  set(target, field, value) {
    this.app.edit({ op: 'set', target, field, value });
  }

  /// One row per field of `fields`, each input named `prefix-field[-axis]`.
  fieldset(title, target, fields, scene, prefix) {
    const fs = el('fieldset', {}, el('legend', {}, title));
    for (const [field, value] of Object.entries(fields || {})) {
      if (HIDDEN_FIELDS.has(field)) continue;
      const row = el('div', { class: 'row' }, el('label', {}, field));
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
        row.append(el('input', { id, type: 'text', value, onchange: (e) => this.set(target, field, e.target.value) }));
      } else if (Array.isArray(value) && value.length === 3 && value.every((v) => typeof v === 'number')) {
        const current = [...value];
        value.forEach((v, axis) => row.append(this.number(`${id}-${axis}`, v, (x) => { current[axis] = x; this.set(target, field, [...current]); })));
        if (COLOR_FIELDS.has(field)) {
          const max = Math.max(...value, 1e-9);
          const scale = max > 1 ? max : 1;
          row.append(el('input', { id: `${id}-color`, type: 'color', value: toHex(value.map((v) => v / scale)),
            onchange: (e) => this.set(target, field, fromHex(e.target.value).map((v) => Number.parseFloat((v * scale).toPrecision(4)))) }));
        }
      } else if (COLOR_FIELDS.has(field) && typeof value === 'number') {
        row.append(this.number(id, value, (v) => this.set(target, field, v)));
      } else {
        // Vertices, textures, colour maps: edited as JSON.
        row.append(el('input', { id, type: 'text', value: JSON.stringify(value), onchange: (e) => {
          try { this.set(target, field, JSON.parse(e.target.value)); } catch (err) { this.app.showMessage(`${field}: not valid JSON (${err.message})`); }
        } }));
      }
      fs.append(row);
    }
    return fs;
  }

  number(id, value, onChange) {
    const input = el('input', { id, type: 'number', step: 'any', value: String(value) });
    input.onchange = () => {
      // Cleared while typing: keep the old value, say nothing.
      if (input.value.trim() === '') { input.value = String(value); return; }
      const v = Number.parseFloat(input.value);
      if (Number.isFinite(v)) onChange(v); else this.app.showMessage('not a number');
    };
    return input;
  }

  transform(target, t) {
    const fs = el('fieldset', {}, el('legend', {}, 'Transform'));
    const translate = t.translate ? [...t.translate] : [0, 0, 0];
    const rotate = t.rotate ? [...t.rotate] : [0, 0, 0];
    const scale = t.scale === undefined ? [1, 1, 1] : Array.isArray(t.scale) ? [...t.scale] : [t.scale, t.scale, t.scale];
    const parts = { translate, rotate, scale };
    for (const [part, values] of Object.entries(parts)) {
      const row = el('div', { class: 'row' }, el('label', {}, part === 'rotate' ? 'rotate (degrees, X then Y then Z)' : part));
      values.forEach((v, axis) => row.append(this.number(`tf-${part}-${axis}`, v, (x) => {
        values[axis] = x;
        this.app.edit({ op: 'set_transform', target, [part]: [...values] });
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
