// vxf view: the voxel editor's page. Every edit is a request to the server, which applies the
// same libvxf operator `vxf op` runs and records it; the page only draws what the server holds.
import * as THREE from 'three';
import { OrbitControls } from '/OrbitControls.js';
import { TransformControls } from '/TransformControls.js';

const $ = (id) => document.getElementById(id);
const state = { info: null, grid: null, cloud: null, ready: false, fps: 0, selected: false, lastError: '' };
window.vxfView = state; // for the browser tests
let awakeUntil = 0; // the page draws until then (see animate)
function wake() { awakeUntil = performance.now() + 1000; }

function status(text, error = false) {
  wake();
  $('status').textContent = text;
  $('status').className = error ? 'error' : '';
  if (error) state.lastError = text;
}

// The session's secret from the page's address (vxf view prints it): every request carries it.
const token = new URLSearchParams(location.search).get('token') || '';
state.call = call; // for the browser tests
async function call(method, url, body) {
  const response = await fetch(url, {
    method, headers: { 'Content-Type': 'application/json', 'X-Vxf-Token': token },
    body: body === undefined ? (method === 'GET' ? undefined : '{}') : JSON.stringify(body) });
  if (!response.ok) {
    let message = response.statusText;
    try { message = (await response.json()).error; } catch (e) { /* not JSON */ }
    throw new Error(message);
  }
  wake(); // an answer usually changes what is drawn
  return response;
}

// The first description, and the points of the grid the address names, are asked for at once,
// while WebGL starts (a software renderer takes a second).
const pointsUrl = (grid, budget) => `/api/points?grid=${encodeURIComponent(grid)}&budget=${budget}`;
let firstInfo = call('GET', '/api/info').then((r) => r.json());
const addressGrid = new URLSearchParams(location.search).get('grid');
let firstPoints = addressGrid ? { url: pointsUrl(addressGrid, 10000), response: call('GET', pointsUrl(addressGrid, 10000)) } : null;
firstPoints?.response.catch(() => {}); // an unknown grid: loadInfo picks another, and this answer is dropped

