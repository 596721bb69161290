// vxf view: the voxel editor's page. Every edit is a request to the server, which applies the
// same libvxf operator `vxf op` runs and records it; the page only draws what the server holds.
import * as THREE from 'three';
import { OrbitControls } from '/OrbitControls.js';

const $ = (id) => document.getElementById(id);
const state = { info: null, grid: null, cloud: null, ready: false, fps: 0, selected: false, lastError: '' };
window.vxfView = state; // for the browser tests

function status(text, error = false) {
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

// Dynamic resolution: below 30 frames a second (a software renderer, a big grid) the canvas is
// drawn at fewer pixels, down to 0.4 of the screen's; above 50 at more, up to all of them.
let frames = 0, since = performance.now(), pixelRatio = 1;
function animate() {
  requestAnimationFrame(animate);
  sun.position.copy(camera.position);
  controls.update();
  renderer.render(scene, camera);
  frames++;
  const now = performance.now();
  if (now - since > 1000) {
    state.fps = frames * 1000 / (now - since);
    frames = 0;
    since = now;
    const wanted = state.fps < 30 ? Math.max(0.4, pixelRatio * 0.8) : state.fps > 50 ? Math.min(1, pixelRatio * 1.25) : pixelRatio;
    if (wanted !== pixelRatio) { pixelRatio = wanted; renderer.setPixelRatio(pixelRatio); resize(); }
    state.pixelRatio = pixelRatio;
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
  $('steps').innerHTML = state.info.steps.map((s, i) => `${i + 1}. ${s.op} ${JSON.stringify(s.params)}`).join('<br>');
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

function fit(lo, hi) {
  const centre = new THREE.Vector3((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2);
  const size = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-6);
  camera.near = size / 1000;
  camera.far = size * 100;
  camera.position.set(centre.x + 0.2 * size, centre.y - 1.9 * size, centre.z + 0.6 * size);
  camera.up.set(0, 0, 1);
  controls.target.copy(centre);
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
container.addEventListener('pointerdown', (event) => {
  if (!event.shiftKey || !points) return;
  event.stopPropagation();
  event.preventDefault();
  brushStart = local(event);
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
  status(message);
}

async function guarded(action) {
  try { await action(); } catch (error) { status(error.message, true); }
}

$('select').addEventListener('click', () => guarded(async () => {
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
$('apply').addEventListener('click', () => guarded(async () => {
  const extra = { hue_shift: parseFloat($('hue').value) || 0, saturation: parseFloat($('sat').value), value: parseFloat($('val').value) };
  if ($('doSet').checked) {
    const hex = $('color').value;
    extra.set = [1, 3, 5].map((i) => Math.pow(parseInt(hex.substr(i, 2), 16) / 255, 2.2) * rampRange()[1]);
  }
  const report = await apply('edit', editParams(extra));
  await refresh(`edit: ${report}`);
}));
$('add').addEventListener('click', () => guarded(async () => refresh(`edit: ${await apply('edit', editParams({ add: true }))}`)));
$('remove').addEventListener('click', () => guarded(async () => refresh(`edit: ${await apply('edit', editParams({ remove: true }))}`)));
$('undo').addEventListener('click', () => guarded(async () => {
  const result = await (await call('POST', '/api/undo')).json();
  if (!result.steps.some((s) => s.op === 'select')) { state.selected = false; $('selected').textContent = ''; }
  await refresh(result.undone ? 'undone' : 'nothing to undo');
}));
$('export').addEventListener('click', () => guarded(async () => {
  const body = { path: $('exportPath').value, mode: $('exportMode').value, grid: state.grid, smooth: parseInt($('smooth').value) || 0 };
  const result = await (await call('POST', '/api/export', body)).json();
  status(`wrote ${result.written}`);
  state.lastExport = result.written;
}));

$('render').addEventListener('click', () => guarded(async () => {
  status('rendering…');
  const body = { width: parseInt($('renderWidth').value) || 480, height: parseInt($('renderHeight').value) || 360 };
  const result = await (await call('POST', '/api/render', body)).json();
  $('renderImage').src = `/api/image?token=${encodeURIComponent(token)}&t=${Date.now()}`;
  $('renderReport').textContent = `${result.ran.join(' + ')} in ${result.seconds.toFixed(1)} s`;
  status(`rendered: ran ${result.ran.join(', ')}`);
  state.rendered = result;
}));

// --- wiring --------------------------------------------------------------------------------------
$('grid').addEventListener('change', () => guarded(async () => { state.grid = $('grid').value; await loadPoints(false); }));
$('budget').addEventListener('change', () => guarded(() => loadPoints(false)));
for (const id of ['rampMin', 'rampMax']) $(id).addEventListener('change', () => { colourPoints(); guarded(loadSlice); });
$('pointScale').addEventListener('change', updatePointSize);
$('showMesh').addEventListener('change', () => guarded(loadMesh));
$('sliceAxis').addEventListener('change', () => { const g = gridInfo(state.grid); if (g && g.index_min) setupSlice(g); });
$('sliceIndex').addEventListener('input', () => guarded(loadSlice));
$('shape').addEventListener('change', () => { showShapeFields(); colourPoints(); });

guarded(async () => {
  await loadInfo();
  await loadPoints(true);
  await loadMesh();
});
