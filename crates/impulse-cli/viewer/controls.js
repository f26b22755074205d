// Playback, input, the programming interface and the start (a part of the replay page's script: see data.js).
  // ---- Playback ------------------------------------------------------------------------
  /** Moves the time cursor to `t` (s), kept in the run; a time that is not a number is
   * ignored. */
  function setTime(t) {
    const x = Number(t);
    if (!Number.isFinite(x)) return;
    state.time = Math.min(end, Math.max(start, x));
    state.dirty = true;
  }
  /** Stops playback: the picture is drawn at full resolution again. */
  function stop() {
    state.playing = false;
    state.renderScale = 1;
    state.dirty = true;
  }
  /** To the next frame after the cursor, or the last frame before it (frames whose times are
   * equal in f32 are passed over). */
  function step(direction) {
    stop();
    let k = frameAt(state.time)[0];
    if (direction > 0) {
      while (k < F - 1 && times[k] <= state.time) k++;
    } else {
      while (k > 0 && times[k] >= state.time) k--;
    }
    setTime(times[k]);
  }
  function jumpToImpact(direction) {
    if (E === 0) return;
    stop();
    const k = firstEventAfter(state.time);
    if (direction > 0) {
      let j = k;
      while (j < E && eventNumbers[5 * j] <= state.time) j++;
      if (j < E) setTime(eventNumbers[5 * j]);
    } else if (k > 0) setTime(eventNumbers[5 * (k - 1)]);
  }
  function play(on) {
    if (!on) stop();
    state.playing = on;
    state.sinceAdapt = 0;
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
            stop();
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
  scrub.addEventListener("pointerdown", () => (state.scrubbing = true));
  window.addEventListener("pointerup", () => (state.scrubbing = false));
  scrub.addEventListener("input", () => {
    stop();
    setTime(scrub.value);
  });
  $("speed").addEventListener("change", (e) => (state.speed = Number(e.target.value)));
  $("solo").addEventListener("change", () => (state.dirty = true));
  function timeFromPlot(e, left, right) {
    const r = e.currentTarget.getBoundingClientRect();
    const f = (e.clientX - r.left - left) / Math.max(r.width - left - right, 1);
    stop();
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
      // deltaMode 1 counts lines, 2 pages (Firefox sends lines): in pixels, about 16 and 800.
      const pixels = e.deltaY * (e.deltaMode === 1 ? 16 : e.deltaMode === 2 ? 800 : 1);
      camera.distance *= Math.exp(pixels * ZOOM_PER_WHEEL);
      state.dirty = true;
    },
    { passive: false },
  );
  window.addEventListener("keydown", (e) => {
    if (e.target instanceof HTMLSelectElement) return;
    // Leave the browser's own shortcuts (Ctrl+F, Ctrl+P, …) alone.
    if (e.ctrlKey || e.metaKey || e.altKey) return;
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
      stop();
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