// --- three.js scene ---------------------------------------------------------------------------
const container = $('view');
const renderer = new THREE.WebGLRenderer({ antialias: false });
renderer.setPixelRatio(1);
container.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x1e1f22);
const camera = new THREE.PerspectiveCamera(40, 1, 0.001, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
state.camera = camera; // for the browser tests
scene.add(new THREE.AmbientLight(0xffffff, 0.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.2);
scene.add(sun);
let points = null, mesh = null, selectionBox = null;

function resize() {
  const w = container.clientWidth, h = container.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();

// Drawn on demand: frames are drawn while something happens (input, an answer from the server)
// and for a second after, then not at all — an idle page costs no CPU, which a software renderer
// would otherwise take from the server on the same machine.
for (const type of ['pointerdown', 'pointermove', 'pointerup', 'wheel', 'keydown', 'input', 'change', 'resize']) {
  window.addEventListener(type, wake, { capture: true, passive: true });
}
state.wake = wake;
// Dynamic resolution while the camera moves: below 30 frames a second (a software renderer, a big
// grid) the canvas is drawn at fewer pixels, down to 0.3 of the screen's; above 50 at more, up to
// all of them. The rate is of the frames drawn, over the time spent drawing them (idle time is not
// counted). The camera still, every pixel is drawn (and the volume refined, see refineVolume).
let frames = 0, busy = 0, movingRatio = 1, lastFrame = 0, cameraMoving = false;
const drawAt = (ratio) => { if (renderer.getPixelRatio() !== ratio) { renderer.setPixelRatio(ratio); resize(); } };
controls.addEventListener('start', () => { cameraMoving = true; drawAt(movingRatio); });
controls.addEventListener('end', () => { cameraMoving = false; drawAt(1); });
// The axis triad: a small scene of the world axes (x red, y green, z blue) drawn in the view's
// lower-left corner, seen from the main camera's direction.
const triadScene = new THREE.Scene();
triadScene.add(new THREE.AxesHelper(1));
const triadCamera = new THREE.OrthographicCamera(-1.3, 1.3, 1.3, -1.3, 0.1, 10);
function drawTriad() {
  const size = 90;
  triadCamera.position.copy(camera.position).sub(controls.target).normalize().multiplyScalar(4);
  triadCamera.up.copy(camera.up);
  triadCamera.lookAt(0, 0, 0);
  renderer.setScissorTest(true);
  renderer.setScissor(0, 0, size, size);
  renderer.setViewport(0, 0, size, size);
  renderer.autoClear = false;
  renderer.clearDepth();
  renderer.render(triadScene, triadCamera);
  renderer.autoClear = true;
  renderer.setScissorTest(false);
  renderer.setViewport(0, 0, container.clientWidth, container.clientHeight);
}
function animate() {
  requestAnimationFrame(animate);
  const now = performance.now();
  if (now > awakeUntil) { lastFrame = 0; return; }
  if (lastFrame) { busy += now - lastFrame; frames++; }
  lastFrame = now;
  sun.position.copy(camera.position);
  controls.update();
  renderer.render(scene, camera);
  drawTriad();
  state.frames = (state.frames || 0) + 1;
  if (busy > 1000) {
    state.fps = frames * 1000 / busy;
    frames = 0;
    busy = 0;
    if (cameraMoving) {
      movingRatio = state.fps < 30 ? Math.max(0.3, movingRatio * 0.8) : state.fps > 50 ? Math.min(1, movingRatio * 1.25) : movingRatio;
      drawAt(movingRatio);
    }
    state.pixelRatio = renderer.getPixelRatio();
  }
}
animate();

// --- colour ------------------------------------------------------------------------------------
// A ramp for float grids (dark blue, teal, yellow); Vec3 grids as their colour, exposed so that
// the ramp's top is white, with a display gamma.
const RAMP = [[0.05, 0.03, 0.35], [0.1, 0.55, 0.6], [0.98, 0.9, 0.15]];
function ramp(t, out, at) {
  t = Math.min(Math.max(t, 0), 1) * (RAMP.length - 1);
  const i = Math.min(Math.floor(t), RAMP.length - 2), f = t - i;
  for (let c = 0; c < 3; c++) out[at + c] = RAMP[i][c] * (1 - f) + RAMP[i + 1][c] * f;
}
function rampRange() {
  const lo = parseFloat($('rampMin').value), hi = parseFloat($('rampMax').value);
  return [isFinite(lo) ? lo : 0, isFinite(hi) && hi > lo ? hi : (isFinite(lo) ? lo + 1 : 1)];
}
function colourPoints() {
  if (!points) return;
  const { data, channels, count } = state.cloud;
  const colours = points.geometry.getAttribute('color');
  const [lo, hi] = rampRange();
  const stride = 3 + channels;
  for (let i = 0; i < count; i++) {
    if (channels === 1) {
      ramp((data[i * stride + 3] - lo) / (hi - lo), colours.array, 3 * i);
    } else {
      for (let c = 0; c < 3; c++) {
        const v = Math.max(data[i * stride + 3 + c], 0) / hi;
        colours.array[3 * i + c] = Math.pow(Math.min(v, 1), 1 / 2.2);
      }
    }
  }
  highlightSelection(colours.array);
  colours.needsUpdate = true;
}

// The points inside the current box or sphere are drawn brighter (the server's selection is the
// same test on voxel centres; here on the drawn points, which at a coarse level are cell means).
function insideSelection(x, y, z) {
  const shape = $('shape').value;
  if (shape === 'box') {
    const v = ['minX', 'minY', 'minZ', 'maxX', 'maxY', 'maxZ'].map((id) => parseFloat($(id).value));
    if (v.some((n) => !isFinite(n))) return false;
    return x >= v[0] && y >= v[1] && z >= v[2] && x <= v[3] && y <= v[4] && z <= v[5];
  }
  if (shape === 'sphere') {
    const c = ['cX', 'cY', 'cZ'].map((id) => parseFloat($(id).value)), r = parseFloat($('radius').value);
    if (c.some((n) => !isFinite(n)) || !isFinite(r)) return false;
    return (x - c[0]) ** 2 + (y - c[1]) ** 2 + (z - c[2]) ** 2 <= r * r;
  }
  return false;
}
function highlightSelection(colours) {
  if (!state.selected) return;
  const { data, channels, count } = state.cloud;
  const stride = 3 + channels;
  for (let i = 0; i < count; i++) {
    if (!insideSelection(data[i * stride], data[i * stride + 1], data[i * stride + 2])) continue;
    for (let c = 0; c < 3; c++) colours[3 * i + c] = 0.5 + 0.5 * colours[3 * i + c];
  }
}

// --- loading -----------------------------------------------------------------------------------
function gridInfo(name) { return state.info.grids.find((g) => g.name === name); }

async function loadInfo() {
  state.info = firstInfo ? await firstInfo : await (await call('GET', '/api/info')).json();
  firstInfo = null;
  $('file').textContent = state.info.file.split('/').pop();
  if (!state.upChosen && state.info.up_axis) { $('upAxis').value = state.info.up_axis; state.upChosen = true; }
  const select = $('grid');
  const previous = state.grid;
  select.innerHTML = '';
  for (const g of state.info.grids) {
    if (!g.channels) continue;
    const option = document.createElement('option');
    option.value = g.name;
    option.textContent = `${g.name} (${g.type}, ${g.active_voxels.toLocaleString()} voxels)`;
    select.appendChild(option);
  }
  const wanted = new URLSearchParams(location.search).get('grid');
  const names = state.info.grids.filter((g) => g.channels).map((g) => g.name);
  state.grid = [previous, wanted, state.info.default_grid].find((n) => n && names.includes(n)) || null;
  if (state.grid) select.value = state.grid;
  // Candidates of a selection: the shown grid's voxels, or another grid's (to add voxels where it has them).
  const from = $('selectFrom'), chosen = from.value;
  from.innerHTML = '<option value="">the shown grid</option>' +
    state.info.grids.map((g) => `<option value="${g.name}">${g.name}</option>`).join('');
  from.value = state.info.grids.some((g) => g.name === chosen) ? chosen : '';
  $('renderFields').hidden = !state.info.scene;
  showEditFields();
  showHistory(state.info.steps, state.info.redo);
  showExportGrids();
}

// --- history: the recorded steps, each switched off or on, moved or removed ---------------------
function showHistory(steps, redo) {
  state.steps = steps;
  const list = $('steps');
  list.innerHTML = '';
  steps.forEach((step, i) => {
    const row = document.createElement('div');
    row.className = 'step' + (step.enabled ? '' : ' off');
    const toggle = document.createElement('input');
    toggle.type = 'checkbox';
    toggle.checked = step.enabled;
    toggle.title = 'apply this step (off: the set as if it were not there)';
    toggle.addEventListener('change', () => changeHistory((all) => { all[i].enabled = toggle.checked; }, 'switched'));
    const text = document.createElement('span');
    const refreshed = step.refreshes && step.refreshes.length ? ` (then ${step.refreshes.join(', ')} recomputed)` : '';
    text.textContent = `${i + 1}. ${step.op} ${JSON.stringify(step.params)}${refreshed}`;
    text.title = text.textContent;
    row.append(toggle, text);
    for (const [label, title, move] of [['▲', 'earlier', -1], ['▼', 'later', 1], ['✕', 'remove', 0]]) {
      const button = document.createElement('button');
      button.textContent = label;
      button.title = title;
      button.className = 'stepButton';
      button.disabled = move !== 0 && (i + move < 0 || i + move >= steps.length);
      button.addEventListener('click', () => changeHistory((all) => {
        if (move === 0) all.splice(i, 1);
        else [all[i], all[i + move]] = [all[i + move], all[i]];
      }, move === 0 ? 'removed' : 'moved'));
      row.appendChild(button);
    }
    list.appendChild(row);
  });
  $('undo').disabled = steps.length === 0;
  $('redo').disabled = !redo;
  state.selected = steps.some((s) => s.op === 'select' && s.enabled);
  if (!state.selected) $('selected').textContent = '';
}
function changeHistory(change, what) {
  return inOrder(async () => {
    await guarded(async () => {
      const steps = state.steps.map((s) => ({ op: s.op, params: s.params, enabled: s.enabled }));
      change(steps);
      await call('POST', '/api/steps', { steps });
    });
    await refresh(`history: step ${what}`); // the server's record, changed or not
  });
}

// A whole export's grids: every one but the selection masks, unless the user says otherwise.
function showExportGrids() {
  const box = $('exportGrids');
  const chosen = new Map([...box.querySelectorAll('input')].map((i) => [i.value, i.checked]));
  box.innerHTML = '';
  for (const g of state.info.grids) {
    const label = document.createElement('label');
    const input = document.createElement('input');
    input.type = 'checkbox';
    input.value = g.name;
    input.checked = chosen.has(g.name) ? chosen.get(g.name) : g.type !== 'bool';
    label.append(input, ` ${g.name}`);
    box.appendChild(label);
  }
  const whole = $('exportMode').value === 'whole';
  box.hidden = !whole;
}

async function loadPoints(fitCamera) {
  if (!state.grid) { status('no float or vec3 grid to show'); return; }
  const started = performance.now();
  const budget = Math.max(1, parseInt($('budget').value) || 10000);
  const url = pointsUrl(state.grid, budget);
  const response = firstPoints && firstPoints.url === url ? await firstPoints.response : await call('GET', url);
  firstPoints = null;
  const header = (name) => parseFloat(response.headers.get(name));
  const data = new Float32Array(await response.arrayBuffer());
  const channels = header('X-Vxf-Channels'), count = header('X-Vxf-Count');
  state.cloud = { data, channels, count, cellVoxels: header('X-Vxf-Cell-Voxels'), cellSize: header('X-Vxf-Cell-Size'),
    min: header('X-Vxf-Min'), max: header('X-Vxf-Max'), active: header('X-Vxf-Active') };
  if (fitCamera || $('rampMax').value === '') {
    $('rampMin').value = channels === 1 ? state.cloud.min.toPrecision(4) : 0;
    $('rampMax').value = state.cloud.max.toPrecision(4);
  }
  const stride = 3 + channels;
  const positions = new Float32Array(3 * count);
  for (let i = 0; i < count; i++) for (let a = 0; a < 3; a++) positions[3 * i + a] = data[i * stride + a];
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * count), 3));
  geometry.computeBoundingSphere();
  if (points) { scene.remove(points); points.geometry.dispose(); }
  points = new THREE.Points(geometry, new THREE.PointsMaterial({ vertexColors: true, size: 1, sizeAttenuation: true }));
  scene.add(points);
  updatePointSize();
  colourPoints();
  showLegend();
  const g = gridInfo(state.grid);
  $('gridInfo').textContent = `${count.toLocaleString()} points for ${state.cloud.active.toLocaleString()} active voxels` +
    (state.cloud.cellVoxels > 1 ? ` (cells of ${state.cloud.cellVoxels}³ voxels)` : ' (one per voxel)') +
    `; values ${state.cloud.min.toPrecision(3)} to ${state.cloud.max.toPrecision(3)}`;
  if (fitCamera && g && g.world_min) fit(g.world_min, g.world_max);
  if (g && g.index_min) setupSlice(g);
  state.ready = true;
  status(`${state.grid}: ${count.toLocaleString()} points in ${((performance.now() - started) / 1000).toFixed(2)} s`);
}

