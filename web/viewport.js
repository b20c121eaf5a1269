// The 3D viewport: the scene's triangles drawn with three.js (solid shading) or the server's
// rendered frames behind the overlays (rendered shading), one perspective view or four views
// (top, front, side, perspective), a grid and axes, click selection with a silhouette outline, and
// translate / rotate / scale gizmos whose result is sent to the server as an edit. The gizmo
// pivots on the selection's own centre (its bounding box's), one gizmo for a multi-selection or a
// group. The view is drawn only when something changed (no redraw while the page is idle).

import * as THREE from './vendor/three.module.min.js';
import { OrbitControls } from './vendor/OrbitControls.min.js';
import { TransformControls } from './vendor/TransformControls.min.js';

const DEG = Math.PI / 180;
// The scene format's rotation is world_from_object = T Rz Ry Rx S: three.js's Euler order 'ZYX'
// is the matrix Rz Ry Rx.
const EULER_ORDER = 'ZYX';
const OUTLINE_COLOR = 0xffa640;

// Seven significant digits, and 0 for what is float noise next to 0 (a turn of 90 degrees
// leaves 1.7e-11 where the matrix has 0), so the file reads as typed.
function round(v) { const r = Number.parseFloat(Number(v).toPrecision(7)); return Math.abs(r) < 1e-9 ? 0 : r; }
// Angles in degrees: to a millionth of a degree, so 1e-14 from a matrix reads back as 0.
function roundAngle(v) { return round(Math.round(v * 1e6) / 1e6); }

/// The Euler angles (radians, order ZYX) of quaternion `q` nearest to `typed` (degrees, as the
/// file has them): a rotation has two Euler triples, each up to turns of 360 degrees, and the
/// matrix's own pick ([180, 43, 180] for a turn of 137 degrees about Y) reads nothing like what
/// was typed. Returns degrees.
export function eulerNearest(q, typed) {
  const e = new THREE.Euler().setFromQuaternion(q, EULER_ORDER);
  const a = [e.x, e.y, e.z].map((r) => r / DEG);
  const b = [a[0] + 180, 180 - a[1], a[2] + 180];
  const near = (v, t) => v + 360 * Math.round((t - v) / 360);
  const fit = (c) => c.map((v, i) => near(v, typed[i]));
  const dist = (c) => c.reduce((s, v, i) => s + (v - typed[i]) ** 2, 0);
  const [ca, cb] = [fit(a), fit(b)];
  return (dist(ca) <= dist(cb) ? ca : cb).map(roundAngle);
}

/// The key of a selection entry: "shape:7" (its stable id), "material:red", "camera".
export function keyOf(sel) {
  if (!sel) return '';
  if (sel.kind === 'camera') return 'camera';
  if (sel.kind === 'material') return `material:${sel.name}`;
  return `${sel.kind}:${sel.id}`;
}

