// The body list, the information, the energy plot and the time line's marks (a part of the replay page's script: see data.js).
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
    if (!state.scrubbing) scrub.value = state.time;
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
  for (let k = 0; k < E; k++) {
    const j = eventNumbers[5 * k + 4];
    if (Number.isFinite(j)) biggest = Math.max(biggest, j);
  }
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
      const j = eventNumbers[5 * k + 4];
      const rel = biggest > 0 && Number.isFinite(j) ? Math.log10(Math.max(j / biggest, 1e-4)) / 4 + 1 : 0;
      const px = Math.round(x(eventNumbers[5 * k])) + 0.5;
      g.moveTo(px, h);
      g.lineTo(px, h - Math.max(3, rel * h));
    }
    g.stroke();
  }