function updatePointSize() {
  if (!points) return;
  // three.js draws sizeAttenuation points size·(height/2)/depth pixels across; a cell of the
  // grid spans cellSize·(height/2)/(depth·tan(fov/2)): at scale 1 each point covers its cell.
  const fit = 1 / Math.tan(THREE.MathUtils.degToRad(camera.fov / 2));
  points.material.size = state.cloud.cellSize * fit * (parseFloat($('pointScale').value) || 1);
}

// Frame a world box: the camera at 1.9 sizes off its centre, from the front and a little above
// (front is −y with Z up, +z with Y up); zoom kept between a fiftieth and twenty sizes of it, so
// the object cannot be lost.
function fit(lo, hi) {
  const centre = new THREE.Vector3((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2);
  const size = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-6);
  camera.near = size / 1000;
  camera.far = size * 100;
  if ($('upAxis').value === 'y') {
    camera.up.set(0, 1, 0);
    camera.position.set(centre.x + 0.2 * size, centre.y + 0.6 * size, centre.z + 1.9 * size);
  } else {
    camera.up.set(0, 0, 1);
    camera.position.set(centre.x + 0.2 * size, centre.y - 1.9 * size, centre.z + 0.6 * size);
  }
  controls.target.copy(centre);
  controls.minDistance = size / 50;
  controls.maxDistance = size * 20;
  camera.updateProjectionMatrix();
  for (const [id, v] of [['minX', lo[0]], ['minY', lo[1]], ['minZ', lo[2]], ['maxX', hi[0]], ['maxY', hi[1]], ['maxZ', hi[2]],
    ['cX', centre.x], ['cY', centre.y], ['cZ', centre.z], ['radius', size / 4]]) {
    if ($(id).value === '') $(id).value = v.toPrecision(5);
  }
}

async function loadMesh() {
  if (mesh) { scene.remove(mesh); mesh.geometry.dispose(); mesh = null; }
  if (!$('showMesh').checked || !state.info.grids.some((g) => g.name === 'surface')) return;
  const buffer = await (await call('GET', '/api/mesh?triangles=8000')).arrayBuffer();
  const [vertices, triangles] = new Uint32Array(buffer, 0, 2);
  if (!triangles) return;
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(buffer, 8, 3 * vertices), 3));
  geometry.setIndex(new THREE.BufferAttribute(new Uint32Array(buffer, 8 + 12 * vertices, 3 * triangles), 1));
  geometry.computeVertexNormals();
  mesh = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ color: 0x9aa0a8, transparent: true, opacity: 0.18,
    depthWrite: false }));
  scene.add(mesh);
}

// --- slices ------------------------------------------------------------------------------------
let slice = null;
function setupSlice(g) {
  const axis = parseInt($('sliceAxis').value);
  const input = $('sliceIndex');
  const lo = g.index_min[axis], hi = g.index_max[axis];
  const keep = parseInt(input.value);
  input.min = lo;
  input.max = hi;
  input.value = keep >= lo && keep <= hi && input.dataset.grid === g.name ? keep : Math.round((lo + hi) / 2);
  input.dataset.grid = g.name;
  showSlicePlane();
  loadSlice();
}
async function loadSlice() {
  if (!state.grid) return;
  const axis = $('sliceAxis').value, index = $('sliceIndex').value;
  slice = await (await call('GET', `/api/slice?grid=${encodeURIComponent(state.grid)}&axis=${axis}&index=${index}`)).json();
  const canvas = $('slice');
  canvas.width = Math.max(slice.width, 1);
  canvas.height = Math.max(slice.height, 1);
  const context = canvas.getContext('2d');
  const image = context.createImageData(canvas.width, canvas.height);
  const [lo, hi] = rampRange();
  const rgb = [0, 0, 0];
  for (let j = 0; j < slice.height; j++) {
    for (let i = 0; i < slice.width; i++) {
      const at = (j * slice.width + i) * slice.channels;
      const pixel = 4 * ((slice.height - 1 - j) * slice.width + i); // rows upward
      if (slice.values[at] === null) { image.data[pixel + 3] = 0; continue; }
      if (slice.channels === 1) ramp((slice.values[at] - lo) / (hi - lo), rgb, 0);
      else for (let c = 0; c < 3; c++) rgb[c] = Math.pow(Math.min(Math.max(slice.values[at + c], 0) / hi, 1), 1 / 2.2);
      for (let c = 0; c < 3; c++) image.data[pixel + c] = Math.round(255 * rgb[c]);
      image.data[pixel + 3] = 255;
    }
  }
  context.putImageData(image, 0, 0);
}
$('slice').addEventListener('mousemove', (event) => {
  if (!slice || !slice.width) return;
  const rect = event.target.getBoundingClientRect();
  const i = Math.floor((event.clientX - rect.left) / rect.width * slice.width);
  const j = slice.height - 1 - Math.floor((event.clientY - rect.top) / rect.height * slice.height);
  if (i < 0 || j < 0 || i >= slice.width || j >= slice.height) return;
  const ijk = [...slice.origin];
  const u = slice.axis === 0 ? 1 : 0, v = slice.axis === 2 ? 1 : 2;
  ijk[u] += i;
  ijk[v] += j;
  const at = (j * slice.width + i) * slice.channels;
  const value = slice.values[at] === null ? 'inactive' : slice.values.slice(at, at + slice.channels).map((x) => x.toPrecision(4)).join(', ');
  $('readout').textContent = `[${ijk.join(', ')}] ${value}`;
});

