// WebGL, the camera, drawing and picking (a part of the replay page's script: see data.js).
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
  /** Frames the scene: the bodies that move, where they go during the run (or, failing that,
   * where they start and end), and the fixed bodies no larger than FIXED_FRAMED times their
   * extent (a table, not a 100 m floor); every body when none moves. A run whose bodies spread
   * past FRAME_GROWTH times their first extent (a ball rolling off the table) is framed as it
   * starts, so the rest does not shrink to a dot. */
  function frameAll() {
    // The world box of the listed bodies' meshes as they start (each mesh's own box turned
    // by the body's rotation: its eight corners).
    const box = (list, frame = 0) => {
      const lo = [Infinity, Infinity, Infinity];
      const hi = [-Infinity, -Infinity, -Infinity];
      for (const b of list) {
        const [mlo, mhi] = meshBoxes[bodies[b].mesh];
        // A body drawn with no triangles (a massless link) has no box.
        if (!(mlo[0] <= mhi[0])) continue;
        const i = (frame * B + b) * 7;
        const p = poses.subarray(i, i + 3);
        const q = poses.subarray(i + 3, i + 7);
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
      // Where the moving bodies go (sampled frames: a swinging arm, dominos that fall), else
      // where they start and end, unless that spreads the box past FRAME_GROWTH times its
      // size at the start (a ball rolling off the table).
      const extent = Math.hypot(...sub(hi, lo));
      const union = (frames) => {
        const u = [lo.slice(), hi.slice()];
        for (const k of frames) {
          const [flo, fhi] = box(moving, k);
          for (let c = 0; c < 3; c++) {
            u[0][c] = Math.min(u[0][c], flo[c]);
            u[1][c] = Math.max(u[1][c], fhi[c]);
          }
        }
        return u;
      };
      const every = Math.max(1, Math.ceil(F / FRAME_SAMPLES_FRAMED));
      const sampled = Array.from({ length: Math.ceil(F / every) }, (_, j) => j * every).concat([F - 1]);
      const [ulo, uhi] = [union(sampled), union([F - 1])].find(
        ([a, b]) => Math.hypot(...sub(b, a)) <= FRAME_GROWTH * extent,
      ) || [lo, hi];
      const grown = Math.hypot(...sub(uhi, ulo));
      const framed = all.filter((i) => bodies[i].kind !== "fixed" || 2 * bodies[i].radius <= FIXED_FRAMED * grown);
      [lo, hi] = box(framed);
      [lo, hi] = [lo.map((x, c) => Math.min(x, ulo[c])), hi.map((x, c) => Math.max(x, uhi[c]))];
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
  const state = {
    time: start,
    playing: false,
    speed: 1,
    selected: -1,
    last: null,
    dirty: true,
    renderScale: 1,
    lowestScale: 1,
    sinceAdapt: 0,
    scrubbing: false,
  };
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
      if (pickBuffer) {
        pickBuffer.attachments.forEach((r) => gl.deleteRenderbuffer(r));
        gl.deleteFramebuffer(pickBuffer.framebuffer);
        pickBuffer = null;
      }
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
      const framebuffer = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.RENDERBUFFER, colour);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depth);
      pickBuffer = { framebuffer, attachments: [colour, depth] };
    }
    beginPass(pickBuffer.framebuffer, [0, 0, 0]);
    drawBodies(viewProjection(), true);
    const px = new Uint8Array(4);
    gl.readPixels(Math.floor(x), canvas.height - 1 - Math.floor(y), 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    return px[0] + (px[1] << 8) + (px[2] << 16) - 1;
  }

