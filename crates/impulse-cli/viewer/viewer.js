// The replay page of `impulse run --html` (crates/impulse-cli/src/html.rs writes it).
//
// Plain JavaScript and WebGL 2, no library and no network: the run is read from the page's
// JSON header (#impulse-header) and its base64 data block (#impulse-data), whose layout
// html.rs documents. Times are seconds, lengths metres, energies joules (the scene's SI
// units). `window.impulseViewer` is the page's programming interface (the browser test and
// a user's console use it); the URL's hash (#t=1.5&body=name) sets the time and the selected
// body when the page opens.
"use strict";
(function () {
  // ---- Named constants -------------------------------------------------------------------
  const FORMAT = "impulse-viewer 1";
  /** Colours (sRGB, 0..1) of the body kinds, the selected body and the impact flashes. */
  const COLOUR = {
    fixed: [0.62, 0.62, 0.6],
    dynamic: [0.95, 0.55, 0.2],
    driven: [0.25, 0.55, 0.95],
    selected: [1.0, 0.0, 1.0],
    flash: [1.0, 0.9, 0.1],
  };
  /** Vertical field of view of the camera (radians). */
  const FOV = (45 * Math.PI) / 180;
  /** The first view: azimuth and elevation of the eye around the scene (radians). */
  const START_YAW = (-55 * Math.PI) / 180;
  const START_PITCH = (35 * Math.PI) / 180;
  /** Room around the framed bodies (1 = they touch the view's edges). */
  const FRAME_MARGIN = 1.15;
  /** Fixed bodies up to this many times the moving bodies' extent are framed too. */
  const FIXED_FRAMED = 2;
  /** Near and far clip planes as fractions/multiples of the eye's distance. */
  const NEAR = 0.01;
  const FAR = 200;
  /** Orbit speed (radians per pixel dragged) and zoom speed (per wheel unit). */
  const ORBIT_PER_PX = 0.008;
  const ZOOM_PER_WHEEL = 0.0015;
  /** Highest elevation of the eye, short of the pole where the view would flip. */
  const MAX_PITCH = 1.55;
  /** A press that moves less than this (CSS px) is a click (a pick), not a drag. */
  const CLICK_PX = 4;
  /** How long an impact flashes, in simulated seconds, and at least this many frames. */
  const FLASH_S = 0.06;
  const FLASH_FRAMES = 3;
  /** Radius of a flash at its start, as a fraction of the framed scene's size. */
  const FLASH_SIZE = 0.015;
  /** Light: ambient share and a key light from above the eye. */
  const AMBIENT = 0.35;
  /** Frame intervals kept for the frame-time statistics. */
  const FRAME_SAMPLES = 600;
  /** Playback keeps at least this frame rate by drawing fewer pixels (the canvas scaled up):
   * every ADAPT_FRAMES frames, if their mean interval is longer, the resolution drops by
   * ADAPT_STEP, down to MIN_RENDER_SCALE. A paused view is always drawn at full resolution. */
  const TARGET_FPS = 30;
  const ADAPT_FRAMES = 10;
  const ADAPT_STEP = 0.7;
  const MIN_RENDER_SCALE = 0.35;

  const api = (window.impulseViewer = { ready: false, errors: [] });
  window.addEventListener("error", (e) => api.errors.push(String(e.message)));

  const $ = (id) => document.getElementById(id);
  function fail(message) {
    const box = $("message");
    box.textContent = message;
    box.hidden = false;
    api.failed = message;
    throw new Error(message);
  }

  // ---- The run -------------------------------------------------------------------------
  const header = JSON.parse($("impulse-header").textContent);
  if (header.format !== FORMAT) {
    fail(`This page holds data of format "${header.format}"; this viewer reads "${FORMAT}".`);
  }
  const raw = atob($("impulse-data").textContent.trim());
  if (raw.length !== header.bytes) {
    fail(`The data block holds ${raw.length} bytes, the header says ${header.bytes}.`);
  }
  const bytes = new Uint8Array(raw.length);
  for (let i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
  // The block is little-endian; so is every platform browsers run on (checked here).
  if (new Uint8Array(new Uint32Array([1]).buffer)[0] !== 1) {
    fail("This viewer needs a little-endian platform.");
  }
  let at = 0;
  const f32 = (n) => {
    const a = new Float32Array(bytes.buffer, at, n);
    at += 4 * n;
    return a;
  };
  const u32 = (n) => {
    const a = new Uint32Array(bytes.buffer, at, n);
    at += 4 * n;
    return a;
  };
  const meshData = header.meshes.map((m) => ({
    positions: f32(3 * m.vertices),
    normals: f32(3 * m.vertices),
    indices: u32(m.indices),
  }));
  const bodies = header.bodies;
  const B = bodies.length;
  const F = header.frames;
  const E = header.events;
  const times = f32(F);
  const poses = f32(F * B * 7);
  const speeds = f32(F * B);
  const energies = f32(F * B);
  const totals = f32(F * 2);
  const eventNumbers = f32(E * 5);
  const eventBodies = u32(E * 2);
  const start = times[0];
  const end = times[F - 1];

  // ---- Small vector and matrix helpers (column-major 4×4, as WebGL reads them) ----------
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
  const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const norm = (a) => scale(a, 1 / Math.hypot(a[0], a[1], a[2]));
  /** Vector v turned by the unit quaternion q = (x, y, z, w): v + 2 q⃗ × (q⃗ × v + w v). */
  const turn = (q, v) => add(v, scale(cross(q, add(cross(q, v), scale(v, q[3]))), 2));
  function multiply(a, b) {
    const m = new Float32Array(16);
    for (let c = 0; c < 4; c++)
      for (let r = 0; r < 4; r++) {
        let s = 0;
        for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
        m[c * 4 + r] = s;
      }
    return m;
  }
  function lookAt(eye, target, up) {
    const f = norm(sub(target, eye));
    const s = norm(cross(f, up));
    const u = cross(s, f);
    return new Float32Array([
      s[0], u[0], -f[0], 0,
      s[1], u[1], -f[1], 0,
      s[2], u[2], -f[2], 0,
      -dot(s, eye), -dot(u, eye), dot(f, eye), 1,
    ]);
  }
  function perspective(fov, aspect, near, far) {
    const t = 1 / Math.tan(fov / 2);
    return new Float32Array([
      t / aspect, 0, 0, 0,
      0, t, 0, 0,
      0, 0, (far + near) / (near - far), -1,
      0, 0, (2 * far * near) / (near - far), 0,
    ]);
  }

  // ---- Poses at a time -----------------------------------------------------------------
  /** The frame at or before `t` and the fraction of the way to the next one. */
  function frameAt(t) {
    let lo = 0;
    let hi = F - 1;
    if (t <= times[0]) return [0, 0];
    if (t >= times[hi]) return [hi, 0];
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (times[mid] <= t) lo = mid;
      else hi = mid;
    }
    return [lo, (t - times[lo]) / (times[lo + 1] - times[lo])];
  }
  /** Body `b`'s position and rotation (x, y, z, w) at `t`: linear between frames, the
   * rotation normalised along the shorter way. */
  function poseAt(b, t) {
    const [k, s] = frameAt(t);
    const i = (k * B + b) * 7;
    if (s === 0) return [poses.slice(i, i + 3), poses.slice(i + 3, i + 7)];
    const j = i + B * 7;
    const p = [0, 1, 2].map((c) => poses[i + c] + s * (poses[j + c] - poses[i + c]));
    let d = 0;
    for (let c = 3; c < 7; c++) d += poses[i + c] * poses[j + c];
    const sign = d < 0 ? -1 : 1;
    const q = [3, 4, 5, 6].map((c) => poses[i + c] + s * (sign * poses[j + c] - poses[i + c]));
    const n = Math.hypot(q[0], q[1], q[2], q[3]);
    return [p, q.map((x) => x / n)];
  }

  // ---- WebGL ---------------------------------------------------------------------------
  /** Whether WebGL runs on a software renderer (SwiftShader, llvmpipe: no GPU, as on a CI
   * machine), where multisampling would halve the frame rate; asked of a throwaway context,
   * since a canvas's antialiasing is fixed when its context is made. */
  function softwareRenderer() {
    const probe = document.createElement("canvas").getContext("webgl2");
    if (!probe) return false;
    const debug = probe.getExtension("WEBGL_debug_renderer_info");
    const name = debug ? String(probe.getParameter(debug.UNMASKED_RENDERER_WEBGL)) : "";
    const lose = probe.getExtension("WEBGL_lose_context");
    if (lose) lose.loseContext();
    return /swiftshader|llvmpipe|software/i.test(name);
  }
  const canvas = $("gl");
  const gl = canvas.getContext("webgl2", { antialias: !softwareRenderer(), preserveDrawingBuffer: false });
  if (!gl) fail("This browser cannot run WebGL 2, which the replay needs.");
  const VERTEX = `#version 300 es
    in vec3 position;
    in vec3 normal;
    uniform mat4 viewProjection;
    uniform vec3 translation;
    uniform vec4 rotation;
    uniform float size;
    out vec3 worldNormal;
    vec3 turn(vec4 q, vec3 v) { return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v); }
    void main() {
      worldNormal = turn(rotation, normal);
      gl_Position = viewProjection * vec4(turn(rotation, size * position) + translation, 1.0);
    }`;
  const FRAGMENT = `#version 300 es
    precision highp float;
    in vec3 worldNormal;
    uniform vec3 colour;
    uniform vec3 light;
    uniform float ambient;
    uniform bool unlit;
    out vec4 result;
    void main() {
      if (unlit) { result = vec4(colour, 1.0); return; }
      float diffuse = abs(dot(normalize(worldNormal), light));
      result = vec4(colour * (ambient + (1.0 - ambient) * diffuse), 1.0);
    }`;
  function shader(type, source) {
    const s = gl.createShader(type);
    gl.shaderSource(s, source);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) fail("shader: " + gl.getShaderInfoLog(s));
    return s;
  }
  const program = gl.createProgram();
  gl.attachShader(program, shader(gl.VERTEX_SHADER, VERTEX));
  gl.attachShader(program, shader(gl.FRAGMENT_SHADER, FRAGMENT));
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) fail("program: " + gl.getProgramInfoLog(program));
  const uniform = {};
  for (const name of ["viewProjection", "translation", "rotation", "size", "colour", "light", "ambient", "unlit"]) {
    uniform[name] = gl.getUniformLocation(program, name);
  }
  const positionAt = gl.getAttribLocation(program, "position");
  const normalAt = gl.getAttribLocation(program, "normal");
  function upload(m) {
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    for (const [data, where] of [[m.positions, positionAt], [m.normals, normalAt]]) {
      gl.bindBuffer(gl.ARRAY_BUFFER, gl.createBuffer());
      gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW);
      gl.enableVertexAttribArray(where);
      gl.vertexAttribPointer(where, 3, gl.FLOAT, false, 0, 0);
    }
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, gl.createBuffer());
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, m.indices, gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    return { vao, count: m.indices.length };
  }
  const meshes = meshData.map(upload);
  /** Each mesh's box in its body's own frame: [lo, hi]. */
  const meshBoxes = meshData.map((m) => {
    const lo = [Infinity, Infinity, Infinity];
    const hi = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < m.positions.length; i += 3)
      for (let c = 0; c < 3; c++) {
        lo[c] = Math.min(lo[c], m.positions[i + c]);
        hi[c] = Math.max(hi[c], m.positions[i + c]);
      }
    return [lo, hi];
  });
  /** A unit sphere for the flashes. */
  const ball = upload(
    (function () {
      const [stacks, slices] = [8, 12];
      const positions = [];
      const indices = [];
      for (let i = 0; i <= stacks; i++)
        for (let j = 0; j <= slices; j++) {
          const th = (Math.PI * i) / stacks;
          const ph = (2 * Math.PI * j) / slices;
          positions.push(Math.sin(th) * Math.cos(ph), Math.sin(th) * Math.sin(ph), Math.cos(th));
        }
      for (let i = 0; i < stacks; i++)
        for (let j = 0; j < slices; j++) {
          const a = i * (slices + 1) + j;
          const b = a + slices + 1;
          indices.push(a, b, b + 1, a, b + 1, a + 1);
        }
      const p = new Float32Array(positions);
      return { positions: p, normals: p, indices: new Uint32Array(indices) };
    })(),
  );

  // ---- The camera ----------------------------------------------------------------------
  const up = norm(header.up);
  // Two horizontal axes: the world axis least along `up`, made perpendicular to it.
  const axis = [[1, 0, 0], [0, 1, 0], [0, 0, 1]].reduce((a, b) => (Math.abs(dot(a, up)) <= Math.abs(dot(b, up)) ? a : b));
  const east = norm(sub(axis, scale(up, dot(axis, up))));
  const north = cross(up, east);
  const camera = { target: [0, 0, 0], distance: 1, yaw: START_YAW, pitch: START_PITCH, size: 1 };
  /** Frames the scene as it starts: the bodies that move, and the fixed bodies no larger
   * than FIXED_FRAMED times their extent (a table, not a 100 m floor); every body when none
   * moves. The start, not the whole run: a ball that rolls off the table would shrink the
   * rest to a dot. */
  function frameAll() {
    // The world box of the listed bodies' meshes as they start (each mesh's own box turned
    // by the body's rotation: its eight corners).
    const box = (list) => {
      const lo = [Infinity, Infinity, Infinity];
      const hi = [-Infinity, -Infinity, -Infinity];
      for (const b of list) {
        const [mlo, mhi] = meshBoxes[bodies[b].mesh];
        const p = poses.subarray(b * 7, b * 7 + 3);
        const q = poses.subarray(b * 7 + 3, b * 7 + 7);
        for (let k = 0; k < 8; k++) {
          const w = add(turn(q, [0, 1, 2].map((c) => ((k >> c) & 1 ? mhi[c] : mlo[c]))), p);
          for (let c = 0; c < 3; c++) {
            lo[c] = Math.min(lo[c], w[c]);
            hi[c] = Math.max(hi[c], w[c]);
          }
        }
      }
      return [lo, hi];
    };
    const all = bodies.map((b, i) => i);
    const moving = all.filter((i) => bodies[i].kind !== "fixed");
    let [lo, hi] = box(moving.length ? moving : all);
    if (moving.length) {
      const extent = Math.hypot(...sub(hi, lo));
      const framed = all.filter((i) => bodies[i].kind !== "fixed" || 2 * bodies[i].radius <= FIXED_FRAMED * extent);
      [lo, hi] = box(framed);
    }
    if (!isFinite(lo[0])) return;
    camera.target = scale(add(lo, hi), 0.5);
    camera.size = Math.max(Math.hypot(...sub(hi, lo)), 1e-6);
    camera.yaw = START_YAW;
    camera.pitch = START_PITCH;
    // The nearest eye, along the view direction, that sees all eight corners of the box
    // with FRAME_MARGIN to spare: a corner c (from the target) at depth d + c·f is in view
    // when |c·r| ≤ (d + c·f)·tan(half width) / margin, and the same upward.
    resize();
    camera.distance = 1;
    const f = norm(sub(camera.target, eye()));
    const r = norm(cross(f, up));
    const u = cross(r, f);
    const tanV = Math.tan(FOV / 2) / FRAME_MARGIN;
    const tanH = (tanV * canvas.width) / Math.max(canvas.height, 1);
    let d = 0;
    for (let k = 0; k < 8; k++) {
      const corner = [0, 1, 2].map((c) => ((k >> c) & 1 ? hi[c] : lo[c]) - camera.target[c]);
      const depth = dot(corner, f);
      d = Math.max(d, Math.abs(dot(corner, r)) / tanH - depth, Math.abs(dot(corner, u)) / tanV - depth);
    }
    camera.distance = Math.max(d, camera.size * NEAR);
  }
  function eye() {
    const c = Math.cos(camera.pitch);
    const dir = add(add(scale(east, c * Math.cos(camera.yaw)), scale(north, c * Math.sin(camera.yaw))), scale(up, Math.sin(camera.pitch)));
    return add(camera.target, scale(dir, camera.distance));
  }
  function viewProjection() {
    const aspect = canvas.width / Math.max(canvas.height, 1);
    const d = camera.distance;
    const far = d * FAR + camera.size;
    return multiply(perspective(FOV, aspect, d * NEAR, far), lookAt(eye(), camera.target, up));
  }

  // ---- State and drawing ---------------------------------------------------------------
  const state = { time: start, playing: false, speed: 1, selected: -1, last: null, dirty: true, renderScale: 1 };
  const frameIntervals = [];
  const drawTimes = [];
  let pickBuffer = null;

  function resize() {
    const ratio = (window.devicePixelRatio || 1) * state.renderScale;
    const w = Math.max(1, Math.round(canvas.clientWidth * ratio));
    const h = Math.max(1, Math.round(canvas.clientHeight * ratio));
    if (canvas.width !== w || canvas.height !== h) {
      canvas.width = w;
      canvas.height = h;
      pickBuffer = null;
    }
  }
  function drawBodies(vp, pick) {
    gl.useProgram(program);
    gl.uniformMatrix4fv(uniform.viewProjection, false, vp);
    gl.uniform1i(uniform.unlit, pick ? 1 : 0);
    gl.uniform1f(uniform.ambient, AMBIENT);
    // A key light from behind the eye, a little above it.
    const e = norm(sub(eye(), camera.target));
    gl.uniform3fv(uniform.light, norm(add(e, scale(up, 0.6))));
    gl.uniform1f(uniform.size, 1);
    const solo = $("solo").checked && state.selected >= 0;
    for (let b = 0; b < B; b++) {
      if (solo && b !== state.selected) continue;
      const [p, q] = poseAt(b, state.time);
      gl.uniform3fv(uniform.translation, p);
      gl.uniform4fv(uniform.rotation, q);
      if (pick) {
        const id = b + 1;
        gl.uniform3f(uniform.colour, (id & 255) / 255, ((id >> 8) & 255) / 255, ((id >> 16) & 255) / 255);
      } else {
        gl.uniform3fv(uniform.colour, b === state.selected ? COLOUR.selected : COLOUR[bodies[b].kind]);
      }
      const m = meshes[bodies[b].mesh];
      gl.bindVertexArray(m.vao);
      gl.drawElements(gl.TRIANGLES, m.count, gl.UNSIGNED_INT, 0);
    }
    if (pick) return;
    // Impacts flash where they happened, shrinking as they age.
    const frameStep = F > 1 ? (end - start) / (F - 1) : 0;
    const window_ = Math.max(FLASH_S, FLASH_FRAMES * frameStep);
    gl.uniform1i(uniform.unlit, 1);
    gl.uniform3fv(uniform.colour, COLOUR.flash);
    gl.uniform4fv(uniform.rotation, [0, 0, 0, 1]);
    gl.bindVertexArray(ball.vao);
    for (let k = firstEventAfter(state.time - window_); k < E && eventNumbers[5 * k] <= state.time; k++) {
      if (solo && eventBodies[2 * k] !== state.selected && eventBodies[2 * k + 1] !== state.selected) continue;
      const age = (state.time - eventNumbers[5 * k]) / window_;
      gl.uniform1f(uniform.size, FLASH_SIZE * camera.size * (1 - 0.7 * age));
      gl.uniform3fv(uniform.translation, eventNumbers.subarray(5 * k + 1, 5 * k + 4));
      gl.drawElements(gl.TRIANGLES, ball.count, gl.UNSIGNED_INT, 0);
    }
  }
  function firstEventAfter(t) {
    let lo = 0;
    let hi = E;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (eventNumbers[5 * mid] < t) lo = mid + 1;
      else hi = mid;
    }
    return lo;
  }
  /** Binds `target` (null: the canvas), clears it to `background` and turns depth on. */
  function beginPass(target, background) {
    gl.bindFramebuffer(gl.FRAMEBUFFER, target);
    gl.viewport(0, 0, canvas.width, canvas.height);
    gl.clearColor(background[0], background[1], background[2], 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
  }
  function draw() {
    const t0 = performance.now();
    resize();
    beginPass(null, [0.875, 0.89, 0.91]);
    drawBodies(viewProjection(), false);
    updatePanels();
    drawTimes.push(performance.now() - t0);
    if (drawTimes.length > FRAME_SAMPLES) drawTimes.shift();
    state.dirty = false;
  }
  /** The body drawn at canvas pixel (x, y) (device pixels from the top left), or -1. */
  function pickAt(x, y) {
    if (!pickBuffer) {
      const colour = gl.createRenderbuffer();
      gl.bindRenderbuffer(gl.RENDERBUFFER, colour);
      gl.renderbufferStorage(gl.RENDERBUFFER, gl.RGBA8, canvas.width, canvas.height);
      const depth = gl.createRenderbuffer();
      gl.bindRenderbuffer(gl.RENDERBUFFER, depth);
      gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, canvas.width, canvas.height);
      pickBuffer = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, pickBuffer);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.RENDERBUFFER, colour);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depth);
    }
    beginPass(pickBuffer, [0, 0, 0]);
    drawBodies(viewProjection(), true);
    const px = new Uint8Array(4);
    gl.readPixels(Math.round(x), Math.round(canvas.height - 1 - y), 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    return px[0] + (px[1] << 8) + (px[2] << 16) - 1;
  }

  // ---- Panels: time line, body list, information, energy plot ---------------------------
  const scrub = $("scrub");
  scrub.min = start;
  scrub.max = end;
  $("title").textContent = header.title;
  $("title").title = `${header.model} · ${header.generator}`;
  $("model").textContent = header.model;
  $("count").textContent = `(${B})`;
  const fmt = (x, unit) => (Number.isFinite(x) ? `${Number(x.toPrecision(4))} ${unit}` : "—");
  const list = $("bodies");
  const rgb = (c) => `rgb(${c.map((x) => Math.round(255 * x)).join(",")})`;
  bodies.forEach((b, i) => {
    const li = document.createElement("li");
    const swatch = document.createElement("span");
    swatch.className = "swatch";
    swatch.style.background = rgb(COLOUR[b.kind]);
    li.append(swatch, document.createTextNode(b.name));
    li.title = `${b.name} (${b.kind})`;
    li.addEventListener("click", () => select(state.selected === i ? -1 : i));
    list.append(li);
  });
  function select(i) {
    const old = list.children[state.selected];
    if (old) old.classList.remove("selected");
    state.selected = i >= 0 && i < B ? i : -1;
    const li = list.children[state.selected];
    if (li) {
      li.classList.add("selected");
      li.scrollIntoView({ block: "nearest" });
    }
    state.dirty = true;
  }
  function updatePanels() {
    const [k, s] = frameAt(state.time);
    const nearest = Math.min(F - 1, s < 0.5 ? k : k + 1);
    setText($("time"), `${state.time.toFixed(3)} / ${end.toFixed(3)} s`);
    setText($("clock"), `t = ${state.time.toFixed(3)} s`);
    if (document.activeElement !== scrub) scrub.value = state.time;
    $("play").classList.toggle("playing", state.playing);
    if (state.selected !== shownInfo) {
      shownInfo = state.selected;
      if (state.selected < 0) {
        info.textContent = "Click a body (here or in the view) to see its speed and energy.";
      } else {
        info.replaceChildren(table(["name", "kind", "frame", "speed", "energy", "position"]));
      }
    }
    if (state.selected >= 0) {
      const b = state.selected;
      const [p] = poseAt(b, state.time);
      const values = [
        bodies[b].name,
        bodies[b].kind,
        `${nearest} (t = ${times[nearest].toFixed(4)} s)`,
        fmt(speeds[nearest * B + b], "m/s"),
        fmt(energies[nearest * B + b], "J"),
        Array.from(p, (x) => x.toFixed(4)).join(", ") + " m",
      ];
      values.forEach((v, k) => setText(infoCells[k], v));
    }
    // The plots are drawn once (again when their size changes); the cursors are moved.
    plotEnergy();
    plotEvents();
    const f = (state.time - start) / Math.max(end - start, 1e-12);
    const plotWidth = energyCanvas.clientWidth - PLOT.left - PLOT.right;
    energyCursor.style.transform = `translateX(${PLOT.left + f * plotWidth}px)`;
    eventsCursor.style.transform = `translateX(${f * eventsCanvas.clientWidth}px)`;
  }
  const info = $("info");
  let shownInfo = null;
  let infoCells = [];
  /** Sets an element's text only when it changes (a change costs a layout). */
  function setText(element, text) {
    if (element.textContent !== text) element.textContent = text;
  }
  /** A table of the named rows; their value cells become `infoCells`. */
  function table(names) {
    const t = document.createElement("table");
    infoCells = names.map((name) => {
      const tr = t.insertRow();
      tr.insertCell().textContent = name;
      return tr.insertCell();
    });
    return t;
  }
  /** Round tick values covering [lo, hi]: steps of 1, 2 or 5 times a power of ten. */
  function ticks(lo, hi, count) {
    const raw = (hi - lo) / Math.max(count, 1);
    const p = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw) || 10 * p;
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
    return out;
  }
  /** A 2-D canvas sized to its CSS box in device pixels, its context scaled to CSS pixels. */
  /** `null` when the canvas already shows its plot at its size. */
  function canvas2d(c) {
    const ratio = window.devicePixelRatio || 1;
    const w = c.clientWidth;
    const h = c.clientHeight;
    if (c.width === Math.round(w * ratio) && c.height === Math.round(h * ratio) && c.drawn) return null;
    c.width = Math.round(w * ratio);
    c.height = Math.round(h * ratio);
    c.drawn = true;
    const g = c.getContext("2d");
    g.setTransform(ratio, 0, 0, ratio, 0, 0);
    g.clearRect(0, 0, w, h);
    return [g, w, h];
  }
  const PLOT = { left: 46, right: 8, top: 18, bottom: 26 };
  const energyCanvas = $("energy");
  const energyCursor = $("energy-cursor");
  const eventsCursor = $("events-cursor");
  energyCursor.style.top = `${PLOT.top}px`;
  energyCursor.style.height = `calc(100% - ${PLOT.top + PLOT.bottom}px)`;
  const series = [
    ["kinetic", "#e8741f", (k) => totals[2 * k]],
    ["potential", "#3c78d8", (k) => totals[2 * k + 1]],
    ["total", "#222", (k) => totals[2 * k] + totals[2 * k + 1]],
  ];
  let energyRange = null;
  function plotEnergy() {
    const drawn = canvas2d(energyCanvas);
    if (!drawn) return;
    const [g, w, h] = drawn;
    if (!energyRange) {
      let lo = Infinity;
      let hi = -Infinity;
      for (let k = 0; k < F; k++)
        for (const [, , y] of series) {
          const v = y(k);
          if (Number.isFinite(v)) {
            lo = Math.min(lo, v);
            hi = Math.max(hi, v);
          }
        }
      if (!Number.isFinite(lo)) energyRange = "none";
      else {
        if (!(hi > lo)) [lo, hi] = [lo - 1, lo + 1];
        const pad = 0.05 * (hi - lo);
        energyRange = [lo - pad, hi + pad];
      }
    }
    if (energyRange === "none") {
      energyCursor.hidden = true;
      g.fillStyle = "#666";
      g.font = "12px system-ui, sans-serif";
      g.fillText("This run recorded no energies.", 10, 30);
      return;
    }
    const [lo, hi] = energyRange;
    const x = (t) => PLOT.left + ((t - start) / Math.max(end - start, 1e-12)) * (w - PLOT.left - PLOT.right);
    const y = (v) => h - PLOT.bottom - ((v - lo) / (hi - lo)) * (h - PLOT.top - PLOT.bottom);
    g.font = "10px system-ui, sans-serif";
    g.strokeStyle = "#e4e4e4";
    g.fillStyle = "#555";
    g.lineWidth = 1;
    g.textAlign = "right";
    g.textBaseline = "middle";
    for (const v of ticks(lo, hi, 5)) {
      g.beginPath();
      g.moveTo(PLOT.left, y(v));
      g.lineTo(w - PLOT.right, y(v));
      g.stroke();
      g.fillText(Number(v.toPrecision(6)).toString(), PLOT.left - 4, y(v));
    }
    g.textAlign = "center";
    g.textBaseline = "top";
    for (const t of ticks(start, end, 4)) {
      g.beginPath();
      g.moveTo(x(t), PLOT.top);
      g.lineTo(x(t), h - PLOT.bottom);
      g.stroke();
      g.fillText(Number(t.toPrecision(6)).toString(), x(t), h - PLOT.bottom + 3);
    }
    g.fillText("time (s)", (PLOT.left + w - PLOT.right) / 2, h - 12);
    g.textAlign = "right";
    g.fillText("J", PLOT.left - 4, 3);
    g.textAlign = "left";
    let lx = PLOT.left + 4;
    for (const [name, colour, value] of series) {
      g.strokeStyle = colour;
      g.lineWidth = 1.5;
      g.beginPath();
      let pen = false;
      for (let k = 0; k < F; k++) {
        const v = value(k);
        if (!Number.isFinite(v)) {
          pen = false;
          continue;
        }
        if (pen) g.lineTo(x(times[k]), y(v));
        else g.moveTo(x(times[k]), y(v));
        pen = true;
      }
      g.stroke();
      g.fillStyle = colour;
      g.fillRect(lx, 7, 10, 3);
      g.fillStyle = "#333";
      g.fillText(name, lx + 13, 3);
      lx += 18 + g.measureText(name).width;
    }
  }
  const eventsCanvas = $("events");
  /** The largest impulse, for the markers' heights (log scale over four decades). */
  let biggest = 0;
  for (let k = 0; k < E; k++) biggest = Math.max(biggest, eventNumbers[5 * k + 4]);
  function plotEvents() {
    const drawn = canvas2d(eventsCanvas);
    if (!drawn) return;
    const [g, w, h] = drawn;
    const x = (t) => ((t - start) / Math.max(end - start, 1e-12)) * w;
    g.fillStyle = "#f0f0f0";
    g.fillRect(0, 0, w, h);
    g.strokeStyle = "#d08000";
    g.lineWidth = 1;
    g.beginPath();
    for (let k = 0; k < E; k++) {
      const rel = Math.log10(Math.max(eventNumbers[5 * k + 4] / biggest, 1e-4)) / 4 + 1;
      const px = Math.round(x(eventNumbers[5 * k])) + 0.5;
      g.moveTo(px, h);
      g.lineTo(px, h - Math.max(3, rel * h));
    }
    g.stroke();
  }

  // ---- Playback ------------------------------------------------------------------------
  function setTime(t) {
    state.time = Math.min(end, Math.max(start, Number(t)));
    state.dirty = true;
  }
  function step(direction) {
    state.playing = false;
    const [k, s] = frameAt(state.time);
    const target = direction > 0 ? Math.min(F - 1, k + 1) : s > 0 ? k : Math.max(0, k - 1);
    setTime(times[target]);
  }
  function jumpToImpact(direction) {
    if (E === 0) return;
    state.playing = false;
    const k = firstEventAfter(state.time);
    if (direction > 0) {
      let j = k;
      while (j < E && eventNumbers[5 * j] <= state.time) j++;
      if (j < E) setTime(eventNumbers[5 * j]);
    } else if (k > 0) setTime(eventNumbers[5 * (k - 1)]);
  }
  function play(on) {
    state.playing = on;
    state.sinceAdapt = 0;
    if (!on) state.renderScale = 1;
    if (on && state.time >= end) setTime(start);
    state.last = null;
    state.dirty = true;
  }
  function tick(now) {
    if (state.playing) {
      if (state.last !== null) {
        frameIntervals.push(now - state.last);
        if (frameIntervals.length > FRAME_SAMPLES) frameIntervals.shift();
        if (++state.sinceAdapt >= ADAPT_FRAMES) {
          state.sinceAdapt = 0;
          const recent = mean(frameIntervals.slice(-ADAPT_FRAMES));
          if (recent > 1000 / TARGET_FPS && state.renderScale > MIN_RENDER_SCALE) {
            state.renderScale = Math.max(MIN_RENDER_SCALE, state.renderScale * ADAPT_STEP);
            state.lowestScale = Math.min(state.lowestScale, state.renderScale);
          }
        }
        let t = state.time + ((now - state.last) / 1000) * state.speed;
        if (t >= end) {
          if ($("loop").checked) t = start + ((t - start) % Math.max(end - start, 1e-12));
          else {
            t = end;
            state.playing = false;
          }
        }
        setTime(t);
      }
      state.last = now;
    }
    if (state.dirty) draw();
    requestAnimationFrame(tick);
  }

  // ---- Input ---------------------------------------------------------------------------
  $("play").addEventListener("click", () => play(!state.playing));
  $("back").addEventListener("click", () => step(-1));
  $("forward").addEventListener("click", () => step(1));
  scrub.addEventListener("input", () => {
    state.playing = false;
    setTime(scrub.value);
  });
  $("speed").addEventListener("change", (e) => (state.speed = Number(e.target.value)));
  $("solo").addEventListener("change", () => (state.dirty = true));
  function timeFromPlot(e, left, right) {
    const r = e.currentTarget.getBoundingClientRect();
    const f = (e.clientX - r.left - left) / Math.max(r.width - left - right, 1);
    state.playing = false;
    setTime(start + Math.min(1, Math.max(0, f)) * (end - start));
  }
  for (const [c, left, right] of [[energyCanvas, PLOT.left, PLOT.right], [eventsCanvas, 0, 0]]) {
    c.addEventListener("pointerdown", (e) => {
      timeFromPlot(e, left, right);
      c.setPointerCapture(e.pointerId);
    });
    c.addEventListener("pointermove", (e) => {
      if (e.buttons) timeFromPlot(e, left, right);
    });
  }
  let drag = null;
  canvas.addEventListener("contextmenu", (e) => e.preventDefault());
  canvas.addEventListener("pointerdown", (e) => {
    drag = { x: e.clientX, y: e.clientY, moved: 0, pan: e.button === 2 || e.shiftKey };
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x;
    const dy = e.clientY - drag.y;
    drag.moved += Math.abs(dx) + Math.abs(dy);
    drag.x = e.clientX;
    drag.y = e.clientY;
    if (drag.pan) {
      // Move the target in the view plane, one pixel's worth of distance per pixel.
      const perPx = (2 * camera.distance * Math.tan(FOV / 2)) / Math.max(canvas.clientHeight, 1);
      const forward = norm(sub(camera.target, eye()));
      const right = norm(cross(forward, up));
      const upward = cross(right, forward);
      camera.target = add(camera.target, add(scale(right, -dx * perPx), scale(upward, dy * perPx)));
    } else {
      camera.yaw -= dx * ORBIT_PER_PX;
      camera.pitch = Math.min(MAX_PITCH, Math.max(-MAX_PITCH, camera.pitch + dy * ORBIT_PER_PX));
    }
    state.dirty = true;
  });
  canvas.addEventListener("pointerup", (e) => {
    if (drag && drag.moved < CLICK_PX) {
      const r = canvas.getBoundingClientRect();
      const ratio = canvas.width / Math.max(r.width, 1);
      select(pickAt((e.clientX - r.left) * ratio, (e.clientY - r.top) * ratio));
    }
    drag = null;
  });
  canvas.addEventListener(
    "wheel",
    (e) => {
      e.preventDefault();
      camera.distance *= Math.exp(e.deltaY * ZOOM_PER_WHEEL);
      state.dirty = true;
    },
    { passive: false },
  );
  window.addEventListener("keydown", (e) => {
    if (e.target instanceof HTMLSelectElement) return;
    const keys = {
      " ": () => play(!state.playing),
      ArrowLeft: () => step(-1),
      ArrowRight: () => step(1),
      Home: () => setTime(start),
      End: () => setTime(end),
      n: () => jumpToImpact(1),
      o: () => {
        $("solo").checked = !$("solo").checked;
        state.dirty = true;
      },
      p: () => jumpToImpact(-1),
      f: () => {
        frameAll();
        state.dirty = true;
      },
    };
    const act = keys[e.key] || keys[e.key.toLowerCase()];
    if (act) {
      e.preventDefault();
      act();
    }
  });
  window.addEventListener("resize", () => (state.dirty = true));

  // ---- The programming interface -------------------------------------------------------
  const mean = (a) => (a.length ? a.reduce((x, y) => x + y, 0) / a.length : NaN);
  const percentile = (a, p) => {
    const s = [...a].sort((x, y) => x - y);
    return s.length ? s[Math.min(s.length - 1, Math.floor(p * s.length))] : NaN;
  };
  Object.assign(api, {
    header,
    start,
    end,
    frames: F,
    /** Time now (s). */
    time: () => state.time,
    /** Moves the time cursor to `t` (s) and draws at once. */
    setTime(t) {
      state.playing = false;
      setTime(t);
      draw();
    },
    /** Selects body `i` (-1: none) and draws. */
    select(i) {
      select(i);
      draw();
    },
    selected: () => state.selected,
    /** Draws only the selected body (`true`) or every body, and draws. */
    solo(on) {
      $("solo").checked = Boolean(on);
      draw();
    },
    /** Body `i`'s position and rotation (x, y, z, w) as drawn at time `t`. */
    pose: (i, t) => poseAt(i, t).map((a) => Array.from(a)),
    /** The body drawn at CSS pixel (x, y) of the canvas, or -1. */
    pick(x, y) {
      const r = canvas.getBoundingClientRect();
      const ratio = canvas.width / Math.max(r.width, 1);
      return pickAt(x * ratio, y * ratio);
    },
    /** World to clip coordinates (column-major 4×4), the camera's target (world) and the
     * canvas's box in CSS pixels. */
    view: () => {
      const r = canvas.getBoundingClientRect();
      return {
        matrix: Array.from(viewProjection()),
        target: camera.target.slice(),
        left: r.left,
        top: r.top,
        width: r.width,
        height: r.height,
      };
    },
    play: (speed) => {
      if (speed) state.speed = speed;
      play(true);
    },
    pause: () => play(false),
    /** Frames the scene again (the first view) and draws. */
    frameAll() {
      frameAll();
      draw();
    },
    playing: () => state.playing,
    /** Frame intervals (ms, from requestAnimationFrame's timestamps while playing) and
     * draw times (ms of script per drawn frame), as count, mean and 95th percentile. */
    frameStats: () => ({
      intervals: frameIntervals.length,
      intervalMean: mean(frameIntervals),
      intervalP95: percentile(frameIntervals, 0.95),
      drawMean: mean(drawTimes),
      drawP95: percentile(drawTimes, 0.95),
      lowestRenderScale: state.lowestScale,
    }),
    resetFrameStats: () => {
      frameIntervals.length = 0;
      drawTimes.length = 0;
      state.lowestScale = state.renderScale;
    },
  });

  // ---- Start ---------------------------------------------------------------------------
  frameAll();
  const hash = new URLSearchParams(location.hash.slice(1));
  if (hash.has("t")) setTime(hash.get("t"));
  if (hash.has("body")) select(bodies.findIndex((b) => b.name === hash.get("body")));
  draw();
  api.ready = true;
  requestAnimationFrame(tick);
})();