// --- brushing: shift-drag a rectangle, the box around the points under it --------------------
// Listened for on the container, before the canvas (capture), and kept from it: the orbit
// controls never see a brushing drag (shift-drag would pan the camera under the brush).
let brushStart = null;
const brush = $('brush');
const local = (event) => {
  const rect = renderer.domElement.getBoundingClientRect();
  return [event.clientX - rect.left, event.clientY - rect.top];
};
// --- painting: a drag with Paint on lays a stroke on the first visible voxels under the cursor --
// The point under the cursor is the nearest drawn point (voxel or cell) whose own disc covers
// it; the brush's centre lies `depth` beyond it along the view ray. The stroke is one `paint`
// step, sent when the drag ends.
let stroke = null;
const paintCursor = $('paintCursor');
function pickFront(x, y) {
  if (!state.cloud) return null;
  const { data, channels, count, cellSize } = state.cloud;
  const stride = 3 + channels;
  const w = renderer.domElement.clientWidth, h = renderer.domElement.clientHeight;
  const fit = (h / 2) / Math.tan(THREE.MathUtils.degToRad(camera.fov / 2));
  const p = new THREE.Vector3(), q = new THREE.Vector3();
  let best = -1, bestDistance = Infinity;
  for (let i = 0; i < count; i++) {
    q.set(data[i * stride], data[i * stride + 1], data[i * stride + 2]);
    const distance = q.distanceTo(camera.position);
    if (distance >= bestDistance) continue;
    p.copy(q).project(camera);
    if (p.z > 1) continue;
    const sx = (p.x + 1) / 2 * w, sy = (1 - p.y) / 2 * h;
    const reach = Math.max(0.5 * cellSize * fit / distance, 1.5);
    if ((sx - x) ** 2 + (sy - y) ** 2 > reach * reach) continue;
    best = i;
    bestDistance = distance;
  }
  if (best < 0) return null;
  const hit = new THREE.Vector3(data[best * stride], data[best * stride + 1], data[best * stride + 2]);
  const depth = parseFloat($('paintDepth').value) || 0;
  if (depth) hit.add(hit.clone().sub(camera.position).normalize().multiplyScalar(depth));
  return hit;
}
function paintRadius() {
  const r = parseFloat($('paintRadius').value);
  return r > 0 ? r : 2 * (state.cloud ? state.cloud.cellSize : 0.01);
}
function showPaintCursor(x, y) {
  if (!$('paintMode').checked || !state.cloud) { paintCursor.style.display = 'none'; return; }
  const h = renderer.domElement.clientHeight;
  const fit = (h / 2) / Math.tan(THREE.MathUtils.degToRad(camera.fov / 2));
  const r = paintRadius() * fit / camera.position.distanceTo(controls.target);
  Object.assign(paintCursor.style, { display: 'block', left: `${x - r}px`, top: `${y - r}px`, width: `${2 * r}px`, height: `${2 * r}px` });
}
function addStrokePoint(x, y) {
  const hit = pickFront(x, y);
  if (!hit) return;
  const last = stroke.points[stroke.points.length - 1];
  if (last && hit.distanceTo(new THREE.Vector3(...last)) < paintRadius() / 3) return; // spaced a third of the radius apart
  if (stroke.points.length < 4000) stroke.points.push([hit.x, hit.y, hit.z]);
}
async function endStroke() {
  const done = stroke;
  stroke = null;
  controls.enabled = true;
  if (!done || !done.points.length) { status('nothing under the brush'); return; }
  const params = { grid: state.grid, points: done.points, radius: paintRadius(), falloff: parseFloat($('paintFalloff').value) || 0,
    strength: Math.min(Math.max(parseFloat($('paintStrength').value), 0), 1), mode: $('paintBlend').value };
  if (shownIsColour()) {
    const hex = $('paintColor').value;
    params.value = [1, 3, 5].map((i) => Math.pow(parseInt(hex.substr(i, 2), 16) / 255, 2.2) * rampRange()[1]);
  } else {
    params.value = parseFloat($('paintValue').value) || 0;
  }
  await inOrder(async () => refresh(`paint: ${await apply('paint', params)}`));
}
container.addEventListener('pointermove', (event) => {
  const [x, y] = local(event);
  showPaintCursor(x, y);
  if (stroke) addStrokePoint(x, y);
});
container.addEventListener('pointerleave', () => { paintCursor.style.display = 'none'; });

container.addEventListener('pointerdown', (event) => {
  if ($('paintMode').checked && !event.shiftKey && points && event.button === 0) {
    event.stopPropagation();
    event.preventDefault();
    container.setPointerCapture(event.pointerId);
    controls.enabled = false;
    stroke = { points: [] };
    addStrokePoint(...local(event));
    return;
  }
  if (!event.shiftKey || !points) return;
  event.stopPropagation();
  event.preventDefault();
  brushStart = local(event);
  container.setPointerCapture(event.pointerId); // released over the panel, the drag still ends here
  Object.assign(brush.style, { display: 'block', left: `${brushStart[0]}px`, top: `${brushStart[1]}px`, width: '0px', height: '0px' });
}, { capture: true });
container.addEventListener('pointermove', (event) => {
  if (!brushStart) return;
  event.stopPropagation();
  const [x0, y0] = brushStart, [x, y] = local(event);
  Object.assign(brush.style, { left: `${Math.min(x0, x)}px`, top: `${Math.min(y0, y)}px`,
    width: `${Math.abs(x - x0)}px`, height: `${Math.abs(y - y0)}px` });
}, { capture: true });
container.addEventListener('pointerup', (event) => {
  if (stroke) { event.stopPropagation(); endStroke(); return; }
  if (!brushStart) return;
  event.stopPropagation();
  const [x0, y0] = brushStart, [x, y] = local(event);
  brushStart = null;
  brush.style.display = 'none';
  brushBox(x0, y0, x, y);
}, { capture: true });
function brushBox(x0, y0, x1, y1) {
  const w = renderer.domElement.clientWidth, h = renderer.domElement.clientHeight;
  const [ax, bx] = [Math.min(x0, x1), Math.max(x0, x1)], [ay, by] = [Math.min(y0, y1), Math.max(y0, y1)];
  const { data, channels, count } = state.cloud;
  const stride = 3 + channels;
  const p = new THREE.Vector3();
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  let n = 0;
  for (let i = 0; i < count; i++) {
    p.set(data[i * stride], data[i * stride + 1], data[i * stride + 2]).project(camera);
    const sx = (p.x + 1) / 2 * w, sy = (1 - p.y) / 2 * h;
    if (p.z > 1 || sx < ax || sx > bx || sy < ay || sy > by) continue;
    n++;
    for (let a = 0; a < 3; a++) {
      const v = data[i * stride + a];
      lo[a] = Math.min(lo[a], v);
      hi[a] = Math.max(hi[a], v);
    }
  }
  if (!n) { status('no points under the brush'); return; }
  // Half a cell around the brushed points' centres, so that their voxels are inside.
  const margin = state.cloud.cellSize / 2;
  ['minX', 'minY', 'minZ'].forEach((id, a) => { $(id).value = (lo[a] - margin).toPrecision(6); });
  ['maxX', 'maxY', 'maxZ'].forEach((id, a) => { $(id).value = (hi[a] + margin).toPrecision(6); });
  $('shape').value = 'box';
  showShapeFields();
  showOutline();
  status(`brushed ${n} points: the box around them is set; Select to select their voxels`);
}

