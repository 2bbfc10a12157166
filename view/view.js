// The browser view of a radiosity run (man page, --view and view.html):
// the mesh with its radiosity per vertex, drawn with WebGL as final.png is
// drawn (the same camera, Gouraud shading, exposure, then sRGB), a walk
// through it, and the run's numbers and error curve. Live, it asks the
// run's server for state.json and mesh.bin; in view.html both are
// embedded in the page.
'use strict';
(function () {
  const $ = (id) => document.getElementById(id);
  const canvas = $('view');
  const chart = $('chart');
  const slider = $('exposure');

  let state = null;   // the last state.json
  let rows = [];      // log.csv's rows: [seconds, shots, wave, elements, unshot, rms, rel_rms]
  let mesh = null;    // the drawn snapshot (parseMesh) and its GL buffers
  let camera = null;  // {eye, fwd}: eye in scene coordinates, fwd unit
  let ended = false;  // the run has ended (or the page is view.html)
  const keys = new Set();
  let lastFrame = 0;

  function setStatus(text, cls) {
    const s = $('status');
    s.textContent = text;
    s.className = cls || '';
  }

  // ---- WebGL ----------------------------------------------------------

  const gl = canvas.getContext('webgl', {antialias: false, preserveDrawingBuffer: true});
  let program = null, uintIndices = false;
  const VERTEX = `
    attribute vec3 a_pos;
    attribute vec3 a_col;
    uniform mat4 u_mvp;
    varying vec3 v_col;
    void main() { v_col = a_col; gl_Position = u_mvp * vec4(a_pos, 1.0); }`;
  // Linear radiosity in, times the exposure, clamped, then the exact sRGB
  // curve per pixel, as final.png is encoded (image.cpp).
  const FRAGMENT = `
    precision highp float;
    varying vec3 v_col;
    uniform float u_exposure;
    void main() {
      vec3 c = clamp(v_col * u_exposure, 0.0, 1.0);
      vec3 s = mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055,
                   step(vec3(0.0031308), c));
      gl_FragColor = vec4(s, 1.0);
    }`;

  function compile(type, text) {
    const sh = gl.createShader(type);
    gl.shaderSource(sh, text);
    gl.compileShader(sh);
    if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(sh));
    return sh;
  }

  function initGL() {
    program = gl.createProgram();
    gl.attachShader(program, compile(gl.VERTEX_SHADER, VERTEX));
    gl.attachShader(program, compile(gl.FRAGMENT_SHADER, FRAGMENT));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
    uintIndices = !!gl.getExtension('OES_element_index_uint');
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LESS);
    // Faces are one-sided, counter-clockwise from the front, as the
    // program's pictures cull them.
    gl.enable(gl.CULL_FACE);
    gl.cullFace(gl.BACK);
    gl.frontFace(gl.CCW);
  }

  // mesh.bin (view.h, ViewMeshBlob): little-endian, as every machine
  // that runs a browser is, so the arrays are read in place.
  function parseMesh(buffer) {
    const dv = new DataView(buffer);
    if (buffer.byteLength < 40 || dv.getUint32(0, true) !== 0x31575652) throw new Error('not a mesh snapshot');
    const n = dv.getUint32(4, true), m = dv.getUint32(8, true);
    if (buffer.byteLength !== 40 + 24 * n + 12 * m) throw new Error('mesh snapshot of the wrong size');
    const origin = [dv.getFloat64(16, true), dv.getFloat64(24, true), dv.getFloat64(32, true)];
    const pos = new Float32Array(buffer, 40, 3 * n);
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < 3 * n; i++) {
      const k = i % 3;
      if (pos[i] < lo[k]) lo[k] = pos[i];
      if (pos[i] > hi[k]) hi[k] = pos[i];
    }
    let indices = new Uint32Array(buffer, 40 + 24 * n, 3 * m);
    if (!uintIndices) {
      if (n > 65536) throw new Error('this browser draws at most 65536 vertices (no OES_element_index_uint)');
      indices = Uint16Array.from(indices);
    }
    return {
      n, m, origin, lo, hi, indices, pos,
      exposure: dv.getFloat32(12, true),
      col: new Float32Array(buffer, 40 + 12 * n, 3 * n),
    };
  }

  function upload(next) {
    if (mesh) for (const b of [mesh.posBuf, mesh.colBuf, mesh.idxBuf]) gl.deleteBuffer(b);
    next.posBuf = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, next.posBuf);
    gl.bufferData(gl.ARRAY_BUFFER, next.pos, gl.STATIC_DRAW);
    next.colBuf = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, next.colBuf);
    gl.bufferData(gl.ARRAY_BUFFER, next.col, gl.STATIC_DRAW);
    next.idxBuf = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, next.idxBuf);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, next.indices, gl.STATIC_DRAW);
    delete next.pos;
    delete next.col;
    delete next.indices;
    mesh = next;
    if (!camera) resetCamera();
    updateExposure();
  }

  // ---- the camera -----------------------------------------------------

  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const norm = (a) => scale(a, 1 / Math.hypot(a[0], a[1], a[2]));

  function resetCamera() {
    const c = state.camera;
    camera = {eye: c.eye.slice(), fwd: norm(sub(c.target, c.eye))};
  }

  // The camera's frame as the program's renderer takes it (image.cpp):
  // right = fwd x +y, up = right x fwd; looking straight down (up), -z (+z)
  // at the top.
  function frame(fwd) {
    let right = cross(fwd, [0, 1, 0]);
    if (Math.hypot(right[0], right[1], right[2]) < 1e-6) right = cross(fwd, [0, 0, fwd[1] > 0 ? 1 : -1]);
    right = norm(right);
    return {right, up: cross(right, fwd)};
  }

  function diagonal() {
    return Math.max(1e-30, Math.hypot(mesh.hi[0] - mesh.lo[0], mesh.hi[1] - mesh.lo[1], mesh.hi[2] - mesh.lo[2]));
  }

  // Column-major: camera space (x right, y up, z depth) to clip space with
  // the vertical field of view of the camera and the canvas' aspect.
  function matrix() {
    const eye = sub(camera.eye, mesh.origin);
    const {right, up} = frame(camera.fwd);
    const fwd = camera.fwd;
    const ty = Math.tan(state.camera.fov * Math.PI / 360);
    const tx = ty * canvas.width / canvas.height;
    let far = 0;
    for (let i = 0; i < 8; i++) {
      const corner = [i & 1 ? mesh.hi[0] : mesh.lo[0], i & 2 ? mesh.hi[1] : mesh.lo[1], i & 4 ? mesh.hi[2] : mesh.lo[2]];
      far = Math.max(far, dot(sub(corner, eye), fwd));
    }
    far = Math.max(far * 1.01, 1e-3 * diagonal());
    const near = far * 2e-4;
    const a = (far + near) / (far - near), b = -2 * far * near / (far - near);
    const row = (v, s, t) => [v[0] * s, v[1] * s, v[2] * s, -dot(v, eye) * s + t];
    const r0 = row(right, 1 / tx, 0), r1 = row(up, 1 / ty, 0), r2 = row(fwd, a, b), r3 = row(fwd, 1, 0);
    const m = new Float32Array(16);
    for (let c = 0; c < 4; c++) {
      m[4 * c] = r0[c];
      m[4 * c + 1] = r1[c];
      m[4 * c + 2] = r2[c];
      m[4 * c + 3] = r3[c];
    }
    return m;
  }

  function exposure() {
    return mesh ? mesh.exposure * Math.pow(2, Number(slider.value)) : 1;
  }

  function draw() {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
    const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) {
      canvas.width = w;
      canvas.height = h;
    }
    gl.viewport(0, 0, w, h);
    gl.clearColor(0, 0, 0, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    if (!mesh) return;
    gl.useProgram(program);
    gl.uniformMatrix4fv(gl.getUniformLocation(program, 'u_mvp'), false, matrix());
    gl.uniform1f(gl.getUniformLocation(program, 'u_exposure'), exposure());
    for (const [name, buf] of [['a_pos', mesh.posBuf], ['a_col', mesh.colBuf]]) {
      const at = gl.getAttribLocation(program, name);
      gl.bindBuffer(gl.ARRAY_BUFFER, buf);
      gl.enableVertexAttribArray(at);
      gl.vertexAttribPointer(at, 3, gl.FLOAT, false, 0, 0);
    }
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, mesh.idxBuf);
    gl.drawElements(gl.TRIANGLES, 3 * mesh.m, uintIndices ? gl.UNSIGNED_INT : gl.UNSIGNED_SHORT, 0);
    canvas.dataset.frames = String(Number(canvas.dataset.frames || 0) + 1);
    canvas.dataset.snapshot = String(mesh.id);
  }

  let drawQueued = false;
  function redraw() {
    if (drawQueued) return;
    drawQueued = true;
    requestAnimationFrame((t) => {
      drawQueued = false;
      walk(t);
      draw();
      if (keys.size) redraw();
    });
  }

  // W A S D along the view and across it, Q E down and up, a quarter of
  // the scene's diagonal a second (Shift: four times that).
  function walk(t) {
    const dt = lastFrame ? Math.min(0.1, (t - lastFrame) / 1000) : 0;
    lastFrame = keys.size ? t : 0;
    if (!mesh || !camera || !dt) return;
    const {right} = frame(camera.fwd);
    const speed = diagonal() * 0.25 * (keys.has('shift') ? 4 : 1) * dt;
    const go = (v, s) => { camera.eye = [camera.eye[0] + v[0] * s, camera.eye[1] + v[1] * s, camera.eye[2] + v[2] * s]; };
    if (keys.has('w')) go(camera.fwd, speed);
    if (keys.has('s')) go(camera.fwd, -speed);
    if (keys.has('d')) go(right, speed);
    if (keys.has('a')) go(right, -speed);
    if (keys.has('e')) go([0, 1, 0], speed);
    if (keys.has('q')) go([0, 1, 0], -speed);
  }

  const MOVES = new Set(['w', 'a', 's', 'd', 'q', 'e']);
  window.addEventListener('keydown', (ev) => {
    if (ev.target === slider || ev.ctrlKey || ev.metaKey || ev.altKey) return;
    const k = ev.key.toLowerCase();
    if (k === 'shift') keys.add(k);
    else if (MOVES.has(k)) keys.add(k);
    else if (k === 'r' && state) { resetCamera(); redraw(); }
    else return;
    ev.preventDefault();
    redraw();
  });
  window.addEventListener('keyup', (ev) => keys.delete(ev.key.toLowerCase()));
  window.addEventListener('blur', () => keys.clear());

  // Mouse look: dragging turns the view (yaw about +y, pitch within 89
  // degrees of level).
  let drag = null;
  canvas.addEventListener('pointerdown', (ev) => {
    drag = {x: ev.clientX, y: ev.clientY};
    canvas.setPointerCapture(ev.pointerId);
    canvas.focus();
  });
  canvas.addEventListener('pointerup', () => { drag = null; });
  canvas.addEventListener('pointermove', (ev) => {
    if (!drag || !camera) return;
    const f = camera.fwd;
    let yaw = Math.atan2(f[0], -f[2]);
    let pitch = Math.asin(Math.max(-1, Math.min(1, f[1])));
    yaw += (ev.clientX - drag.x) * 0.004;
    pitch -= (ev.clientY - drag.y) * 0.004;
    const lim = 89 * Math.PI / 180;
    pitch = Math.max(-lim, Math.min(lim, pitch));
    camera.fwd = [Math.sin(yaw) * Math.cos(pitch), Math.sin(pitch), -Math.cos(yaw) * Math.cos(pitch)];
    drag = {x: ev.clientX, y: ev.clientY};
    redraw();
  });
  window.addEventListener('resize', redraw);

  function updateExposure() {
    const s = Number(slider.value);
    $('exposure-value').textContent = (s >= 0 ? '+' : '') + s.toFixed(1) + ' EV';
    $('exposure-value').title = 'exposure ' + exposure().toPrecision(4) + ' (automatic ' +
                                (mesh ? mesh.exposure.toPrecision(4) : '-') + ')';
    redraw();
  }
  slider.addEventListener('input', updateExposure);

  // ---- the panel ------------------------------------------------------

  function show(id, text, value) {
    const el = $(id);
    el.textContent = text;
    el.dataset.value = String(value);
  }

  function duration(s) {
    if (s < 60) return s.toFixed(1) + ' s';
    const m = Math.floor(s / 60), h = Math.floor(m / 60);
    const two = (x) => String(x).padStart(2, '0');
    return h ? h + ':' + two(m % 60) + ':' + two(Math.floor(s % 60)) : m + ':' + two(Math.floor(s % 60));
  }

  function updatePanel() {
    $('title').textContent = state.scene;
    document.title = state.scene + ' - radiosity';
    const r = rows[rows.length - 1];
    if (r) {
      show('wave', String(r[2]), r[2]);
      show('shots', String(r[1]), r[1]);
      show('unshot', r[4].toExponential(3), r[4]);
      show('elements', String(r[3]), r[3]);
      show('time', duration(r[0]), r[0]);
      $('rms-row').hidden = r[5] === null;
      if (r[5] !== null) show('rms', r[5].toExponential(3) + ' (' + (100 * r[6]).toFixed(2) + '%)', r[5]);
    }
    show('workers', state.workers ? String(state.workers) : '0 (master alone)', state.workers);
    if (mesh) show('picture', mesh.shots + ' shots', mesh.shots);
    drawChart();
  }

  // The unshot fraction (and the relative RMS error, with --reference)
  // against run time, a log scale down to below the target; dashed: where
  // a wave starts, and the target.
  function drawChart() {
    const c = chart.getContext('2d');
    const W = chart.width, H = chart.height, L = 34, B = 14;
    c.clearRect(0, 0, W, H);
    c.font = '10px sans-serif';
    c.fillStyle = '#99a';
    if (!rows.length) return;
    const tmax = Math.max(1e-3, rows[rows.length - 1][0]);
    let lo = state.epsilon;
    for (const r of rows) {
      if (r[4] > 0) lo = Math.min(lo, r[4]);
      if (r[6] > 0) lo = Math.min(lo, r[6]);
    }
    const top = 0, bottom = Math.floor(Math.log10(lo)) - 0.2;
    const x = (t) => L + (W - L - 4) * t / tmax;
    const y = (v) => 4 + (H - B - 8) * (top - Math.log10(v)) / (top - bottom);
    c.strokeStyle = '#445';
    c.lineWidth = 1;
    for (let d = 0; d >= Math.ceil(bottom); d--) {
      c.beginPath();
      c.moveTo(L, y(Math.pow(10, d)));
      c.lineTo(W - 4, y(Math.pow(10, d)));
      c.stroke();
      if (d % 2 === 0 || bottom > -5) c.fillText(d ? '1e' + d : '1', 2, y(Math.pow(10, d)) + 3);
    }
    c.fillText('0', L - 3, H - 2);
    c.fillText(duration(tmax), W - 40, H - 2);
    c.setLineDash([3, 3]);
    c.strokeStyle = '#777';
    for (let i = 1; i < rows.length; i++)
      if (rows[i][2] !== rows[i - 1][2]) {
        c.beginPath();
        c.moveTo(x(rows[i][0]), 4);
        c.lineTo(x(rows[i][0]), H - B);
        c.stroke();
      }
    c.strokeStyle = '#6a6';
    c.beginPath();
    c.moveTo(L, y(state.epsilon));
    c.lineTo(W - 4, y(state.epsilon));
    c.stroke();
    c.setLineDash([]);
    const line = (k, color) => {
      c.strokeStyle = color;
      c.beginPath();
      let started = false;
      for (const r of rows) {
        if (!(r[k] > 0)) continue;
        if (started) c.lineTo(x(r[0]), y(r[k]));
        else c.moveTo(x(r[0]), y(r[k]));
        started = true;
      }
      c.stroke();
    };
    line(4, '#eee');
    line(6, '#f0a040');
  }

  // ---- data -----------------------------------------------------------

  function takeState(s) {
    if (s.first !== rows.length) rows = rows.slice(0, s.first);
    rows = rows.concat(s.rows);
    state = s;
    ended = s.status !== 'running';
  }

  function takeMesh(buffer, id, shots) {
    const next = parseMesh(buffer);
    next.id = id;
    next.shots = shots;
    upload(next);
    updatePanel();
    redraw();
  }

  let fetching = false;
  async function fetchMesh() {
    fetching = true;
    try {
      const r = await fetch('mesh.bin', {cache: 'no-store'});
      if (r.ok) {
        const [id, shots] = (r.headers.get('X-Radiosity-Snapshot') || '0 0').split(' ').map(Number);
        const buffer = await r.arrayBuffer();
        try {
          takeMesh(buffer, id, shots);
        } catch (e) {  // a bad snapshot: said, and the next one is asked for
          setStatus('snapshot ' + id + ': ' + e.message, 'error');
        }
      }
    } finally {
      fetching = false;
    }
  }

  // Live: the state every half second (the rows not seen yet), the mesh
  // when the server has a newer snapshot than the one drawn.
  async function poll() {
    try {
      const r = await fetch('state.json?rows=' + rows.length, {cache: 'no-store'});
      if (!r.ok) throw new Error('the server answered ' + r.status);
      takeState(await r.json());
      if (ended) setStatus('the run has ended: ' + state.status, 'ended');
      else setStatus('running');
      updatePanel();
      if (!fetching && (!mesh || mesh.id !== state.snapshot.id) && state.snapshot.id) await fetchMesh();
    } catch (e) {
      if (state) setStatus(ended ? 'the run has ended: ' + state.status : 'the run is gone (' + e.message + '); its last picture', 'ended');
      else setStatus('cannot reach the run: ' + e.message, 'error');
      if (state) return;  // the run is over: what is shown stays
    }
    setTimeout(poll, 500);
  }

  function start() {
    if (!gl) {
      setStatus('this browser has no WebGL', 'error');
      return;
    }
    try {
      initGL();
    } catch (e) {
      setStatus('WebGL: ' + e.message, 'error');
      return;
    }
    updateExposure();
    const embedded = $('radiosity-state');
    if (!embedded) {
      poll();
      return;
    }
    // view.html: the final state and mesh are in the page.
    try {
      takeState(JSON.parse(embedded.textContent));
      const text = atob($('radiosity-mesh').textContent.trim());
      const bytes = new Uint8Array(text.length);
      for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
      setStatus('the run ended: ' + state.status, 'ended');
      takeMesh(bytes.buffer, state.snapshot.id, state.snapshot.shots);
    } catch (e) {
      setStatus('cannot read the embedded result: ' + e.message, 'error');
    }
  }

  start();
})();