export class Viewport {
  constructor(canvas, labels, app) {
    this.canvas = canvas;
    this.labels = labels;
    this.app = app;
    this.rendered = true;
    this.quad = false;
    this.snap = false;
    this.selection = [];
    this.hidden = new Set();      // keys of entries hidden in this tab's solid view
    this.draws = 0;               // views drawn, for the idle test
    this.frameTexture = null;
    this.frameAspect = 1;
    this.objects = [];          // { holder, mesh, target, kind }
    this.pickables = [];
    this.lastViewSent = '';

    this.pivot = new THREE.Object3D();   // what the gizmo moves; the selection follows it
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
    this.renderer.setScissorTest(true);
    this.scene = new THREE.Scene();
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x444450, 2.2));
    this.headlight = new THREE.DirectionalLight(0xffffff, 1.2);
    this.scene.add(this.headlight);
    this.content = new THREE.Group();
    this.scene.add(this.content);
    this.helpers = new THREE.Group();
    this.scene.add(this.helpers);

    // Views: the perspective one is orbited; the orthographic ones pan and zoom.
    this.perspective = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
    this.views = [
      { name: 'Top', camera: new THREE.OrthographicCamera(), dir: [0, 1, 0], up: [0, 0, -1], layer: 1 },
      { name: 'Front', camera: new THREE.OrthographicCamera(), dir: [0, 0, 1], up: [0, 1, 0], layer: 2 },
      { name: 'Right', camera: new THREE.OrthographicCamera(), dir: [1, 0, 0], up: [0, 1, 0], layer: 3 },
      { name: 'Perspective', camera: this.perspective, layer: 1 },
    ];
    // Our pointer listener first, so the view under the pointer owns the gesture.
    canvas.addEventListener('pointerdown', (e) => this.onPointerDown(e));
    canvas.addEventListener('pointerup', (e) => this.onPointerUp(e));
    canvas.addEventListener('pointermove', (e) => this.onPointerMove(e));
    // The rectangle of a box selection.
    this.boxDiv = document.createElement('div');
    this.boxDiv.id = 'box-select';
    canvas.parentElement.appendChild(this.boxDiv);
    for (const view of this.views) {
      view.camera.layers.enable(view.layer);
      view.controls = new OrbitControls(view.camera, canvas);
      view.controls.enableDamping = false;
      if (view.camera.isOrthographicCamera) {
        view.controls.enableRotate = false;
        view.controls.screenSpacePanning = true;
      }
      view.controls.addEventListener('change', () => {
        if (view.camera === this.perspective) this.sendView();
        this.requestDraw();
      });
    }
    this.activeView = this.views[3];

    this.gizmo = new TransformControls(this.perspective, canvas);
    this.gizmo.setSize(0.9);
    this.gizmo.addEventListener('dragging-changed', (e) => {
      for (const view of this.views) view.controls.enabled = !e.value;
      if (e.value) this.startGizmo(); else this.commitGizmo();
    });
    this.gizmo.addEventListener('objectChange', () => this.followGizmo());
    this.gizmo.addEventListener('change', () => this.requestDraw());
    this.scene.add(this.pivot);
    this.gizmoHelper = this.gizmo.getHelper();
    this.scene.add(this.gizmoHelper);
    this.makeOutlinePass();

    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
    this.requestDraw();
  }

  /// Draws at the next animation frame, once however often it is asked; nothing else draws, so
  /// an idle page costs nothing.
  requestDraw() {
    if (this.drawPending) return;
    this.drawPending = true;
    requestAnimationFrame(() => {
      this.drawPending = false;
      this.draw();
    });
  }

  // Layout -------------------------------------------------------------------------------------

  /// The rectangles of the visible views in CSS pixels, origin at the top left.
  rects() {
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    if (!this.quad) return [{ view: this.views[3], x: 0, y: 0, w, h }];
    const hw = Math.floor(w / 2), hh = Math.floor(h / 2);
    return [
      { view: this.views[0], x: 0, y: 0, w: hw, h: hh },
      { view: this.views[1], x: hw, y: 0, w: w - hw, h: hh },
      { view: this.views[2], x: 0, y: hh, w: hw, h: h - hh },
      { view: this.views[3], x: hw, y: hh, w: w - hw, h: h - hh },
    ];
  }

  resize() {
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    if (!w || !h) return;
    this.renderer.setSize(w, h, false);
    this.labels.innerHTML = '';
    for (const r of this.rects()) {
      if (this.quad) {
        const label = document.createElement('div');
        label.className = 'label';
        label.style.left = `${r.x + 6}px`;
        label.style.top = `${r.y + 4}px`;
        label.textContent = r.view.name;
        this.labels.appendChild(label);
      }
      this.fitCamera(r.view.camera, r.w, r.h);
    }
    this.sendView(true);
    this.requestDraw();
  }

  fitCamera(camera, w, h) {
    const aspect = w / Math.max(h, 1);
    if (camera.isPerspectiveCamera) {
      camera.aspect = aspect;
    } else {
      const half = camera.userData.half || 1;
      camera.left = -half * aspect; camera.right = half * aspect; camera.top = half; camera.bottom = -half;
    }
    camera.updateProjectionMatrix();
  }

  setQuad(quad) { this.quad = quad; this.resize(); }

  /// Solid or rendered shading. The server goes on refining the same view meanwhile (it
  /// ignores a view it renders already), so switching back does not restart the preview.
  setRendered(rendered) {
    this.rendered = rendered;
    if (rendered && this.pendingFrame) this.setFrame(this.pendingFrame);
    if (rendered) this.sendView(true);
    this.requestDraw();
  }

  /// Wireframe shading of the solid view: every surface drawn as its triangles' edges.
  setWireframe(on) {
    this.wireframe = on;
    for (const o of this.objects) {
      if (o.kind !== 'mesh' && o.kind !== 'area') continue;
      for (const m of [o.mesh.material].flat()) m.wireframe = on;
    }
    this.requestDraw();
  }

  /// The mouse scheme: 'default' (left drag orbits, right or Shift+left pans) or 'blender'
  /// (middle drag orbits, Shift+middle pans, the left button only selects and drags gizmos).
  setNavigation(scheme) {
    this.navigation = scheme;
    const buttons = scheme === 'blender'
      ? { LEFT: null, MIDDLE: THREE.MOUSE.ROTATE, RIGHT: null }
      : { LEFT: THREE.MOUSE.ROTATE, MIDDLE: THREE.MOUSE.DOLLY, RIGHT: THREE.MOUSE.PAN };
    for (const view of this.views) {
      // The orthographic views pan with the orbit button (they do not turn).
      view.controls.mouseButtons = view.camera.isOrthographicCamera && scheme === 'blender'
        ? { LEFT: null, MIDDLE: THREE.MOUSE.PAN, RIGHT: null } : { ...buttons };
    }
  }

  /// Blender's numpad views in the perspective view: 1 front, 3 right, 7 top; `opposite` (Ctrl)
  /// back, left, bottom. The distance to the orbit centre stays.
  axisView(key, opposite) {
    const dirs = { 1: [0, 0, 1], 3: [1, 0, 0], 7: [0, 1, 0] };
    const d = dirs[key];
    if (!d) return;
    const view = this.views[3];
    const distance = this.perspective.position.distanceTo(view.controls.target);
    const dir = new THREE.Vector3(...d).multiplyScalar(opposite ? -1 : 1);
    this.perspective.up.set(0, 1, 0);
    if (key === 7) this.perspective.up.set(0, 0, opposite ? 1 : -1);
    this.perspective.position.copy(view.controls.target).addScaledVector(dir, distance);
    this.perspective.lookAt(view.controls.target);
    view.controls.update();
    this.sendView(true);
    this.requestDraw();
  }

  setHidden(keys) {
    this.hidden = new Set(keys);
    this.requestDraw();
  }

  setSnap(snap) {
    this.snap = snap;
    this.applySnap();
  }

  setMode(mode) {
    this.mode = mode;
    this.gizmo.setMode(mode);
    this.applySnap();
    this.setSelection(this.selection);
  }

  applySnap() {
    const step = this.gridStep || 0.1;
    this.gizmo.setTranslationSnap(this.snap ? step : null);
    this.gizmo.setRotationSnap(this.snap ? 15 * DEG : null);
    this.gizmo.setScaleSnap(this.snap ? 0.1 : null);
  }

  // The scene ----------------------------------------------------------------------------------

  setScene(scene, first) {
    this.sceneData = scene;
    for (const o of this.objects) {
      o.holder.traverse((c) => { if (c.geometry) c.geometry.dispose(); });
      this.content.remove(o.holder);
    }
    this.objects = [];
    this.pickables = [];
    const lo = new THREE.Vector3(...scene.bounds.min), hi = new THREE.Vector3(...scene.bounds.max);
    const extent = Math.max(lo.distanceTo(hi), 1e-3);
    this.extent = extent;
    scene.shapes.forEach((shape, index) => this.addEntry(shape, { kind: 'shape', index, id: shape.id }));
    scene.lights.forEach((light, index) => this.addLight(light, { kind: 'light', index, id: light.id }));
    (scene.instances || []).forEach((instance, index) => this.addEntry(instance, { kind: 'instance', index, id: instance.id }));
    this.addCamera(scene.camera);
    this.buildGrid(lo, hi, extent);
    if (first) {
      this.viewThroughCamera();
      this.frameOrtho(lo, hi, extent);
    }
    this.setSelection(this.selection);
    this.requestDraw();
  }

  /// A holder at the entry's transform, with its world triangles mapped into the holder's space.
  makeHolder(fields) {
    const holder = new THREE.Object3D();
    const t = fields.transform || {};
    if (t.translate) holder.position.set(...t.translate);
    if (t.rotate) holder.rotation.set(t.rotate[0] * DEG, t.rotate[1] * DEG, t.rotate[2] * DEG, EULER_ORDER);
    else holder.rotation.order = EULER_ORDER;
    if (t.scale !== undefined) {
      if (Array.isArray(t.scale)) holder.scale.set(...t.scale); else holder.scale.setScalar(t.scale);
    }
    holder.updateMatrix();
    return holder;
  }

  meshOf(positions, holder, material) {
    const geometry = new THREE.BufferGeometry();
    const array = new Float32Array(positions);
    geometry.setAttribute('position', new THREE.BufferAttribute(array, 3));
    geometry.applyMatrix4(holder.matrix.clone().invert());
    geometry.computeVertexNormals();
    return new THREE.Mesh(geometry, material);
  }

  addEntry(entry, target) {
    const holder = this.makeHolder(entry.fields);
    const surface = (rgb, emissive) => {
      const color = new THREE.Color(...rgb);
      return emissive
        ? new THREE.MeshBasicMaterial({ color, side: THREE.DoubleSide })
        : new THREE.MeshLambertMaterial({ color, side: THREE.DoubleSide });
    };
    // An entry of several materials (a CSG object's leaves, an instanced object's shapes)
    // comes in groups of triangles, one colour each.
    const groups = entry.groups && entry.groups.length ? entry.groups : null;
    const material = groups ? groups.map((g) => surface(g.color, g.emissive)) : surface(entry.color, entry.emissive);
    if (this.wireframe) for (const m of [material].flat()) m.wireframe = true;
    const mesh = this.meshOf(entry.positions, holder, material);
    if (groups) groups.forEach((g, i) => mesh.geometry.addGroup(g.start * 3, g.count * 3, i));
    holder.add(mesh);
    this.content.add(holder);
    const object = { holder, mesh, target, kind: 'mesh' };
    mesh.userData.object = object;
    this.objects.push(object);
    this.pickables.push(mesh);
    return object;
  }

  addLight(light, target) {
    if (light.kind === 'area') {
      const object = this.addEntry({ ...light, color: [1, 0.95, 0.7], emissive: true }, target);
      object.kind = 'area';
      return;
    }
    const holder = new THREE.Object3D();
    holder.rotation.order = EULER_ORDER;
    const size = this.extent * 0.02;
    const icon = new THREE.Mesh(new THREE.OctahedronGeometry(size), new THREE.MeshBasicMaterial({ color: 0xffe080, wireframe: true }));
    holder.add(icon);
    const lo = new THREE.Vector3(...this.sceneData.bounds.min), hi = new THREE.Vector3(...this.sceneData.bounds.max);
    const position = light.position ? new THREE.Vector3(...light.position)
      : new THREE.Vector3((lo.x + hi.x) / 2, hi.y + this.extent * 0.1, (lo.z + hi.z) / 2);
    holder.position.copy(position);
    if (light.direction) {
      const dir = new THREE.Vector3(...light.direction).normalize();
      holder.add(new THREE.ArrowHelper(dir, new THREE.Vector3(), this.extent * 0.12, 0xffe080));
    }
    this.content.add(holder);
    const object = { holder, mesh: icon, target, kind: light.kind };
    icon.userData.object = object;
    this.objects.push(object);
    this.pickables.push(icon);
  }

  addCamera(camera) {
    const holder = new THREE.Object3D();
    holder.position.set(...camera.position);
    const size = this.extent * 0.05;
    const geometry = new THREE.ConeGeometry(size * 0.7, size, 4, 1, true);
    geometry.rotateX(-Math.PI / 2);
    geometry.rotateZ(Math.PI / 4);
    geometry.translate(0, 0, -size / 2);
    const body = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({ color: 0x90c0ff, wireframe: true }));
    // Point the cone along the camera's view.
    const m = new THREE.Matrix4().lookAt(new THREE.Vector3(...camera.position), new THREE.Vector3(...camera.look_at), new THREE.Vector3(...camera.up));
    body.quaternion.setFromRotationMatrix(m);
    holder.add(body);
    this.content.add(holder);
    this.cameraIcon = holder;
    const object = { holder, mesh: body, target: { kind: 'camera', id: 'camera' }, kind: 'camera' };
    body.userData.object = object;
    this.objects.push(object);
    this.pickables.push(body);
  }

  buildGrid(lo, hi, extent) {
    this.helpers.clear();
    // Grid lines at a power of ten of the scene's size.
    const step = 10 ** Math.floor(Math.log10(extent / 4));
    this.gridStep = step;
    const size = Math.ceil((extent * 2) / step) * step;
    const divisions = Math.round(size / step);
    const centre = new THREE.Vector3().addVectors(lo, hi).multiplyScalar(0.5);
    const snapTo = (v) => Math.round(v / step) * step;
    const grids = [
      { layer: 1, rotate: null, pos: [snapTo(centre.x), lo.y, snapTo(centre.z)] },
      { layer: 2, rotate: [Math.PI / 2, 0, 0], pos: [snapTo(centre.x), snapTo(centre.y), lo.z] },
      { layer: 3, rotate: [0, 0, Math.PI / 2], pos: [lo.x, snapTo(centre.y), snapTo(centre.z)] },
    ];
    for (const g of grids) {
      const grid = new THREE.GridHelper(size, divisions, 0x6a6f78, 0x3a3e45);
      grid.userData.grid = true;
      if (g.rotate) grid.rotation.set(...g.rotate);
      grid.position.set(...g.pos);
      grid.layers.set(g.layer);
      this.helpers.add(grid);
    }
    const axes = new THREE.AxesHelper(extent * 0.25);
    // Hidden over the render too (with the grids): nothing of the editor's drawn over the image
    // but the selection.
    axes.userData.grid = true;
    axes.layers.enableAll();
    this.helpers.add(axes);
    this.applySnap();
  }

  frameOrtho(lo, hi, extent) {
    const centre = new THREE.Vector3().addVectors(lo, hi).multiplyScalar(0.5);
    for (const view of this.views.slice(0, 3)) {
      const c = view.camera;
      c.userData.half = extent * 0.6;
      c.position.copy(centre).addScaledVector(new THREE.Vector3(...view.dir), extent * 2);
      c.up.set(...view.up);
      c.near = -extent * 10; c.far = extent * 10;
      view.controls.target.copy(centre);
      c.lookAt(centre);
      view.controls.update();
    }
    this.perspective.near = extent * 1e-3;
    this.perspective.far = extent * 100;
    this.resize();
  }

  // Cameras ------------------------------------------------------------------------------------

  viewThroughCamera() {
    const cam = this.sceneData && this.sceneData.camera;
    if (!cam) return;
    const view = this.views[3];
    this.perspective.position.set(...cam.position);
    this.perspective.up.set(...cam.up).normalize();
    this.perspective.fov = cam.projection === 'perspective' ? cam.fov : 45;
    view.controls.target.set(...cam.look_at);
    // A look_at next to the eye (a glTF camera's is 1 mm ahead) would make the orbit turn
    // about the eye: orbit about the point of the view's axis nearest the scene's centre.
    const eye = this.perspective.position;
    const ahead = view.controls.target.clone().sub(eye);
    if (this.extent && ahead.length() < this.extent * 0.05 && ahead.length() > 0) {
      const b = this.sceneData.bounds;
      const centre = new THREE.Vector3(...b.min).add(new THREE.Vector3(...b.max)).multiplyScalar(0.5);
      const dir = ahead.normalize();
      const distance = Math.max(centre.sub(eye).dot(dir), this.extent * 0.25);
      view.controls.target.copy(eye).addScaledVector(dir, distance);
    }
    this.perspective.lookAt(view.controls.target);
    this.perspective.updateProjectionMatrix();
    view.controls.update();
    this.sendView(true);
    this.requestDraw();
  }

  /// Points the perspective view at the selection (or the whole scene) from where it looks now,
  /// close enough that it fills about two thirds of the view.
  frameSelected() {
    const box = new THREE.Box3();
    const objects = this.selection.length ? this.selection.map((s) => this.objectOf(s)).filter(Boolean) : this.objects;
    for (const o of objects) box.union(this.worldBox(o));
    if (box.isEmpty()) return;
    const centre = box.getCenter(new THREE.Vector3());
    const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, this.extent * 1e-3);
    const view = this.views[3];
    const dir = this.perspective.position.clone().sub(view.controls.target).normalize();
    const distance = radius / Math.sin((this.perspective.fov * DEG) / 2) * 1.1;
    view.controls.target.copy(centre);
    this.perspective.position.copy(centre).addScaledVector(dir, distance);
    this.perspective.lookAt(centre);
    view.controls.update();
    for (const v of this.views.slice(0, 3)) {
      v.controls.target.copy(centre);
      v.camera.position.copy(centre).addScaledVector(new THREE.Vector3(...v.dir), this.extent * 2);
      v.camera.userData.half = radius * 1.3;
      v.camera.zoom = 1;
    }
    this.resize();
    this.sendView(true);
  }

  /// The point new things go: in front of the view where its centre meets the scene, else at
  /// its orbit centre (or closer, within
  /// the scene's size); moved sideways past anything already there, then dropped onto the
  /// surface facing up below it, when there is one (`floor` is then true and the point is on
  /// it): things stand on the floor, not half under it.
  placement(size) {
    const view = this.views[3];
    const forward = view.controls.target.clone().sub(this.perspective.position);
    const distance = Math.min(forward.length(), this.extent);
    forward.normalize();
    let base = this.perspective.position.clone().addScaledVector(forward, distance);
    const surfaces = this.pickables.filter((m) => ['mesh', 'area'].includes(m.userData.object.kind) && !this.hidden.has(keyOf(m.userData.object.target)));
    const raycaster = new THREE.Raycaster();
    const up = (hit) => hit.face && Math.abs(hit.face.normal.clone().transformDirection(hit.object.matrixWorld).y) > 0.7;
    raycaster.set(this.perspective.position, forward);
    const [ahead] = raycaster.intersectObjects(surfaces, false);
    // What the view's centre meets (an object there is stepped past sideways below).
    if (ahead && ahead.distance < this.extent * 3) base = ahead.point.clone();
    const right = new THREE.Vector3().crossVectors(forward, this.perspective.up).normalize();
    // Things there already: their boxes grown by the new thing's size; floors and walls (a side
    // more than half the scene across) do not count, everything stands on or beside them.
    const boxes = this.objects.filter((o) => o.kind === 'mesh' || o.kind === 'area').map((o) => this.worldBox(o))
      .filter((b) => { const d = b.getSize(new THREE.Vector3()); return Math.max(d.x, d.y, d.z) < this.extent * 0.5; })
      .map((b) => b.expandByScalar(size));
    // The floor below a point (from a little above, so a point on it finds it).
    const floorBelow = (q) => {
      raycaster.set(q.clone().setY(q.y + size * 0.01), new THREE.Vector3(0, -1, 0));
      return raycaster.intersectObjects(surfaces, false).find((hit) => up(hit) && hit.distance < this.extent);
    };
    // The nearest free place with a floor under it, else the nearest free place.
    // Sideways first, then in rows nearer the view (flat along the floor).
    const nearer = new THREE.Vector3(-forward.x, 0, -forward.z);
    if (nearer.lengthSq() > 1e-6) nearer.normalize();
    let free = null;
    for (let n = 0; n < 40 * 3; n++) {
      const k = n % 40, row = Math.floor(n / 40);
      const step = (k % 2 ? 1 : -1) * Math.ceil(k / 2);
      if (Math.abs(step) > 6 && row > 0) continue;
      const q = base.clone().addScaledVector(right, step * size * 2.5).addScaledVector(nearer, row * size * 2.5);
      if (boxes.some((b) => b.containsPoint(q))) continue;
      const below = floorBelow(q);
      // Standing there: its own box (a size around the point above the floor) clear too.
      if (below && !boxes.some((b) => b.containsPoint(below.point.clone().setY(below.point.y + size)))) {
        return { point: below.point.toArray().map(round), floor: true };
      }
      if (!free) free = q;
    }
    return { point: (free || base).toArray().map(round), floor: false };
  }

  /// The centre of a new thing of half-size `size` (`placement`, lifted onto the floor).
  placementPoint(size) {
    const { point, floor } = this.placement(size);
    if (floor) point[1] = round(point[1] + size);
    return point;
  }

  /// How far a duplicate of `list` moves: along x by the selection's width and a tenth more
  /// (a twentieth of the scene for something flat along x), so the copy sits beside it.
  duplicateOffset(list) {
    const box = new THREE.Box3();
    for (const s of list) { const o = this.objectOf(s); if (o) box.union(this.worldBox(o)); }
    const width = box.isEmpty() ? 0 : box.max.x - box.min.x;
    return [round(Math.max(width * 1.1, this.extent * 0.05)), 0, 0];
  }

  cameraToView() {
    const p = this.perspective;
    const target = this.views[3].controls.target;
    this.app.edit({
      op: 'set_fields', target: 'camera',
      fields: { position: p.position.toArray().map(round), look_at: target.toArray().map(round), up: p.up.toArray().map(round), fov: round(p.fov) },
    });
  }

  /// Tells the server where the perspective view looks (throttled), for the rendered preview.
  sendView(force = false) {
    if (!this.rendered || !this.sceneData) return;
    const r = this.rects().find((x) => x.view === this.views[3]);
    if (!r || r.w < 1 || r.h < 1) return;
    const p = this.perspective;
    const view = {
      position: p.position.toArray(), look_at: this.views[3].controls.target.toArray(), up: p.up.toArray(),
      fov: p.fov, width: Math.round(r.w), height: Math.round(r.h),
    };
    const key = JSON.stringify(view);
    if (key === this.lastViewSent && !force) return;
    const now = performance.now();
    clearTimeout(this.viewTimer);
    const wait = Math.max(0, 80 - (now - (this.lastViewTime || 0)));
    this.viewTimer = setTimeout(() => {
      this.lastViewTime = performance.now();
      this.lastViewSent = key;
      this.frameAspect = view.width / view.height;
      this.app.sendView(view);
    }, force ? 0 : wait);
  }

  /// A rendered frame: decoded and drawn in Rendered shading; in Solid shading only kept (the
  /// last one), so frames arriving while it is not shown cost no decoding.
  setFrame(blob) {
    if (!this.rendered) { this.pendingFrame = blob; return; }
    this.pendingFrame = null;
    const url = URL.createObjectURL(blob);
    const image = new Image();
    image.onload = () => {
      const texture = new THREE.Texture(image);
      texture.colorSpace = THREE.SRGBColorSpace;
      texture.needsUpdate = true;
      if (this.frameTexture) this.frameTexture.dispose();
      this.frameTexture = texture;
      URL.revokeObjectURL(url);
      if (this.rendered) this.requestDraw();
    };
    image.src = url;
  }

  // Selection and gizmos -----------------------------------------------------------------------

  /// The selection outline is its silhouette: the selected object drawn alone, flat white, into
  /// a mask (`outlineMask`), then a full-view pass paints the mask's outside border, a few pixels
  /// wide, over the view. The whole silhouette shows, parts behind other objects included, as
  /// in the modelling tools, and it works for every shape (a sphere has no edges to draw).
  makeOutlinePass() {
    this.outlineMask = new THREE.WebGLRenderTarget(1, 1, { depthBuffer: false });
    this.outlineMask.scissorTest = true;
    this.maskMaterial = new THREE.MeshBasicMaterial({ color: 0xffffff, side: THREE.DoubleSide, wireframe: false });
    this.outlineQuad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), new THREE.ShaderMaterial({
      uniforms: { mask: { value: this.outlineMask.texture }, size: { value: new THREE.Vector2(1, 1) },
        // Written to the canvas as is (no colour management in this pass): OUTLINE_COLOR's sRGB bytes.
        color: { value: new THREE.Color().setRGB(...[16, 8, 0].map((b) => ((OUTLINE_COLOR >> b) & 255) / 255), THREE.LinearSRGBColorSpace) },
        radius: { value: 2 } },
      vertexShader: 'void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }',
      fragmentShader: `
        uniform sampler2D mask; uniform vec2 size; uniform vec3 color; uniform int radius;
        void main() {
          vec2 uv = gl_FragCoord.xy / size;
          if (texture2D(mask, uv).r > 0.5) discard;
          float near = 0.0;
          for (int i = -3; i <= 3; i++) for (int j = -3; j <= 3; j++) {
            if (abs(i) > radius || abs(j) > radius || i * i + j * j > radius * radius + 1) continue;
            near = max(near, texture2D(mask, uv + vec2(float(i), float(j)) / size).r);
          }
          if (near < 0.5) discard;
          gl_FragColor = vec4(color, 1.0);
        }`,
      depthTest: false, depthWrite: false, toneMapped: false,
    }));
    this.outlineQuad.frustumCulled = false;
    this.outlineScene = new THREE.Scene();
    this.outlineScene.add(this.outlineQuad);
    this.outlineCamera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
    this.outlineLayer = 7;
  }

  /// Draws the selection's silhouettes into the view rectangle (x, y from the bottom, CSS pixels).
  drawOutline(camera, x, y, w, h) {
    const objects = this.selection.map((s) => this.objectOf(s)).filter((o) => o && !this.hidden.has(keyOf(o.target)));
    if (!objects.length) return;
    const ratio = this.renderer.getPixelRatio();
    const size = this.renderer.getDrawingBufferSize(new THREE.Vector2());
    if (this.outlineMask.width !== size.x || this.outlineMask.height !== size.y) this.outlineMask.setSize(size.x, size.y);
    this.outlineMask.viewport.set(x * ratio, y * ratio, w * ratio, h * ratio);
    this.outlineMask.scissor.copy(this.outlineMask.viewport);
    // The selected objects alone, in white on black, seen by this view's camera (the axes and
    // the gizmo are on every layer, so they are hidden).
    const visible = objects.map((o) => o.mesh.visible), background = this.scene.background, layers = camera.layers.mask;
    for (const o of objects) { o.mesh.visible = true; o.mesh.layers.enable(this.outlineLayer); }
    this.helpers.visible = false;
    this.gizmoHelper.visible = false;
    camera.layers.set(this.outlineLayer);
    this.scene.background = null;
    this.scene.overrideMaterial = this.maskMaterial;
    const clear = this.renderer.getClearColor(new THREE.Color()), alpha = this.renderer.getClearAlpha();
    this.renderer.setClearColor(0x000000, 1);
    this.renderer.setRenderTarget(this.outlineMask);
    this.renderer.render(this.scene, camera);
    this.renderer.setRenderTarget(null);
    this.renderer.setClearColor(clear, alpha);
    this.scene.overrideMaterial = null;
    this.scene.background = background;
    camera.layers.mask = layers;
    objects.forEach((o, i) => { o.mesh.layers.disable(this.outlineLayer); o.mesh.visible = visible[i]; });
    this.helpers.visible = true;
    this.gizmoHelper.visible = true;
    // Their border over the view, shaded only in the rectangle around them (the pass reads
    // up to 49 mask texels a pixel: over a whole view that is slow on a software renderer).
    const radius = Math.max(1, Math.round(1.5 * ratio));
    this.outlineQuad.material.uniforms.size.value.copy(size);
    this.outlineQuad.material.uniforms.radius.value = radius;
    let box = null;
    for (const o of objects) {
      const b = this.screenBox(o.mesh, camera, x, y, w, h, radius / ratio + 2);
      if (!b) continue;
      box = box ? (() => {
        const x0 = Math.min(box.x, b.x), y0 = Math.min(box.y, b.y);
        return { x: x0, y: y0, w: Math.max(box.x + box.w, b.x + b.w) - x0, h: Math.max(box.y + box.h, b.y + b.h) - y0 };
      })() : b;
    }
    if (!box) return;
    this.renderer.setScissor(box.x, box.y, box.w, box.h);
    this.renderer.autoClear = false;
    this.renderer.render(this.outlineScene, this.outlineCamera);
    this.renderer.autoClear = true;
    this.renderer.setScissor(x, y, w, h);
  }

  /// The rectangle (CSS pixels from the bottom left) that `mesh` covers in the view at x, y, w, h
  /// seen by `camera`, grown by `pad`; the whole view when part of it is behind the camera;
  /// null when it is off the view.
  screenBox(mesh, camera, x, y, w, h, pad) {
    if (!mesh.geometry.boundingBox) mesh.geometry.computeBoundingBox();
    const b = mesh.geometry.boundingBox;
    const view = new THREE.Vector3();
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    for (let i = 0; i < 8; i++) {
      const p = new THREE.Vector3(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z).applyMatrix4(mesh.matrixWorld);
      view.copy(p).applyMatrix4(camera.matrixWorldInverse);
      if (camera.isPerspectiveCamera && view.z > -camera.near) return { x, y, w, h };
      p.project(camera);
      x0 = Math.min(x0, p.x); x1 = Math.max(x1, p.x); y0 = Math.min(y0, p.y); y1 = Math.max(y1, p.y);
    }
    const left = Math.max(x, Math.floor(x + (x0 * 0.5 + 0.5) * w - pad));
    const right = Math.min(x + w, Math.ceil(x + (x1 * 0.5 + 0.5) * w + pad));
    const bottom = Math.max(y, Math.floor(y + (y0 * 0.5 + 0.5) * h - pad));
    const top = Math.min(y + h, Math.ceil(y + (y1 * 0.5 + 0.5) * h + pad));
    if (right <= left || top <= bottom) return null;
    return { x: left, y: bottom, w: right - left, h: top - bottom };
  }

  /// The world-space bounding box of an object as drawn.
  worldBox(object) {
    object.holder.updateMatrixWorld(true);
    return new THREE.Box3().setFromObject(object.holder, true);
  }

  /// `sel`: a list of selection entries ({kind, id} and the like). The gizmo goes on a pivot at
  /// the selection's centre: one object's pivot turns and scales with its transform (so the
  /// gizmo's axes are the object's own), several objects share an unturned one.
  setSelection(sel) {
    this.selection = Array.isArray(sel) ? sel : sel ? [sel] : [];
    this.gizmo.detach();
    this.requestDraw();
    const objects = this.selection.map((s) => this.objectOf(s)).filter(Boolean);
    const movable = objects.filter((o) => ['mesh', 'area', 'point', 'spot', 'camera'].includes(o.kind));
    if (!movable.length || movable.length !== objects.length) return;
    const turnable = movable.every((o) => o.kind === 'mesh' || o.kind === 'area');
    // Point and spot lights and the camera move only.
    if (!turnable && this.gizmo.getMode() !== 'translate') this.gizmo.setMode('translate');
    const box = new THREE.Box3();
    for (const o of movable) box.union(this.worldBox(o));
    this.pivot.position.copy(box.getCenter(new THREE.Vector3()));
    if (movable.length === 1 && turnable) {
      this.pivot.quaternion.copy(movable[0].holder.quaternion);
      this.pivot.scale.copy(movable[0].holder.scale);
    } else {
      this.pivot.quaternion.identity();
      this.pivot.scale.set(1, 1, 1);
    }
    if (movable.length === 1 && !turnable) this.pivot.position.copy(movable[0].holder.position);
    this.pivot.updateMatrixWorld(true);
    this.gizmo.attach(this.pivot);
  }

  objectOf(sel) {
    if (!sel) return null;
    if (sel.kind === 'camera') return this.objects.find((o) => o.kind === 'camera') || null;
    return this.objects.find((o) => o.target.kind === sel.kind && o.target.id === sel.id) || null;
  }

  /// A drag begins: remember where the pivot and each selected holder were.
  startGizmo() {
    this.pivot.updateMatrixWorld(true);
    this.dragStart = {
      pivot: this.pivot.matrixWorld.clone(),
      objects: this.selection.map((s) => this.objectOf(s)).filter(Boolean).map((o) => {
        o.holder.updateMatrix();
        return { object: o, matrix: o.holder.matrix.clone() };
      }),
    };
  }

  /// The change the drag made so far: new pivot times old pivot's inverse.
  dragDelta() {
    this.pivot.updateMatrixWorld(true);
    return this.pivot.matrixWorld.clone().multiply(this.dragStart.pivot.clone().invert());
  }

  /// During a drag every selected holder follows the pivot, so the outlines move at once.
  followGizmo() {
    if (!this.dragStart) return;
    const delta = this.dragDelta();
    for (const { object, matrix } of this.dragStart.objects) {
      const m = delta.clone().multiply(matrix);
      m.decompose(object.holder.position, object.holder.quaternion, object.holder.scale);
    }
    this.requestDraw();
  }

  /// Sends the drag's result as one edit (a batch for several objects): a transform for shapes,
  /// instances and area lights (only the part the gizmo's mode changes, its angles nearest to
  /// those typed), a position for point and spot lights, position and look_at for the camera.
  commitGizmo() {
    if (!this.dragStart) return;
    const delta = this.dragDelta();
    const mode = this.gizmo.getMode();
    const commands = [];
    for (const { object, matrix } of this.dragStart.objects) {
      const t = object.target;
      const m = delta.clone().multiply(matrix);
      if (object.kind === 'mesh' || object.kind === 'area') {
        // A grid of instances turns about its transform's origin here; the server then places
        // the copies along the world axes again (the grid's offsets come after the transform).
        const position = new THREE.Vector3(), quaternion = new THREE.Quaternion(), scale = new THREE.Vector3();
        m.decompose(position, quaternion, scale);
        const entry = this.entryFields(t);
        const typed = (entry.transform && entry.transform.rotate) || [0, 0, 0];
        const command = { op: 'set_transform', target: { [`${t.kind}_id`]: t.id }, translate: position.toArray().map(round) };
        if (mode === 'rotate') command.rotate = eulerNearest(quaternion, typed);
        if (mode === 'scale') command.scale = scale.toArray().map(round);
        commands.push(command);
      } else if (object.kind === 'point' || object.kind === 'spot') {
        const start = new THREE.Vector3().setFromMatrixPosition(matrix);
        const moved = start.clone().applyMatrix4(delta);
        const fields = { position: moved.toArray().map(round) };
        const light = this.sceneData.lights.find((l) => l.id === t.id);
        if (object.kind === 'spot' && light && light.fields.point_at) {
          fields.point_at = new THREE.Vector3(...light.fields.point_at).add(moved.clone().sub(start)).toArray().map(round);
        }
        commands.push({ op: 'set_fields', target: { light_id: t.id }, fields });
      } else if (object.kind === 'camera') {
        const cam = this.sceneData.camera;
        const start = new THREE.Vector3(...cam.position);
        const moved = start.clone().applyMatrix4(delta);
        const lookAt = new THREE.Vector3(...cam.look_at).add(moved.clone().sub(start));
        commands.push({ op: 'set_fields', target: 'camera', fields: { position: moved.toArray().map(round), look_at: lookAt.toArray().map(round) } });
      }
    }
    this.dragStart = null;
    if (commands.length === 1) this.app.edit(commands[0]);
    else if (commands.length) this.app.edit({ op: 'batch', commands });
  }

  /// The edit of a typed transform part (`translate`, `rotate` or `scale`, three numbers) of
  /// entry `sel`. A typed rotate or scale turns and scales about the entry's own centre (its
  /// bounding box's, in its own coordinates), as the gizmo does, not about the world's origin:
  /// the translate takes up the difference, so the centre stays where it is.
  ///
  /// The holder takes the new transform at once: a second part typed before the server's
  /// answer arrives then turns about the centre as the first left it, not as it was.
  typedTransform(sel, part, values) {
    const command = this.typedCommand(sel, part, values);
    const o = this.objectOf(sel);
    if (o && (o.kind === 'mesh' || o.kind === 'area')) {
      if (command.translate) o.holder.position.set(...command.translate);
      if (part === 'rotate') o.holder.rotation.set(values[0] * DEG, values[1] * DEG, values[2] * DEG, EULER_ORDER);
      if (part === 'scale') o.holder.scale.set(...values);
      o.holder.updateMatrix();
    }
    return command;
  }

  typedCommand(sel, part, values) {
    const target = { [`${sel.kind}_id`]: sel.id };
    const command = { op: 'set_transform', target, [part]: [...values] };
    const o = this.objectOf(sel);
    if (part === 'translate' || !o || (o.kind !== 'mesh' && o.kind !== 'area')) return command;
    o.mesh.geometry.computeBoundingBox();
    if (o.mesh.geometry.boundingBox.isEmpty()) return command;
    const local = o.mesh.geometry.boundingBox.getCenter(new THREE.Vector3());
    o.holder.updateMatrix();
    const centre = local.clone().applyMatrix4(o.holder.matrix);
    const after = new THREE.Object3D();
    after.rotation.order = EULER_ORDER;
    after.position.copy(o.holder.position);
    after.quaternion.copy(o.holder.quaternion);
    after.scale.copy(o.holder.scale);
    if (part === 'rotate') after.rotation.set(values[0] * DEG, values[1] * DEG, values[2] * DEG, EULER_ORDER);
    else after.scale.set(...values);
    after.updateMatrix();
    after.position.add(centre.clone().sub(local.clone().applyMatrix4(after.matrix)));
    command.translate = after.position.toArray().map(round);
    return command;
  }

  /// The fields of the entry a target names, as written in the file.
  entryFields(t) {
    const list = t.kind === 'shape' ? this.sceneData.shapes : t.kind === 'light' ? this.sceneData.lights : this.sceneData.instances || [];
    const entry = list.find((e) => e.id === t.id);
    return entry ? entry.fields : {};
  }

  viewAt(x, y) {
    return this.rects().find((r) => x >= r.x && x < r.x + r.w && y >= r.y && y < r.y + r.h);
  }

  /// Blender's G / R / S: the selection follows the mouse (moved in the view's plane through
  /// its centre, turned about the view's axis, scaled by the distance to its centre) until a
  /// click or Enter confirms (one edit, as a gizmo drag) or Escape or a right click cancels.
  startModal(mode, clientX, clientY) {
    if (!this.gizmo.object || this.modal) return false;
    const turnable = this.selection.map((s) => this.objectOf(s)).every((o) => o && (o.kind === 'mesh' || o.kind === 'area'));
    if (mode !== 'translate' && !turnable) return false;
    const r = this.rects().find((x) => x.view === this.activeView) || this.rects()[0];
    this.gizmo.setMode(mode);
    this.startGizmo();
    const rect = this.canvas.getBoundingClientRect();
    const centre = this.pivot.position.clone().project(r.view.camera);
    this.modal = {
      mode, r, x0: clientX, y0: clientY,
      cx: rect.left + r.x + (centre.x * 0.5 + 0.5) * r.w, cy: rect.top + r.y + (-centre.y * 0.5 + 0.5) * r.h,
      position: this.pivot.position.clone(), quaternion: this.pivot.quaternion.clone(), scale: this.pivot.scale.clone(),
    };
    for (const view of this.views) view.controls.enabled = false;
    this.canvas.style.cursor = 'move';
    return true;
  }

  moveModal(clientX, clientY) {
    const m = this.modal;
    if (!m) return;
    const camera = m.r.view.camera;
    this.pivot.position.copy(m.position);
    this.pivot.quaternion.copy(m.quaternion);
    this.pivot.scale.copy(m.scale);
    if (m.mode === 'translate') {
      // Pixels to world units at the centre's depth, along the camera's right and up.
      const a = m.position.clone().project(camera);
      const ndc = new THREE.Vector3(a.x + ((clientX - m.x0) / m.r.w) * 2, a.y - ((clientY - m.y0) / m.r.h) * 2, a.z);
      this.pivot.position.copy(ndc.unproject(camera));
    } else if (m.mode === 'rotate') {
      const angle = Math.atan2(clientY - m.cy, clientX - m.cx) - Math.atan2(m.y0 - m.cy, m.x0 - m.cx);
      const axis = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 2).normalize();
      this.pivot.quaternion.premultiply(new THREE.Quaternion().setFromAxisAngle(axis, -angle));
    } else {
      const d0 = Math.max(Math.hypot(m.x0 - m.cx, m.y0 - m.cy), 1);
      this.pivot.scale.multiplyScalar(Math.max(Math.hypot(clientX - m.cx, clientY - m.cy) / d0, 1e-3));
    }
    this.followGizmo();
  }

  endModal(confirm) {
    const m = this.modal;
    if (!m) return;
    this.modal = null;
    this.canvas.style.cursor = '';
    for (const view of this.views) view.controls.enabled = true;
    if (confirm) { this.commitGizmo(); return; }
    this.pivot.position.copy(m.position);
    this.pivot.quaternion.copy(m.quaternion);
    this.pivot.scale.copy(m.scale);
    this.followGizmo();
    this.dragStart = null;
    this.setSelection(this.selection);
  }

  /// B: the next left drag draws a box and selects what is in it (with the Blender mouse, a
  /// left drag off the gizmo always does).
  startBoxSelect() {
    this.boxArmed = true;
    this.canvas.style.cursor = 'crosshair';
  }

  cancelBoxSelect() {
    this.boxArmed = false;
    this.box = null;
    this.boxDiv.style.display = 'none';
    this.canvas.style.cursor = '';
  }

  onPointerDown(e) {
    if (this.modal) {
      // A left click confirms G / R / S, a right click cancels; the view does not move.
      e.stopImmediatePropagation();
      this.endModal(e.button === 0);
      return;
    }
    const rect = this.canvas.getBoundingClientRect();
    const x = e.clientX - rect.left, y = e.clientY - rect.top;
    const r = this.viewAt(x, y);
    if (!r) return;
    this.activeView = r.view;
    for (const view of this.views) view.controls.enabled = view === r.view && !this.gizmo.dragging;
    this.gizmo.camera = r.view.camera;
    this.down = { x: e.clientX, y: e.clientY };
    const blenderBox = this.navigation === 'blender' && e.button === 0 && !this.gizmo.axis;
    if ((this.boxArmed && e.button === 0) || blenderBox) {
      // The orbit controls see the press next: disabled, they do not start.
      for (const view of this.views) view.controls.enabled = false;
      this.box = { x0: x, y0: y, x1: x, y1: y, r, additive: e.shiftKey || e.ctrlKey || e.metaKey };
    }
  }

  onPointerMove(e) {
    this.pointer = { x: e.clientX, y: e.clientY };
    if (this.modal) { this.moveModal(e.clientX, e.clientY); return; }
    if (!this.box) return;
    const rect = this.canvas.getBoundingClientRect();
    this.box.x1 = e.clientX - rect.left;
    this.box.y1 = e.clientY - rect.top;
    const b = this.box;
    Object.assign(this.boxDiv.style, {
      display: 'block', left: `${Math.min(b.x0, b.x1)}px`, top: `${Math.min(b.y0, b.y1)}px`,
      width: `${Math.abs(b.x1 - b.x0)}px`, height: `${Math.abs(b.y1 - b.y0)}px`,
    });
  }

  /// Selects the entries whose bounding box's centre the dragged box holds, in its view.
  finishBoxSelect() {
    const b = this.box;
    this.cancelBoxSelect();
    const [x0, x1] = [Math.min(b.x0, b.x1), Math.max(b.x0, b.x1)];
    const [y0, y1] = [Math.min(b.y0, b.y1), Math.max(b.y0, b.y1)];
    const camera = b.r.view.camera;
    camera.updateMatrixWorld();
    const picked = [];
    for (const o of this.objects) {
      if (o.kind === 'camera' || this.hidden.has(keyOf(o.target))) continue;
      const p = this.worldBox(o).getCenter(new THREE.Vector3()).project(camera);
      if (p.z > 1 || p.z < -1) continue;
      const px = b.r.x + (p.x * 0.5 + 0.5) * b.r.w, py = b.r.y + (-p.y * 0.5 + 0.5) * b.r.h;
      if (px >= x0 && px <= x1 && py >= y0 && py <= y1) picked.push({ kind: o.target.kind, id: o.target.id });
    }
    this.app.selectMany(picked, b.additive);
  }

  onPointerUp(e) {
    if (!this.down || e.button !== 0) return;
    const moved = Math.hypot(e.clientX - this.down.x, e.clientY - this.down.y);
    this.down = null;
    if (this.box) {
      if (moved > 4) { this.finishBoxSelect(); return; }
      // A click, not a drag: select as any click does.
      this.cancelBoxSelect();
    }
    if (moved > 4 || this.gizmo.dragging || this.gizmo.axis) return;
    const rect = this.canvas.getBoundingClientRect();
    const x = e.clientX - rect.left, y = e.clientY - rect.top;
    const r = this.viewAt(x, y);
    if (!r) return;
    const ndc = new THREE.Vector2(((x - r.x) / r.w) * 2 - 1, -((y - r.y) / r.h) * 2 + 1);
    const raycaster = new THREE.Raycaster();
    raycaster.setFromCamera(ndc, r.view.camera);
    const hits = raycaster.intersectObjects(this.pickables.filter((m) => this.pickable(m)), false);
    const additive = e.shiftKey || e.ctrlKey || e.metaKey;
    if (!hits.length) { if (!additive) this.app.select(null); return; }
    const t = hits[0].object.userData.object.target;
    this.app.pick(t.kind === 'camera' ? { kind: 'camera' } : { kind: t.kind, id: t.id }, additive);
  }

  /// Whether a click may pick `mesh`: not hidden by the user (H) in this tab. Surfaces are left
  /// undrawn over the rendered image (`draw` clears their `visible`), yet what the click lands on
  /// there is the same object, so their visibility is not asked; an icon's is.
  pickable(mesh) {
    const o = mesh.userData.object;
    if (this.hidden.has(keyOf(o.target))) return false;
    return mesh.visible || o.kind === 'mesh' || o.kind === 'area';
  }

  // Drawing ------------------------------------------------------------------------------------

  draw() {
    this.draws += 1;
    const height = this.canvas.clientHeight;
    this.headlight.position.copy(this.perspective.position);
    for (const r of this.rects()) {
      const view = r.view;
      const rendered = this.rendered && view === this.views[3] && this.frameTexture;
      for (const o of this.objects) {
        const hidden = this.hidden.has(keyOf(o.target));
        o.mesh.visible = !hidden && (!rendered || (o.kind !== 'mesh' && o.kind !== 'area'));
      }
      // The render has no grid or axes drawn over it.
      for (const g of this.helpers.children) if (g.userData.grid) g.visible = !rendered;
      // Seen from (nearly) its own position, the camera's icon would fill the view.
      if (this.cameraIcon) {
        this.cameraIcon.visible = view !== this.views[3] || this.cameraIcon.position.distanceTo(this.perspective.position) > this.extent * 0.1;
      }
      this.scene.background = rendered ? this.frameTexture : new THREE.Color(view === this.views[3] ? 0x2b2e33 : 0x26292e);
      this.gizmo.camera = view.camera;
      const y = height - r.y - r.h;
      this.renderer.setViewport(r.x, y, r.w, r.h);
      this.renderer.setScissor(r.x, y, r.w, r.h);
      this.renderer.render(this.scene, view.camera);
      this.drawOutline(view.camera, r.x, y, r.w, r.h);
    }
    this.gizmo.camera = this.activeView.camera;
  }
}