// --- edits -------------------------------------------------------------------------------------
function showShapeFields() {
  const shape = $('shape').value;
  $('boxFields').hidden = shape !== 'box';
  $('sphereFields').hidden = shape !== 'sphere';
  $('rangeFields').hidden = shape !== 'range';
}
const numbers = (ids) => ids.map((id) => parseFloat($(id).value));

async function apply(op, params) {
  const result = await (await call('POST', '/api/apply', { op, params })).json();
  return result.report;
}

async function refresh(message) {
  await loadInfo();
  await loadPoints(false);
  await showGrid();
  status(message);
}

async function guarded(action) {
  try { await action(); } catch (error) { status(error.message, true); }
}
// What changes the server's record (an edit, a history change, undo and redo, a paint stroke, an
// export of it) runs in the order the artist asked, each after the one before has finished and the
// page shows its result: a Ctrl-Z pressed while an edit is in flight undoes that edit, not the one
// before it, whatever order the browser's connections would deliver the requests in.
let pendingChanges = Promise.resolve();
function inOrder(action) {
  pendingChanges = pendingChanges.then(() => guarded(action));
  return pendingChanges;
}

$('select').addEventListener('click', () => inOrder(async () => {
  const shape = $('shape').value;
  const params = { grid: $('selectFrom').value || state.grid, shape, out: 'mask' };
  if (shape === 'box') { params.min = numbers(['minX', 'minY', 'minZ']); params.max = numbers(['maxX', 'maxY', 'maxZ']); }
  if (shape === 'sphere') { params.centre = numbers(['cX', 'cY', 'cZ']); params.radius = parseFloat($('radius').value); }
  if (shape === 'range') { params.low = parseFloat($('low').value); params.high = parseFloat($('high').value); }
  const report = await apply('select', params);
  state.selected = true;
  $('selected').textContent = report;
  await refresh(`select: ${report}`);
}));

function editParams(extra) {
  const params = { grid: state.grid, ...extra };
  if (state.selected) params.selection = 'mask';
  return params;
}
// The edit panel for the shown grid: colours (vec3) are set, hue-shifted and saturated; numbers
// (float grids: density, temperature, a weight) set and scaled. Both take an offset.
const shownIsColour = () => (gridInfo(state.grid)?.channels || 3) === 3;
function showEditFields() {
  const colour = shownIsColour();
  for (const e of document.querySelectorAll('.colourOnly')) e.hidden = !colour;
  for (const e of document.querySelectorAll('.numberOnly')) e.hidden = colour;
  $('valLabel').textContent = colour ? 'value x' : 'scale x';
}
$('apply').addEventListener('click', () => inOrder(async () => {
  const extra = { value: parseFloat($('val').value), offset: parseFloat($('offset').value) || 0 };
  if (shownIsColour()) {
    extra.hue_shift = parseFloat($('hue').value) || 0;
    extra.saturation = parseFloat($('sat').value);
    if ($('doSet').checked) {
      const hex = $('color').value;
      extra.set = [1, 3, 5].map((i) => Math.pow(parseInt(hex.substr(i, 2), 16) / 255, 2.2) * rampRange()[1]);
    }
  } else if ($('doSetValue').checked) {
    extra.set = parseFloat($('setValue').value);
  }
  const report = await apply('edit', editParams(extra));
  await refresh(`edit: ${report}`);
}));
// Noise breaks up the selection's values: each scaled by 1 ± amount (fractal Perlin noise).
$('noise').addEventListener('click', () => inOrder(async () => {
  const params = editParams({ mode: 'multiply', offset: 1, amplitude: parseFloat($('noiseAmount').value) || 0,
    frequency: parseFloat($('noiseFrequency').value) || 8 });
  await refresh(`noise: ${await apply('noise', params)}`);
}));
$('add').addEventListener('click', () => inOrder(async () => refresh(`edit: ${await apply('edit', editParams({ add: true }))}`)));
$('remove').addEventListener('click', () => inOrder(async () => refresh(`edit: ${await apply('edit', editParams({ remove: true }))}`)));
const undo = () => inOrder(async () => {
  const result = await (await call('POST', '/api/undo')).json();
  await refresh(result.undone ? 'undone' : 'nothing to undo');
});
const redo = () => inOrder(async () => {
  const result = await (await call('POST', '/api/redo')).json();
  await refresh(result.redone ? 'redone' : 'nothing to redo');
});
$('undo').addEventListener('click', undo);
$('redo').addEventListener('click', redo);
// Ctrl-Z and Ctrl-Shift-Z (Cmd on a Mac), Ctrl-Y, except while typing in a field.
window.addEventListener('keydown', (event) => {
  if (!(event.ctrlKey || event.metaKey) || ['INPUT', 'SELECT', 'TEXTAREA'].includes(event.target.tagName)) return;
  const key = event.key.toLowerCase();
  if (key === 'z' && !event.shiftKey) { event.preventDefault(); undo(); }
  if ((key === 'z' && event.shiftKey) || key === 'y') { event.preventDefault(); redo(); }
});
$('exportMode').addEventListener('change', showExportGrids);
$('export').addEventListener('click', () => inOrder(async () => {
  const body = { path: $('exportPath').value, mode: $('exportMode').value, grid: state.grid, smooth: parseInt($('smooth').value) || 0 };
  if (body.mode === 'whole') body.grids = [...$('exportGrids').querySelectorAll('input')].filter((i) => i.checked).map((i) => i.value);
  const result = await (await call('POST', '/api/export', body)).json();
  status(`wrote ${result.written}`);
  state.lastExport = result.written;
}));

$('render').addEventListener('click', () => guarded(async () => {
  status('rendering…');
  const body = { width: parseInt($('renderWidth').value) || 480, height: parseInt($('renderHeight').value) || 360 };
  // The server renders on the request's own thread; meanwhile its progress, and the page stays live.
  const poll = setInterval(async () => {
    try {
      const p = await (await call('GET', '/api/progress')).json();
      if (p.rendering) status(`rendering: ${p.step} ${p.percent}% (${p.seconds.toFixed(1)} s)`);
    } catch (e) { /* the next poll */ }
  }, 300);
  let result;
  try { result = await (await call('POST', '/api/render', body)).json(); } finally { clearInterval(poll); }
  $('renderImage').src = `/api/image?token=${encodeURIComponent(token)}&t=${Date.now()}`;
  $('renderReport').textContent = `${result.ran.join(' + ')} in ${result.seconds.toFixed(1)} s`;
  status(`rendered: ran ${result.ran.join(', ')}`);
  state.rendered = result;
}));

