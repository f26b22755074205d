// The replay page of `impulse run --html` (crates/impulse-cli/src/html.rs writes it).
//
// Plain JavaScript and WebGL 2, no library and no network: the run is read from the page's
// JSON header (#impulse-header) and its base64 data block (#impulse-data), whose layout
// html.rs documents. Times are seconds, lengths metres, energies joules (the scene's SI
// units). `window.impulseViewer` is the page's programming interface (the browser test and
// a user's console use it); the URL's hash (#t=1.5&body=name) sets the time and the selected
// body when the page opens.
//
// The script is four files, joined in this order inside one function by html.rs (one scope,
// strict mode): data.js (constants, the run, vector helpers, poses at a time), render.js
// (WebGL, the camera, drawing and picking), panels.js (the body list, the information, the
// energy plot and the time line's marks) and controls.js (playback, input, the programming
// interface, the start).
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
  /** The first view takes in where the moving bodies go unless that grows the framed box
   * past this many times its size at the start. */
  const FRAME_GROWTH = 3;
  /** Most frames the first view looks at (evenly spaced over the run). */
  const FRAME_SAMPLES_FRAMED = 200;
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
  // The sections the header describes must fill the block exactly (checked before reading).
  {
    const B = header.bodies.length;
    const F = header.frames;
    const words =
      header.meshes.reduce((n, m) => n + 6 * m.vertices + m.indices, 0) + F + 9 * F * B + 2 * F + 7 * header.events;
    if (4 * words !== bytes.length) {
      fail(`The data block holds ${bytes.length} bytes; its header accounts for ${4 * words}.`);
    }
  }
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

