// proxform's report page: tables, figures and a 3-D replay drawn from the data inlined in the
// page (no file fetched). window.proxform is the page's API (the browser test uses it).
"use strict";
(function () {
  const D = JSON.parse(document.getElementById("data").textContent);
  const S = D.summary;
  const SC = D.scenario || null;
  const AX = D.axes;
  const $ = (id) => document.getElementById(id);
  const el = (tag, text, cls) => {
    const e = document.createElement(tag);
    if (text !== undefined) e.textContent = text;
    if (cls) e.className = cls;
    return e;
  };
  // A number as a figure shows it: 4 significant digits, no trailing zeros.
  const fmt = (v) => {
    if (v === null || v === undefined || !isFinite(v)) return "–";
    if (v === 0) return "0";
    const a = Math.abs(v);
    if (a >= 1e5 || a < 1e-3) return v.toExponential(2);
    if (a >= 1000) return v.toFixed(0);
    const s = v.toPrecision(4);
    return s.includes(".") ? s.replace(/\.?0+$/, "") : s;
  };
  const allowable = AX.map((a) => (S.allowable_error ? S.allowable_error[a.key] : null));

  // ---- header ----
  $("name").textContent = D.name;
  const pass = S.pass_fraction >= 1;
  $("verdict").textContent = pass ? "PASS" : "FAIL (" + fmt(100 * S.pass_fraction) + " % of runs passed)";
  $("verdict").className = pass ? "pass" : "fail";
  $("about").textContent = S.uavs + " UAVs, " + S.runs + " run(s) from seed " + S.seed + " · " + D.version;
  const cond = $("conditions");
  const conditions = SC ? SC.conditions.slice() : [];
  conditions.push(
    "allowable errors " + AX.map((a, k) => a.label.split(" ")[0] + " " + fmt(allowable[k])).join(", ") +
      " (m and °); safety distance " + fmt(S.safety_distance_m) + " m"
  );
  if (!SC) conditions.push("(no scenario.toml in the folder: no planned path, links or faults shown)");
  for (const c of conditions) cond.appendChild(el("li", c));
  $("command").textContent = D.command || "(not recorded)";

  // ---- summary table ----
  const sum = $("summary");
  const row = (cells, head) => {
    const tr = el("tr");
    for (const c of cells) {
      const td = el(head ? "th" : "td", typeof c === "object" && c !== null ? c.text : c);
      if (c && c.over) td.className = "over";
      tr.appendChild(td);
    }
    return tr;
  };
  sum.appendChild(row(["error", "worst", "p99", "median", "RMS", "allowable"], true));
  AX.forEach((a, k) => {
    const w = S.worst_abs_error[a.key];
    sum.appendChild(row([a.label, { text: fmt(w), over: w > allowable[k] }, fmt(S.p99_abs_error[a.key]),
      fmt(S.median_abs_error[a.key]), fmt(S.rms_error[a.key]), fmt(allowable[k])]));
  });
  const facts = [
    ["runs passed", fmt(100 * S.pass_fraction) + " % of " + S.runs],
    ["minimum separation", fmt(S.min_separation_m) + " m (safety " + fmt(S.safety_distance_m) + " m)"],
    ["runs with a close pair", String(S.unsafe_runs)],
    ["runs off the planned path", String(S.off_path_runs)],
    ["adjustments per UAV-minute", fmt(S.adjustments_per_uav_minute)],
  ];
  for (const [k, v] of facts) {
    const tr = row([k, v]);
    tr.lastChild.colSpan = 5;
    sum.appendChild(tr);
  }

  // ---- per-UAV table ----
  const ut = $("uavs");
  ut.appendChild(row(["UAV"].concat(AX.map((a) => a.label), ["adjust/run", "runs passed"]), true));
  if (SC) {
    const tr = row(["UAV " + SC.navigator + " (navigator)"].concat(AX.map(() => "–"), ["–", "–"]));
    tr.dataset.uav = SC.navigator;
    ut.appendChild(tr);
  }
  (S.per_uav || []).forEach((id, i) => {
    const w = S.per_uav_worst[i];
    const cells = ["UAV " + id].concat(AX.map((a, k) => ({ text: fmt(w[a.key]), over: w[a.key] > allowable[k] })));
    cells.push(fmt(S.per_uav_adjustments[i]), S.per_uav_runs_passed[i] + " / " + S.per_uav_runs_flown[i]);
    const tr = row(cells);
    tr.dataset.uav = id;
    ut.appendChild(tr);
  });

  // ---- charts ----
  const niceStep = (range, n) => {
    const raw = range / Math.max(n, 1);
    const p = Math.pow(10, Math.floor(Math.log10(raw)));
    const m = raw / p;
    return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
  };
  const ticks = (lo, hi, n) => {
    if (!(hi > lo)) return [lo];
    const st = niceStep(hi - lo, n);
    const out = [];
    for (let v = Math.ceil(lo / st) * st; v <= hi + st * 1e-9; v += st) out.push(Math.abs(v) < st * 1e-9 ? 0 : v);
    return out;
  };
  // A frame of axes on a 2-D canvas: returns the mapping of data to pixels.
  const frame2d = (cv, x0, x1, y0, y1, title, xlabel) => {
    const c = cv.getContext("2d");
    const W = cv.width, H = cv.height, L = 58, R = 12, T = 24, B = 38;
    c.clearRect(0, 0, W, H);
    c.fillStyle = "#fff"; c.fillRect(0, 0, W, H);
    const X = (x) => L + ((x - x0) / (x1 - x0 || 1)) * (W - L - R);
    const Y = (y) => H - B - ((y - y0) / (y1 - y0 || 1)) * (H - T - B);
    c.strokeStyle = "#ddd"; c.fillStyle = "#444"; c.font = "11px sans-serif"; c.lineWidth = 1;
    c.textAlign = "right"; c.textBaseline = "middle";
    for (const v of ticks(y0, y1, 5)) { c.beginPath(); c.moveTo(L, Y(v)); c.lineTo(W - R, Y(v)); c.stroke(); c.fillText(fmt(v), L - 4, Y(v)); }
    c.textAlign = "center"; c.textBaseline = "top";
    for (const v of ticks(x0, x1, 6)) { c.beginPath(); c.moveTo(X(v), T); c.lineTo(X(v), H - B); c.stroke(); c.fillText(fmt(v), X(v), H - B + 4); }
    c.strokeStyle = "#888"; c.strokeRect(L, T, W - L - R, H - T - B);
    c.font = "bold 12px sans-serif"; c.textAlign = "left"; c.fillText(title, L, 5);
    c.font = "11px sans-serif"; c.textAlign = "center"; c.fillText(xlabel, L + (W - L - R) / 2, H - 16);
    return { c, X, Y, L, R, T, B, W, H };
  };
  const hue = (j, n) => "hsl(" + Math.round((360 * j) / Math.max(n, 1)) + ",65%,42%)";

  const series = [];
  const SE = D.series;
  const nav = SC ? SC.navigator : 1;
  if (SE && SE.times.length) {
    const n = SE.uavs.length, T = SE.times;
    AX.forEach((a, k) => {
      const cv = el("canvas"); cv.width = 620; cv.height = 260; cv.setAttribute("aria-label", "error " + a.label);
      $("series").appendChild(cv);
      let m = allowable[k] || 0;
      for (let i = k; i < SE.err.length; i += 6) if (SE.err[i] !== null) m = Math.max(m, Math.abs(SE.err[i]));
      m = (m || 1) * 1.08;
      const f = frame2d(cv, T[0], T[T.length - 1], -m, m, "error " + a.label, "time (s)");
      if (allowable[k]) {
        f.c.fillStyle = "rgba(40,160,80,0.12)";
        f.c.fillRect(f.L, f.Y(allowable[k]), f.W - f.L - f.R, f.Y(-allowable[k]) - f.Y(allowable[k]));
      }
      f.c.lineWidth = 1;
      SE.uavs.forEach((id, j) => {
        if (id === nav) return;
        f.c.strokeStyle = hue(j, n); f.c.beginPath();
        let pen = false;
        T.forEach((t, fi) => {
          const v = SE.err[(fi * n + j) * 6 + k];
          if (v === null) { pen = false; return; }
          if (pen) f.c.lineTo(f.X(t), f.Y(v)); else f.c.moveTo(f.X(t), f.Y(v));
          pen = true;
        });
        f.c.stroke();
      });
      series.push({ cv, f, base: f.c.getImageData(0, 0, cv.width, cv.height) });
    });
    // The legend, outside the plots: each follower's colour.
    const legend = el("p", undefined, "hint");
    SE.uavs.forEach((id, j) => {
      if (id === nav || j >= 40) return;
      const sw = el("span", "■ ");
      sw.style.color = hue(j, n);
      legend.appendChild(sw);
      legend.appendChild(document.createTextNode("UAV " + id + "  "));
    });
    if (n > 40) legend.appendChild(document.createTextNode("… and " + (n - 40) + " more"));
    if (SE.recorded > n) legend.appendChild(document.createTextNode(" (the first " + n + " of the " + SE.recorded + " recorded)"));
    $("series").after(legend);
  }
  const drawCursors = (t) => {
    for (const s of series) {
      s.f.c.putImageData(s.base, 0, 0);
      s.f.c.strokeStyle = "#000"; s.f.c.lineWidth = 1; s.f.c.beginPath();
      s.f.c.moveTo(s.f.X(t), s.f.T); s.f.c.lineTo(s.f.X(t), s.f.H - s.f.B); s.f.c.stroke();
    }
  };

  // Distributions over the runs.
  const HI = D.hist;
  if (HI && HI.runs > 1) {
    const keys = AX.map((a, k) => [a.key, "worst error " + a.label, allowable[k]]);
    keys.push(["min_separation_m", "minimum separation (m)", S.safety_distance_m]);
    for (const [key, label, limit] of keys) {
      const h = HI[key];
      if (!h) continue;
      const cv = el("canvas"); cv.width = 620; cv.height = 240; $("hist").appendChild(cv);
      const x1 = h.lo + h.width * h.counts.length;
      const lo = Math.min(h.lo, limit ?? h.lo), hi = Math.max(x1, limit ?? x1);
      const f = frame2d(cv, lo, hi, 0, Math.max(...h.counts) * 1.1, label + " over " + HI.runs + " runs", label);
      f.c.fillStyle = "rgba(50,90,180,0.7)";
      h.counts.forEach((cnt, b) => {
        const xa = f.X(h.lo + b * h.width), xb = f.X(h.lo + (b + 1) * h.width);
        f.c.fillRect(xa, f.Y(cnt), Math.max(xb - xa - 1, 1), f.Y(0) - f.Y(cnt));
      });
      if (limit !== undefined && limit !== null) {
        f.c.setLineDash([5, 4]); f.c.strokeStyle = "#c0262d"; f.c.beginPath();
        f.c.moveTo(f.X(limit), f.T); f.c.lineTo(f.X(limit), f.H - f.B); f.c.stroke(); f.c.setLineDash([]);
      }
    }
  } else {
    $("hist-section").querySelector(".hint").textContent = "One run: no distribution (fly --runs N for one).";
  }

  // ---- the 3-D replay ----
  const R = D.replay;
  const api = { ready: false };
  window.proxform = api;
  if (!R || !R.times.length) {
    $("replay-section").querySelector("h2").textContent = "Replay: no trajectories in this folder";
    api.ready = true;
    return;
  }
  const n = R.uavs.length, F = R.times.length;
  if (n < S.uavs) {
    $("replay-section").querySelector("h2").textContent =
      "Replay of the first run: the " + n + " UAVs trajectories.csv recorded, of " + S.uavs + " (--trajectory-uavs chooses them)";
  }
  const P = (f, j) => {
    const b = (f * n + j) * 3;
    return R.pos[b] === null ? null : [R.pos[b], R.pos[b + 1], R.pos[b + 2]];
  };
  const scene = $("scene"), labels = $("labels");
  const gl = scene.getContext("webgl", { preserveDrawingBuffer: true, antialias: true });
  const l2 = labels.getContext("2d");
  let prog = null, buf = null, aP = 0, aC = 0, uM = null, uS = null;
  if (gl) {
    const sh = (type, src) => { const s = gl.createShader(type); gl.shaderSource(s, src); gl.compileShader(s); return s; };
    prog = gl.createProgram();
    gl.attachShader(prog, sh(gl.VERTEX_SHADER,
      "attribute vec3 p; attribute vec3 c; uniform mat4 m; uniform float s; varying vec3 v; varying float r;" +
      "void main(){ gl_Position = m * vec4(p, 1.0); gl_PointSize = s; v = c; r = s > 1.5 ? 1.0 : 0.0; }"));
    gl.attachShader(prog, sh(gl.FRAGMENT_SHADER,
      "precision mediump float; varying vec3 v; varying float r;" +
      "void main(){ if (r > 0.5) { vec2 d = gl_PointCoord - 0.5; if (dot(d, d) > 0.25) discard; } gl_FragColor = vec4(v, 1.0); }"));
    gl.linkProgram(prog);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error("the 3-D view's shaders: " + gl.getProgramInfoLog(prog));
    gl.useProgram(prog);
    buf = gl.createBuffer();
    aP = gl.getAttribLocation(prog, "p"); aC = gl.getAttribLocation(prog, "c");
    uM = gl.getUniformLocation(prog, "m"); uS = gl.getUniformLocation(prog, "s");
  }
  // Column-major 4×4 matrices.
  const mul = (a, b) => {
    const o = new Float64Array(16);
    for (let i = 0; i < 4; i++) for (let j = 0; j < 4; j++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += a[k * 4 + j] * b[i * 4 + k];
      o[i * 4 + j] = s;
    }
    return o;
  };
  const perspective = (fovy, aspect, near, far) => {
    const f = 1 / Math.tan(fovy / 2), o = new Float64Array(16);
    o[0] = f / aspect; o[5] = f; o[10] = (far + near) / (near - far); o[11] = -1; o[14] = (2 * far * near) / (near - far);
    return o;
  };
  const lookAt = (e, c, u) => {
    const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    const norm = (a) => { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; };
    const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    const z = norm(sub(e, c)), x = norm(cross(u, z)), y = cross(z, x);
    return Float64Array.from([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0, -dot(x, e), -dot(y, e), -dot(z, e), 1]);
  };
  const centroid = (f) => {
    const c = [0, 0, 0];
    let k = 0;
    for (let j = 0; j < n; j++) { const p = P(f, j); if (p) { c[0] += p[0]; c[1] += p[1]; c[2] += p[2]; k++; } }
    return k ? c.map((v) => v / k) : [0, 0, 0];
  };
  let extent = 1;
  for (const f of [0, Math.floor(F / 2), F - 1]) {
    const c = centroid(f);
    for (let j = 0; j < n; j++) { const p = P(f, j); if (p) extent = Math.max(extent, Math.hypot(p[0] - c[0], p[1] - c[1], p[2] - c[2])); }
  }
  const cam = { az: -2.3, el: 0.45, dist: 3.2 * extent, target: centroid(0) };
  const resetView = () => { cam.az = -2.3; cam.el = 0.45; cam.dist = 3.2 * extent; cam.target = centroid(cur); };
  let cur = 0, playing = false, tSim = R.times[0], speed = 1, last = null;
  const links = SC ? SC.links : [];
  const slot = new Map(R.uavs.map((id, j) => [id, j]));
  const events = SC ? SC.events : [];
  const tEnd = R.times[F - 1], t0 = R.times[0];

  let matrix = null;
  const draw = () => {
    const t = R.times[cur];
    if ($("follow").checked) cam.target = centroid(cur);
    const o = cam.target;
    const eye = [Math.cos(cam.el) * Math.cos(cam.az) * cam.dist, Math.cos(cam.el) * Math.sin(cam.az) * cam.dist, Math.sin(cam.el) * cam.dist];
    matrix = mul(perspective(0.8, scene.width / scene.height, cam.dist * 0.01, cam.dist * 20 + 10 * extent), lookAt(eye, [0, 0, 0], [0, 0, 1]));
    const lines = [], pts = [];
    const seg = (a, b, col) => { lines.push(a[0] - o[0], a[1] - o[1], a[2] - o[2], ...col, b[0] - o[0], b[1] - o[1], b[2] - o[2], ...col); };
    // The ground grid, anchored to the world, below the formation.
    let zmin = Infinity;
    for (let j = 0; j < n; j++) { const p = P(cur, j); if (p) zmin = Math.min(zmin, p[2]); }
    const zg = (isFinite(zmin) ? zmin : o[2]) - 0.4 * extent;
    const sp = Math.pow(10, Math.floor(Math.log10(extent))), K = Math.ceil((2.5 * extent) / sp);
    const gx = Math.round(o[0] / sp) * sp, gy = Math.round(o[1] / sp) * sp, g = [0.82, 0.84, 0.87];
    for (let k = -K; k <= K; k++) {
      seg([gx + k * sp, gy - K * sp, zg], [gx + k * sp, gy + K * sp, zg], g);
      seg([gx - K * sp, gy + k * sp, zg], [gx + K * sp, gy + k * sp, zg], g);
    }
    // The navigator's planned path, dashed.
    if (SC) {
      const pa = SC.path;
      for (let i = 0; i + 1 < pa.length; i += 2) seg(pa[i].slice(1), pa[i + 1].slice(1), [0.35, 0.5, 0.95]);
    }
    // Trails: the last 10 s.
    let f0 = cur;
    while (f0 > 0 && R.times[f0 - 1] >= t - 10) f0--;
    for (let j = 0; j < n; j++) {
      const col = R.uavs[j] === nav ? [0.55, 0.65, 0.95] : [0.6, 0.6, 0.6];
      for (let f = f0; f < cur; f++) { const a = P(f, j), b = P(f + 1, j); if (a && b) seg(a, b, col); }
    }
    // Links to the references.
    for (const [a, b] of links) {
      const ja = slot.get(a), jb = slot.get(b);
      if (ja === undefined || jb === undefined) continue;
      const pa = P(cur, ja), pb = P(cur, jb);
      if (pa && pb) seg(pa, pb, [0.55, 0.55, 0.55]);
    }
    // Close pairs.
    const close = [];
    const safety = S.safety_distance_m || 0;
    if (n <= 400 && safety > 0) {
      for (let i = 0; i < n; i++) {
        const a = P(cur, i); if (!a) continue;
        for (let j = i + 1; j < n; j++) {
          const b = P(cur, j);
          if (b && Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]) < safety) { seg(a, b, [0.9, 0.1, 0.1]); close.push([R.uavs[i], R.uavs[j]]); }
        }
      }
    }
    for (let j = 0; j < n; j++) {
      const p = P(cur, j); if (!p) continue;
      const w = R.within[cur * n + j];
      const col = R.uavs[j] === nav ? [0.15, 0.35, 0.85] : w === "1" ? [0.1, 0.6, 0.25] : w === "0" ? [0.85, 0.15, 0.15] : [0.5, 0.5, 0.5];
      pts.push(p[0] - o[0], p[1] - o[1], p[2] - o[2], ...col);
    }
    if (gl) {
      gl.viewport(0, 0, scene.width, scene.height);
      gl.clearColor(0.969, 0.973, 0.98, 1); gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      gl.enable(gl.DEPTH_TEST);
      gl.uniformMatrix4fv(uM, false, Float32Array.from(matrix));
      gl.bindBuffer(gl.ARRAY_BUFFER, buf);
      const put = (arr, mode, size) => {
        if (!arr.length) return;
        gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(arr), gl.STREAM_DRAW);
        gl.enableVertexAttribArray(aP); gl.vertexAttribPointer(aP, 3, gl.FLOAT, false, 24, 0);
        gl.enableVertexAttribArray(aC); gl.vertexAttribPointer(aC, 3, gl.FLOAT, false, 24, 12);
        gl.uniform1f(uS, size);
        gl.drawArrays(mode, 0, arr.length / 6);
      };
      put(lines, gl.LINES, 1);
      put(pts, gl.POINTS, n > 200 ? 5 : 10);
    }
    // Labels.
    l2.clearRect(0, 0, labels.width, labels.height);
    if ($("ids").checked) {
      l2.font = "11px sans-serif"; l2.fillStyle = "#222";
      for (let j = 0; j < n && n <= 400; j++) {
        const s = project(P(cur, j)); if (s) l2.fillText(String(R.uavs[j]), s[0] + 6, s[1] - 6);
      }
    }
    if (!gl) { l2.fillStyle = "#a00"; l2.fillText("WebGL is not available in this browser: no 3-D view.", 20, 30); }
    $("clock").textContent = "t = " + fmt(t) + " s" + (close.length ? " · close: " + close.map((p) => p.join("–")).join(", ") : "");
    $("scrub").value = String(cur);
    drawTimeline(t);
    drawCursors(t);
  };
  const project = (p) => {
    if (!p || !matrix) return null;
    const o = cam.target, q = [p[0] - o[0], p[1] - o[1], p[2] - o[2], 1];
    const c = [0, 1, 2, 3].map((r) => matrix[r] * q[0] + matrix[4 + r] * q[1] + matrix[8 + r] * q[2] + matrix[12 + r] * q[3]);
    if (c[3] <= 0) return null;
    return [((c[0] / c[3] + 1) / 2) * labels.width, ((1 - c[1] / c[3]) / 2) * labels.height];
  };
  const tl = $("timeline"), tc = tl.getContext("2d");
  const drawTimeline = (t) => {
    const W = tl.width, H = tl.height, X = (v) => 8 + ((v - t0) / (tEnd - t0 || 1)) * (W - 16);
    tc.clearRect(0, 0, W, H);
    tc.fillStyle = "#e4e6ea"; tc.fillRect(8, H / 2 - 3, W - 16, 6);
    tc.fillStyle = "#e07b00";
    for (const e of events) tc.fillRect(X(e.t) - 1.5, 2, 3, H - 4);
    tc.fillStyle = "#222"; tc.beginPath(); tc.arc(X(t), H / 2, 6, 0, 2 * Math.PI); tc.fill();
  };
  const evl = $("events");
  for (const e of events) evl.appendChild(el("li", "t = " + fmt(e.t) + " s: " + (e.uav ? "UAV " + e.uav + " " : "") + e.what));

  // ---- interaction ----
  const frameAt = (t) => {
    let lo = 0, hi = F - 1;
    while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (R.times[mid] <= t + 1e-9) lo = mid; else hi = mid - 1; }
    return lo;
  };
  const seekFrame = (f) => { cur = Math.max(0, Math.min(F - 1, f)); tSim = R.times[cur]; draw(); };
  const setPlaying = (p) => { playing = p; $("play").textContent = p ? "Pause" : "Play"; last = null; if (p) requestAnimationFrame(tick); };
  const tick = (now) => {
    if (!playing) return;
    if (last !== null) {
      tSim += ((now - last) / 1000) * speed;
      if (tSim >= tEnd) { tSim = tEnd; setPlaying(false); }
      const f = frameAt(tSim);
      if (f !== cur) { cur = f; draw(); }
    }
    last = now;
    if (playing) requestAnimationFrame(tick);
  };
  $("scrub").max = String(F - 1);
  $("scrub").addEventListener("input", () => seekFrame(parseInt($("scrub").value, 10)));
  $("play").addEventListener("click", () => { if (cur >= F - 1) seekFrame(0); setPlaying(!playing); });
  $("speed").addEventListener("change", () => { speed = parseFloat($("speed").value); });
  $("follow").addEventListener("change", draw);
  $("ids").addEventListener("change", draw);
  $("reset").addEventListener("click", () => { resetView(); draw(); });
  tl.addEventListener("click", (e) => {
    const r = tl.getBoundingClientRect();
    seekFrame(frameAt(t0 + ((e.clientX - r.left) / r.width) * (tEnd - t0)));
  });
  let drag = null;
  scene.addEventListener("mousedown", (e) => { drag = [e.clientX, e.clientY]; });
  window.addEventListener("mouseup", () => { drag = null; });
  window.addEventListener("mousemove", (e) => {
    if (!drag) return;
    cam.az -= (e.clientX - drag[0]) * 0.008;
    cam.el = Math.max(-1.5, Math.min(1.5, cam.el + (e.clientY - drag[1]) * 0.008));
    drag = [e.clientX, e.clientY];
    draw();
  });
  scene.addEventListener("wheel", (e) => { e.preventDefault(); cam.dist *= Math.exp(e.deltaY * 0.001); draw(); }, { passive: false });

  // ---- the page's API ----
  api.uavs = () => R.uavs.slice();
  api.times = () => R.times.slice();
  api.seek = (t) => { seekFrame(frameAt(t)); return R.times[cur]; };
  api.time = () => R.times[cur];
  api.positions = () => {
    const out = {};
    for (let j = 0; j < n; j++) { const p = P(cur, j); if (p) out[R.uavs[j]] = p; }
    return out;
  };
  api.play = () => setPlaying(true);
  api.pause = () => setPlaying(false);
  api.playing = () => playing;
  // Pixels of the 3-D view that differ from its background.
  api.drawnPixels = () => {
    if (!gl) return 0;
    const px = new Uint8Array(scene.width * scene.height * 4);
    gl.readPixels(0, 0, scene.width, scene.height, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let k = 0;
    for (let i = 0; i < px.length; i += 4) if (Math.abs(px[i] - 247) + Math.abs(px[i + 1] - 248) + Math.abs(px[i + 2] - 250) > 12) k++;
    return k;
  };
  api.webgl = !!gl;
  draw();
  api.ready = true;
})();