// --- the volume: a brick of cells ray-marched in the page ------------------------------------------
// The server sends each cell's mean value and its coverage (the share of its voxels active);
// the page makes them an RGBA 3D texture — the ramp's colour (a float grid) or the colour itself
// (a vec3 grid), and as alpha the coverage times the value's place on the ramp — and marches it
// front to back, a step a cell, each step's opacity 1 − exp(−opacity·alpha·step).
const volumeVertex = `
out vec3 vLocal;
void main() {
  vLocal = position + 0.5;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;
const volumeFragment = `
precision highp float;
precision highp sampler3D;
uniform sampler3D volume;
uniform vec3 eye;       // the camera in the box's own [0, 1]³
uniform vec3 cells;     // the brick's cells along each axis
uniform float opacity;  // per cell at alpha 1
uniform float stride;   // cells a step: 1, or 2 while the camera moves
in vec3 vLocal;
out vec4 outColor;
void main() {
  vec3 d = normalize(vLocal - eye);
  vec3 inv = 1.0 / d;
  vec3 t0 = (vec3(0.0) - eye) * inv, t1 = (vec3(1.0) - eye) * inv;
  vec3 lo = min(t0, t1), hi = max(t0, t1);
  float near = max(max(max(lo.x, lo.y), lo.z), 0.0), far = min(min(hi.x, hi.y), hi.z);
  if (near >= far) discard;
  float step = stride / max(max(cells.x, cells.y), cells.z);
  float stepCells = length(d * cells) * step; // cells crossed per step
  vec4 sum = vec4(0.0);
  for (int i = 0; i < 1024; i++) {
    float t = near + (float(i) + 0.5) * step;
    if (t > far || sum.a > 0.99) break;
    vec4 v = texture(volume, eye + d * t);
    float a = 1.0 - exp(-opacity * v.a * stepCells);
    sum.rgb += (1.0 - sum.a) * a * v.rgb;
    sum.a += (1.0 - sum.a) * a;
  }
  outColor = sum;
}`;
let volume = null;
state.volume = null;     // the brick at the budget the page asked for, drawn while the camera moves
state.fineVolume = null; // a finer one, fetched when the camera stops and drawn until it moves again
let volumeGeneration = 0, refineTimer = null;
async function fetchBrick(cells) {
  const response = await call('GET', `/api/volume?grid=${encodeURIComponent(state.grid)}&cells=${cells}`);
  const triple = (name) => response.headers.get(name).split(',').map(parseFloat);
  const data = new Float32Array(await response.arrayBuffer());
  return { data, dims: triple('X-Vxf-Dims'), channels: parseInt(response.headers.get('X-Vxf-Channels')),
    lo: triple('X-Vxf-World-Min'), hi: triple('X-Vxf-World-Max'), min: parseFloat(response.headers.get('X-Vxf-Min')),
    max: parseFloat(response.headers.get('X-Vxf-Max')), cellVoxels: parseInt(response.headers.get('X-Vxf-Cell-Voxels')) };
}
const volumeCells = () => Math.max(4096, parseInt($('cells').value) || 262144);
async function loadVolume() {
  if (!state.grid) return;
  const started = performance.now();
  const generation = ++volumeGeneration;
  const brick = await fetchBrick(volumeCells());
  if (generation !== volumeGeneration) return; // a newer load (another grid, an edit) overtook this one
  for (const old of [state.volume, state.fineVolume]) old?.texture?.dispose();
  state.volume = brick;
  state.fineVolume = null;
  if ($('rampMax').value === '') {
    $('rampMin').value = brick.channels === 1 ? brick.min.toPrecision(4) : 0;
    $('rampMax').value = brick.max.toPrecision(4);
  }
  buildVolume();
  const [nx, ny, nz] = brick.dims;
  status(`${state.grid}: a volume of ${nx}x${ny}x${nz} cells of ${brick.cellVoxels}³ voxels in ` +
    `${((performance.now() - started) / 1000).toFixed(2)} s`);
  state.ready = true;
  if (!cameraMoving) scheduleRefine();
}
// Refinement: once the camera has been still for a moment, the same grid at eight times the cells
// (at most 128³, a texture of 8 MB), unless the brick already holds every voxel.
const kFineCells = 128 * 128 * 128;
function scheduleRefine() {
  clearTimeout(refineTimer);
  refineTimer = setTimeout(() => guarded(refineVolume), 300);
}
async function refineVolume() {
  const coarse = state.volume;
  if (cameraMoving || !coarse || state.fineVolume || $('viewMode').value !== 'volume' || coarse.cellVoxels <= 1) return;
  const cells = Math.min(8 * volumeCells(), kFineCells);
  if (cells <= volumeCells()) return;
  const generation = volumeGeneration, started = performance.now();
  const brick = await fetchBrick(cells);
  if (generation !== volumeGeneration || state.volume !== coarse) return;
  state.fineVolume = brick;
  if (!cameraMoving) buildVolume();
  const [nx, ny, nz] = brick.dims;
  status(`${state.grid}: refined to ${nx}x${ny}x${nz} cells of ${brick.cellVoxels}³ voxels in ` +
    `${((performance.now() - started) / 1000).toFixed(2)} s`);
}
controls.addEventListener('start', () => {
  clearTimeout(refineTimer);
  if (state.fineVolume && volume && volume.userData.brick === state.fineVolume) buildVolume(); // coarse while moving
});
controls.addEventListener('end', () => {
  if (state.fineVolume) buildVolume(); else scheduleRefine();
});
// A brick's texture, made once per ramp: the ramp's colour (or the colour itself) and alpha.
function volumeTexels(brick) {
  const { data, dims, channels } = brick;
  const count = dims[0] * dims[1] * dims[2], stride = channels + 1;
  const texels = new Uint8Array(4 * count);
  const [lo, hi] = rampRange();
  const rgb = [0, 0, 0];
  for (let i = 0; i < count; i++) {
    const coverage = data[i * stride + channels];
    if (!(coverage > 0)) continue;
    let alpha;
    if (channels === 1) {
      const t = Math.min(Math.max((data[i * stride] - lo) / (hi - lo), 0), 1);
      ramp(t, rgb, 0);
      alpha = coverage * t;
    } else {
      for (let c = 0; c < 3; c++) rgb[c] = Math.pow(Math.min(Math.max(data[i * stride + c], 0) / hi, 1), 1 / 2.2);
      alpha = coverage * Math.max(rgb[0], rgb[1], rgb[2]);
    }
    for (let c = 0; c < 3; c++) texels[4 * i + c] = Math.round(255 * rgb[c]);
    texels[4 * i + 3] = Math.round(255 * alpha);
  }
  return texels;
}
function brickTexture(brick) {
  const key = rampRange().join(',');
  if (brick.texture && brick.textureKey === key) return brick.texture;
  if (brick.texture) brick.texture.dispose();
  const { dims } = brick;
  const texture = new THREE.Data3DTexture(volumeTexels(brick), dims[0], dims[1], dims[2]);
  texture.format = THREE.RGBAFormat;
  texture.type = THREE.UnsignedByteType;
  texture.minFilter = texture.magFilter = THREE.LinearFilter;
  texture.unpackAlignment = 1;
  texture.needsUpdate = true;
  brick.texture = texture;
  brick.textureKey = key;
  return texture;
}
// The opacity field is per cell of the budget's brick: a finer brick's cells are thinner in proportion,
// so that refinement sharpens the volume without making it denser.
const volumeOpacity = (brick) => (parseFloat($('opacity').value) || 0) * brick.cellVoxels / state.volume.cellVoxels;
// The drawn volume: the fine brick when the camera is still and it is there, else the coarse one.
function buildVolume() {
  if (volume) { scene.remove(volume); volume.geometry.dispose(); volume.material.dispose(); volume = null; }
  if (!state.volume || $('viewMode').value !== 'volume') { showLegend(); return; }
  const brick = (!cameraMoving && state.fineVolume) || state.volume;
  const { dims, lo, hi } = brick;
  const material = new THREE.ShaderMaterial({
    glslVersion: THREE.GLSL3, vertexShader: volumeVertex, fragmentShader: volumeFragment, side: THREE.BackSide,
    transparent: true, premultipliedAlpha: true, depthWrite: false,
    blending: THREE.CustomBlending, blendSrc: THREE.OneFactor, blendDst: THREE.OneMinusSrcAlphaFactor,
    uniforms: { volume: { value: brickTexture(brick) }, eye: { value: new THREE.Vector3() }, cells: { value: new THREE.Vector3(...dims) },
      opacity: { value: volumeOpacity(brick) }, stride: { value: 1 } } });
  volume = new THREE.Mesh(new THREE.BoxGeometry(1, 1, 1), material);
  volume.userData.brick = brick;
  volume.scale.set(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  volume.position.set((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2);
  volume.onBeforeRender = () => {
    volume.worldToLocal(material.uniforms.eye.value.copy(camera.position)).addScalar(0.5); // [0, 1]³
    material.uniforms.stride.value = cameraMoving ? 2 : 1; // half the samples while tumbling, the same opacity
  };
  scene.add(volume);
  showLegend();
}
function showLegend() {
  const legend = $('legend');
  const shown = $('viewMode').value === 'volume' || (state.cloud && state.cloud.channels === 1);
  legend.style.display = shown && state.grid ? 'block' : 'none';
  const channels = $('viewMode').value === 'volume' ? state.volume?.channels : state.cloud?.channels;
  const [lo, hi] = rampRange();
  $('legendBar').style.background = channels === 3 ? 'linear-gradient(to right, #000, #fff)'
    : `linear-gradient(to right, ${RAMP.map((c) => `rgb(${c.map((x) => Math.round(255 * x)).join(',')})`).join(', ')})`;
  $('legendLo').textContent = channels === 3 ? '0' : lo.toPrecision(3);
  $('legendHi').textContent = hi.toPrecision(3);
  $('legendName').textContent = state.grid || '';
}
// The shown grid as the view mode says: its volume (loaded again) or its points (kept loaded:
// painting picks among them in either mode).
async function showGrid() {
  const asVolume = $('viewMode').value === 'volume';
  if (asVolume) await loadVolume(); else buildVolume(); // buildVolume drops the volume in points mode
  if (points) points.visible = !asVolume;
  showLegend();
}
$('viewMode').addEventListener('change', () => guarded(showGrid));
$('opacity').addEventListener('change', () => { if (volume) volume.material.uniforms.opacity.value = volumeOpacity(volume.userData.brick); });
$('cells').addEventListener('change', () => guarded(showGrid));

// --- framing, the selection's outline and the slice plane ----------------------------------------
function frameAll() {
  const g = gridInfo(state.grid);
  if (g && g.world_min) fit(g.world_min, g.world_max);
}
function frameSelected() {
  const shape = $('shape').value;
  if (shape === 'box') {
    const v = numbers(['minX', 'minY', 'minZ', 'maxX', 'maxY', 'maxZ']);
    if (v.every(isFinite)) { fit(v.slice(0, 3), v.slice(3)); return; }
  } else if (shape === 'sphere') {
    const c = numbers(['cX', 'cY', 'cZ']), r = parseFloat($('radius').value);
    if (c.every(isFinite) && r > 0) { fit(c.map((x) => x - r), c.map((x) => x + r)); return; }
  }
  frameAll();
}
let outline = null, slicePlane = null;
function showOutline() {
  if (outline) { scene.remove(outline); outline.geometry.dispose(); outline = null; }
  const shape = $('shape').value;
  if (shape === 'box') {
    const v = numbers(['minX', 'minY', 'minZ', 'maxX', 'maxY', 'maxZ']);
    if (!v.every(isFinite)) return;
    outline = new THREE.Box3Helper(new THREE.Box3(new THREE.Vector3(...v.slice(0, 3)), new THREE.Vector3(...v.slice(3))), 0xffdd44);
  } else if (shape === 'sphere') {
    const c = numbers(['cX', 'cY', 'cZ']), r = parseFloat($('radius').value);
    if (!c.every(isFinite) || !(r > 0)) return;
    outline = new THREE.LineSegments(new THREE.WireframeGeometry(new THREE.SphereGeometry(r, 16, 8)), new THREE.LineBasicMaterial({ color: 0xffdd44 }));
    outline.position.set(...c);
  }
  if (outline) scene.add(outline);
  syncHandle();
}
function showSlicePlane() {
  if (slicePlane) { scene.remove(slicePlane); slicePlane.geometry.dispose(); slicePlane = null; }
  const g = gridInfo(state.grid);
  if (!$('showSlicePlane').checked || !g || !g.world_min) return;
  const axis = parseInt($('sliceAxis').value), index = parseInt($('sliceIndex').value);
  const lo = g.world_min, hi = g.world_max;
  // World bounds are the index bounds' voxel centres: linear between them.
  const span = g.index_max[axis] - g.index_min[axis];
  const position = span > 0 ? lo[axis] + (index - g.index_min[axis]) / span * (hi[axis] - lo[axis]) : lo[axis];
  const size = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
  const u = axis === 0 ? 1 : 0, v = axis === 2 ? 1 : 2;
  const geometry = new THREE.PlaneGeometry(size[u], size[v]);
  slicePlane = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({ color: 0x66aaff, transparent: true, opacity: 0.15,
    side: THREE.DoubleSide, depthWrite: false }));
  const centre = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2];
  centre[axis] = position;
  slicePlane.position.set(...centre);
  if (axis === 0) slicePlane.rotation.y = Math.PI / 2;
  if (axis === 1) slicePlane.rotation.x = Math.PI / 2;
  scene.add(slicePlane);
  syncHandle();
}
// --- handles: the selection box or sphere, or the slice plane, dragged in the view --------------
// three.js's TransformControls on a stand-in object: moved, its position is the selection's
// centre (or the slice plane's place); resized, its scale the box's size (or the sphere's
// radius). Each change writes the fields back, so a handle and the numbers always agree.
const gizmo = new TransformControls(camera, renderer.domElement);
const handle = new THREE.Object3D();
scene.add(gizmo, handle);
gizmo.addEventListener('dragging-changed', (event) => {
  controls.enabled = !event.value;
  if (!event.value && $('handle').value === 'slice') guarded(loadSlice); // the slice's values once the drag ends
});
// The handle follows what it stands for when that changes otherwise (fields typed, a brushed box,
// another grid), but not while it is the one dragging.
function syncHandle() { if (!gizmo.dragging) attachHandle(); }
function attachHandle() {
  gizmo.detach();
  const mode = $('handle').value, shape = $('shape').value;
  gizmo.showX = gizmo.showY = gizmo.showZ = true;
  handle.scale.set(1, 1, 1);
  if (mode === 'slice') {
    if (!slicePlane) return;
    const axis = parseInt($('sliceAxis').value);
    handle.position.copy(slicePlane.position);
    gizmo.setMode('translate');
    [gizmo.showX, gizmo.showY, gizmo.showZ] = [axis === 0, axis === 1, axis === 2];
  } else if (mode && shape === 'box') {
    const v = numbers(['minX', 'minY', 'minZ', 'maxX', 'maxY', 'maxZ']);
    if (!v.every(isFinite)) return;
    handle.position.set((v[0] + v[3]) / 2, (v[1] + v[4]) / 2, (v[2] + v[5]) / 2);
    handle.scale.set(Math.abs(v[3] - v[0]), Math.abs(v[4] - v[1]), Math.abs(v[5] - v[2]));
    gizmo.setMode(mode === 'move' ? 'translate' : 'scale');
  } else if (mode && shape === 'sphere') {
    const c = numbers(['cX', 'cY', 'cZ']), r = parseFloat($('radius').value);
    if (!c.every(isFinite) || !(r > 0)) return;
    handle.position.set(...c);
    handle.scale.setScalar(r);
    gizmo.setMode(mode === 'move' ? 'translate' : 'scale');
  } else {
    return; // no handle, or a range selection (nothing to drag)
  }
  gizmo.attach(handle);
}
gizmo.addEventListener('objectChange', () => {
  const mode = $('handle').value, p = handle.position, s = handle.scale;
  if (mode === 'slice') {
    const g = gridInfo(state.grid), axis = parseInt($('sliceAxis').value), input = $('sliceIndex');
    const span = g.index_max[axis] - g.index_min[axis], extent = g.world_max[axis] - g.world_min[axis];
    const at = extent > 0 ? g.index_min[axis] + (p.getComponent(axis) - g.world_min[axis]) / extent * span : g.index_min[axis];
    input.value = Math.min(Math.max(Math.round(at), g.index_min[axis]), g.index_max[axis]);
    showSlicePlane();
    return;
  }
  if ($('shape').value === 'box') {
    const lo = [p.x - s.x / 2, p.y - s.y / 2, p.z - s.z / 2], hi = [p.x + s.x / 2, p.y + s.y / 2, p.z + s.z / 2];
    ['minX', 'minY', 'minZ'].forEach((id, a) => { $(id).value = lo[a].toPrecision(6); });
    ['maxX', 'maxY', 'maxZ'].forEach((id, a) => { $(id).value = hi[a].toPrecision(6); });
  } else {
    // A sphere stays a sphere: the radius is the axis the user pulled (the one that moved most).
    const r = parseFloat($('radius').value);
    const pulled = [s.x, s.y, s.z].reduce((best, x) => (Math.abs(x - r) > Math.abs(best - r) ? x : best), r);
    handle.scale.setScalar(Math.abs(pulled));
    $('radius').value = Math.abs(pulled).toPrecision(6);
    ['cX', 'cY', 'cZ'].forEach((id, a) => { $(id).value = p.getComponent(a).toPrecision(6); });
  }
  showOutline();
  colourPoints();
});
$('handle').addEventListener('change', attachHandle);
// For the browser tests: where the handle is, and a point along one of its arrows (the gizmo keeps
// a constant size on screen, as TransformControls sizes it).
state.THREE = THREE;
state.handlePosition = () => handle.position.toArray();
state.handleAxisPoint = (axis, along) => {
  const size = handle.position.distanceTo(camera.position) * Math.min(1.9 * Math.tan(Math.PI * camera.fov / 360) / camera.zoom, 7) / 4;
  const p = handle.position.clone();
  p.setComponent(axis, p.getComponent(axis) + along * size);
  return p.toArray();
};
$('frameAll').addEventListener('click', frameAll);
$('frameSelected').addEventListener('click', frameSelected);
$('upAxis').addEventListener('change', frameAll);
$('showSlicePlane').addEventListener('change', showSlicePlane);
for (const id of ['minX', 'minY', 'minZ', 'maxX', 'maxY', 'maxZ', 'cX', 'cY', 'cZ', 'radius']) $(id).addEventListener('change', showOutline);
window.addEventListener('keydown', (event) => {
  if (event.ctrlKey || event.metaKey || event.altKey || ['INPUT', 'SELECT', 'TEXTAREA'].includes(event.target.tagName)) return;
  if (event.key === 'Home') { event.preventDefault(); frameAll(); }
  if (event.key === 'f' || event.key === 'F') { event.preventDefault(); frameSelected(); }
  const handleKeys = { w: 'move', r: 'resize', s: 'slice', Escape: '' };
  if (event.key in handleKeys || event.key.toLowerCase() in handleKeys) {
    const mode = handleKeys[event.key] ?? handleKeys[event.key.toLowerCase()];
    $('handle').value = $('handle').value === mode ? '' : mode; // the same key again drops the handle
    attachHandle();
  }
});

// --- wiring --------------------------------------------------------------------------------------
$('grid').addEventListener('change', () => guarded(async () => {
  state.grid = $('grid').value;
  showEditFields();
  $('rampMax').value = ''; // the new grid's range
  await loadPoints(false);
  await showGrid();
}));
$('budget').addEventListener('change', () => guarded(() => loadPoints(false)));
for (const id of ['rampMin', 'rampMax']) $(id).addEventListener('change', () => { colourPoints(); buildVolume(); guarded(loadSlice); });
$('pointScale').addEventListener('change', updatePointSize);
$('showMesh').addEventListener('change', () => guarded(loadMesh));
$('sliceAxis').addEventListener('change', () => { const g = gridInfo(state.grid); if (g && g.index_min) setupSlice(g); });
$('sliceIndex').addEventListener('input', () => { showSlicePlane(); guarded(loadSlice); });
$('shape').addEventListener('change', () => { showShapeFields(); showOutline(); colourPoints(); });

guarded(async () => {
  await loadInfo();
  await loadPoints(true);
  await loadMesh();
});
