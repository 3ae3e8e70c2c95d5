// The projector page: the arena drawn straight in projector pixels, every vertex warped here through the floor →
// projector homography H (a homography maps lines to lines, so segments and polygons stay exact; a circle maps to
// a conic, drawn exactly as the ellipse it is: one arc under that ellipse's affine transform); the density is
// resampled through H every STEP projector px (bilinear, only when it changed) and drawn smoothed up, so the
// compositor warps nothing (a perspective-transformed layer cost it ≈ 10 ms a frame). Fed by the console (a
// long poll of /projector/next, one request at a time: the config — H, the projector's size, the layers,
// brightness and blackout — and the newest Frame's picture, swarmdeck.console.projector.message). Messages are
// only stored; one requestAnimationFrame draws the newest, so a slow page skips frames and never lags. If drawing
// takes longer than BUDGET_MS the page drops layers (DROP_ORDER) until it fits, and takes them back when there is
// room. Without H it writes "no homography — run swarmdeck calibrate projector" across the screen.
// window.swarmdeckProjector tells tests and the bench what was drawn and when.
"use strict";
(() => {
  const floor = document.getElementById("floor");
  const warp = document.getElementById("warp");
  const heatCanvas = document.createElement("canvas");  // the density resampled in projector px / STEP (offscreen)
  const hctx = heatCanvas.getContext("2d");
  const notice = document.getElementById("notice");
  const ctx = floor.getContext("2d", { alpha: false });  // opaque: black where nothing is drawn
  const nctx = notice.getContext("2d");
  const BUDGET_MS = 20;           // a frame's drawing budget (30 frames/s with room for the browser)
  const DROP_ORDER = ["safety", "halos", "graph", "centroids", "annotations", "cells", "goals"];
  // Sizes on the floor, m (the lines' widths are scaled to projector px at the arena's centre).
  const MARGIN_M = 0.3;           // how far round the arena the canvas reaches (halos, look-ahead discs), m
  const LINE_M = 0.01, GRAPH_M = 0.0075, HALO_LINE_M = 0.015, CENTROID_M = 0.02, GOAL_M = 0.03, ESTOP_M = 0.06;
  const st = (window.swarmdeckProjector = {
    frames: 0, seq: null, tick: null, config: null, drawn: [], latency: [], drawMs: [], dropped: [],
    message: "", connected: false, lastDraw: null, layersDrawn: [], annotationsDrawn: 0,
    // floor m → projector px, as this page computes it (tests compare it with the homography)
    project: (x, y) => { P(x, y); return [px - 0.5 + offL, py - 0.5 + offT]; },
  });
  let config = null, pending = null, last = null, ema = 0;
  // G = C·H: floor m → canvas px (pixel edges; projector pixel centre i is at canvas i + 0.5 − the canvas's
  // offset on the screen); Gi its inverse
  let g0 = 1, g1 = 0, g2 = 0, g3 = 0, g4 = 1, g5 = 0, g6 = 0, g7 = 0, g8 = 1;
  const Gi = new Float64Array(9);
  let offL = 0, offT = 0;        // the canvas's place on the screen, projector px
  let S = 1;                      // projector px per floor m at the arena's centre (line widths, text)
  let px = 0, py = 0;             // P's answer (no allocation per vertex)
  function P(x, y) {
    const w = g6 * x + g7 * y + g8;
    px = (g0 * x + g1 * y + g2) / w; py = (g3 * x + g4 * y + g5) / w;
  }
  const STEP = 4;                 // the density is resampled every STEP projector px, then drawn smoothed up
  let heatImg = null, heatRgb = null, heatKey = "", heatSrc = null;
  let heatIdx = null, heatFx = null, heatFy = null;

  function fitNotice() {
    notice.width = window.innerWidth; notice.height = window.innerHeight;
  }
  function say(text) {  // full-screen text, not warped (there may be no homography)
    fitNotice();
    nctx.clearRect(0, 0, notice.width, notice.height);
    st.message = text;
    if (!text) return;
    nctx.fillStyle = "#ffffff";
    nctx.font = `bold ${Math.max(18, Math.round(notice.width / 32))}px system-ui, sans-serif`;
    nctx.textAlign = "center"; nctx.textBaseline = "middle";
    const lines = text.split("\n");
    lines.forEach((line, k) => nctx.fillText(line, notice.width / 2, notice.height / 2 + (k - (lines.length - 1) / 2) * notice.width / 24));
  }

  const mul = (A, B) => A.map((r) => [0, 1, 2].map((j) => r[0] * B[0][j] + r[1] * B[1][j] + r[2] * B[2][j]));
  function inverse(M) {  // 3 × 3, row-major into Gi
    const [a, b, c] = M[0], [d, e, f] = M[1], [g, h, i] = M[2];
    const A = e * i - f * h, B = f * g - d * i, C = d * h - e * g, det = a * A + b * B + c * C;
    const v = [A, c * h - b * i, b * f - c * e, B, a * i - c * g, c * d - a * f, C, b * g - a * h, a * e - b * d];
    for (let k = 0; k < 9; k += 1) Gi[k] = v[k] / det;
  }

  function applyConfig(c) {
    config = c;
    st.config = c;
    const dpr = window.devicePixelRatio || 1, screenW = Math.round(window.innerWidth * dpr);
    const screenH = Math.round(window.innerHeight * dpr);
    floor.width = screenW; floor.height = screenH;
    warp.style.opacity = String(c.settings.opacity);
    if (!c.H) {
      warp.style.display = "none";
      say("no homography — run swarmdeck calibrate projector");
      return;
    }
    // The canvas covers only the arena (and MARGIN_M round it) on the screen: less for the browser to composite.
    const [x0, x1, y0, y1] = c.bounds, M = MARGIN_M;
    const corners = [[x0 - M, y0 - M], [x1 + M, y0 - M], [x1 + M, y1 + M], [x0 - M, y1 + M]];
    const w = corners.map(([x, y]) => c.H[2][0] * x + c.H[2][1] * y + c.H[2][2]);
    let left = 0, top = 0, right = screenW, bottom = screenH;
    if (w.every((v) => v > 0)) {
      const cxs = corners.map(([x, y], k) => (c.H[0][0] * x + c.H[0][1] * y + c.H[0][2]) / w[k] + 0.5);
      const cys = corners.map(([x, y], k) => (c.H[1][0] * x + c.H[1][1] * y + c.H[1][2]) / w[k] + 0.5);
      left = Math.max(0, Math.floor(Math.min(...cxs))); right = Math.min(screenW, Math.ceil(Math.max(...cxs)));
      top = Math.max(0, Math.floor(Math.min(...cys))); bottom = Math.min(screenH, Math.ceil(Math.max(...cys)));
      if (right - left < 2 || bottom - top < 2) { left = 0; top = 0; right = screenW; bottom = screenH; }
    }
    offL = left; offT = top;
    floor.width = right - left; floor.height = bottom - top;
    floor.style.left = left / dpr + "px"; floor.style.top = top / dpr + "px";
    floor.style.width = floor.width / dpr + "px"; floor.style.height = floor.height / dpr + "px";
    const G = mul([[1, 0, 0.5 - left], [0, 1, 0.5 - top], [0, 0, 1]], c.H);
    [[g0, g1, g2], [g3, g4, g5], [g6, g7, g8]] = G;
    inverse(G);
    const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2, e = 1e-3;
    P(cx, cy); const ax = px, ay = py;
    P(cx + e, cy); const bx = px - ax, by = py - ay;
    P(cx, cy + e); const dx = px - ax, dy = py - ay;
    S = Math.sqrt(Math.abs(bx * dy - by * dx)) / e;
    heatKey = "";  // the density's lookup is rebuilt for the new homography
    warp.style.display = c.settings.blackout ? "none" : "block";
    say("");
    if (last) pending = last;
  }

  // The density's lookup: for every STEP × STEP cell of the canvas, the heat map's pixel (top-left of the four
  // it blends, −1 outside the arena) and the bilinear weights, through Gi. Built once per homography and size.
  function heatLookup(w, h, bounds) {
    const W = Math.ceil(floor.width / STEP), Hh = Math.ceil(floor.height / STEP), n = W * Hh;
    const [x0, x1, y0, y1] = bounds, sx = w / (x1 - x0), sy = h / (y1 - y0);
    heatIdx = new Int32Array(n); heatFx = new Float32Array(n); heatFy = new Float32Array(n);
    for (let j = 0, k = 0; j < Hh; j += 1) {
      for (let i = 0; i < W; i += 1, k += 1) {
        const X = (i + 0.5) * STEP, Y = (j + 0.5) * STEP, q = Gi[6] * X + Gi[7] * Y + Gi[8];
        const x = (Gi[0] * X + Gi[1] * Y + Gi[2]) / q, y = (Gi[3] * X + Gi[4] * Y + Gi[5]) / q;
        if (!(x >= x0 && x <= x1 && y >= y0 && y <= y1)) { heatIdx[k] = -1; continue; }
        const u = Math.min(Math.max((x - x0) * sx - 0.5, 0), w - 1), v = Math.min(Math.max((y1 - y) * sy - 0.5, 0), h - 1);
        const iu = Math.max(0, Math.min(Math.floor(u), w - 2)), iv = Math.max(0, Math.min(Math.floor(v), h - 2));
        heatIdx[k] = iv * w + iu; heatFx[k] = u - iu; heatFy[k] = v - iv;
      }
    }
    heatCanvas.width = W; heatCanvas.height = Hh;
    heatImg = hctx.createImageData(W, Hh);
    heatSrc = new Uint8Array(3 * w * h);
    heatRgb = null;
  }

  function heatPixels(d) {  // the density's new pixels through the lookup (bilinear), into the offscreen canvas
    const raw = atob(d.rgb), src = heatSrc, out = heatImg.data, n = heatIdx.length, row = 3 * d.w;
    for (let j = 0; j < src.length; j += 1) src[j] = raw.charCodeAt(j);
    for (let k = 0, o = 0; k < n; k += 1, o += 4) {
      const i = heatIdx[k];
      if (i < 0) { out[o + 3] = 0; continue; }
      const a = heatFx[k], b = heatFy[k], s = 3 * i;
      const w00 = (1 - a) * (1 - b), w10 = a * (1 - b), w01 = (1 - a) * b, w11 = a * b;
      out[o] = w00 * src[s] + w10 * src[s + 3] + w01 * src[s + row] + w11 * src[s + row + 3];
      out[o + 1] = w00 * src[s + 1] + w10 * src[s + 4] + w01 * src[s + row + 1] + w11 * src[s + row + 4];
      out[o + 2] = w00 * src[s + 2] + w10 * src[s + 5] + w01 * src[s + row + 2] + w11 * src[s + row + 5];
      out[o + 3] = 255;
    }
    hctx.putImageData(heatImg, 0, 0);
  }

  function on(layer) {
    return config && config.settings[layer] && !st.dropped.includes(layer);
  }

  // A circle on the floor (centre x, y, radius r m) added to the current path as the ellipse H makes of it: the
  // image conic C' = Gi^T C Gi of the circle's C, its centre and the affine map of the unit circle onto it
  // (Cholesky), one arc under that transform. Returns false (nothing added) if the image is not an ellipse.
  function ellipse(x, y, r) {
    const u0 = Gi[0] - x * Gi[6], v0 = Gi[3] - y * Gi[6], w0 = Gi[6];
    const u1 = Gi[1] - x * Gi[7], v1 = Gi[4] - y * Gi[7], w1 = Gi[7];
    const u2 = Gi[2] - x * Gi[8], v2 = Gi[5] - y * Gi[8], w2 = Gi[8], rr = r * r;
    const a = u0 * u0 + v0 * v0 - rr * w0 * w0, b = u0 * u1 + v0 * v1 - rr * w0 * w1;
    const d = u1 * u1 + v1 * v1 - rr * w1 * w1, p = u0 * u2 + v0 * v2 - rr * w0 * w2;
    const q = u1 * u2 + v1 * v2 - rr * w1 * w2, c = u2 * u2 + v2 * v2 - rr * w2 * w2;
    const det = a * d - b * b;
    if (!(det > 0)) return false;
    const ex = (b * q - d * p) / det, ey = (b * p - a * q) / det, k = -(p * ex + q * ey) - c;
    if (!(k / a > 0)) return false;
    const l0 = Math.sqrt(a / k), l1 = b / k / l0, l2 = Math.sqrt(d / k - l1 * l1);
    if (!(l2 > 0)) return false;
    ctx.setTransform(1 / l0, 0, -l1 / (l0 * l2), 1 / l2, ex, ey);
    ctx.moveTo(1, 0);
    ctx.arc(0, 0, 1, 0, 2 * Math.PI);
    return true;
  }

  function quad(x0, x1, y0, y1) {  // a floor rectangle's outline, exact
    P(x0, y0); ctx.moveTo(px, py); P(x1, y0); ctx.lineTo(px, py);
    P(x1, y1); ctx.lineTo(px, py); P(x0, y1); ctx.lineTo(px, py); ctx.closePath();
  }

  function draw(m) {
    const t0 = performance.now();
    const P_ = m.palette;
    const drawnLayers = [];
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = "#000000";
    ctx.fillRect(0, 0, floor.width, floor.height);
    if (config.settings.blackout) { st.layersDrawn = []; return performance.now() - t0; }
    if (m.density && config.settings.density && m.density.w > 1 && m.density.h > 1) {
      const d = m.density, key = `${d.w}x${d.h}:${m.bounds}`;
      if (key !== heatKey) { heatLookup(d.w, d.h, m.bounds); heatKey = key; }
      if (d.rgb !== heatRgb) { heatPixels(d); heatRgb = d.rgb; }  // only when the density changed
      ctx.imageSmoothingEnabled = true;
      ctx.drawImage(heatCanvas, 0, 0, heatCanvas.width * STEP, heatCanvas.height * STEP);
      drawnLayers.push("density");
    }
    if (on("cells") && m.edges.length) {
      ctx.strokeStyle = P_.voronoi; ctx.lineWidth = LINE_M * S;
      ctx.beginPath();
      for (const [[ax, ay], [bx, by]] of m.edges) { P(ax, ay); ctx.moveTo(px, py); P(bx, by); ctx.lineTo(px, py); }
      ctx.stroke();
      drawnLayers.push("cells");
    }
    if (on("centroids") && m.centroids.length) {
      ctx.fillStyle = P_.centroid;
      ctx.beginPath();
      for (const [cx, cy] of m.centroids) quad(cx - CENTROID_M, cx + CENTROID_M, cy - CENTROID_M, cy + CENTROID_M);
      ctx.fill();
      drawnLayers.push("centroids");
    }
    if (on("goals") && m.goals.length) {
      ctx.strokeStyle = "#ffffff"; ctx.lineWidth = LINE_M * S;
      ctx.beginPath();
      for (const [gx, gy] of m.goals) {
        P(gx - GOAL_M, gy + GOAL_M); ctx.moveTo(px, py); P(gx + GOAL_M, gy - GOAL_M); ctx.lineTo(px, py);
        P(gx - GOAL_M, gy - GOAL_M); ctx.moveTo(px, py); P(gx + GOAL_M, gy + GOAL_M); ctx.lineTo(px, py);
      }
      ctx.stroke();
      drawnLayers.push("goals");
    }
    if (on("graph") && m.graph) {  // the communication graph: one segment per linked pair, coloured by traffic
      ctx.lineWidth = GRAPH_M * S;
      const segs = m.graph.segments, colours = m.graph.colours;
      for (let i = 0; i < segs.length; i += 1) {
        const [[ax, ay], [bx, by]] = segs[i];
        ctx.strokeStyle = colours[i];
        ctx.beginPath(); P(ax, ay); ctx.moveTo(px, py); P(bx, by); ctx.lineTo(px, py); ctx.stroke();
      }
      drawnLayers.push("graph");
    }
    if (on("safety") && m.safety) {
      const r = m.safety.radius;
      ctx.strokeStyle = P_.changed; ctx.lineWidth = 0.75 * LINE_M * S;
      ctx.beginPath();
      for (const [x, y] of m.safety.xy) ellipse(x, y, r);
      ctx.setTransform(1, 0, 0, 1, 0, 0);
      ctx.stroke();
      drawnLayers.push("safety");
    }
    if (on("halos") && m.halos) {
      const r = m.halos.radius, xy = m.halos.xy, colour = m.halos.colour;
      ctx.lineWidth = HALO_LINE_M * S;
      m.halos.palette.forEach((c, k) => {  // one path per colour
        ctx.strokeStyle = c;
        ctx.beginPath();
        for (let i = 0; i < xy.length; i += 1) if (colour[i] === k) ellipse(xy[i][0], xy[i][1], r);
        ctx.setTransform(1, 0, 0, 1, 0, 0);
        ctx.stroke();
      });
      drawnLayers.push("halos");
    }
    if (on("annotations") && m.annotations) {
      drawAnnotations(m.annotations);
      st.annotationsDrawn = m.annotations.kinds.length;
      drawnLayers.push("annotations");
    }
    const [x0, x1, y0, y1] = m.bounds;
    ctx.strokeStyle = P_.boundary; ctx.lineWidth = LINE_M * S;
    ctx.beginPath(); quad(x0, x1, y0, y1); ctx.stroke();
    if (m.run_state === "estop") {
      const i = ESTOP_M / 2;
      ctx.strokeStyle = P_.stopped; ctx.lineWidth = ESTOP_M * S;
      ctx.beginPath(); quad(x0 + i, x1 - i, y0 + i, y1 - i); ctx.stroke();
    }
    st.layersDrawn = drawnLayers;
    return performance.now() - t0;
  }

  // What the experiment drew (console.picture.annotations.annotations_json, as the portal's live view draws it):
  // kinds 0 point, 1 polyline, 2 circle, 3 polygon, 4 text; vertices and sizes (radius, line width, text height)
  // in metres, colours given. Text is drawn under the homography's local affine map at its anchor (1 unit = 1 mm).
  function drawAnnotations(a) {
    ctx.save();
    ctx.lineCap = "round"; ctx.lineJoin = "round"; ctx.textAlign = "center"; ctx.textBaseline = "middle";
    const V = a.vertices, O = a.offsets;
    for (let i = 0; i < a.kinds.length; i += 1) {
      const kind = a.kinds[i], size = a.sizes[i], colour = a.colours[i], o = O[i], end = O[i + 1];
      ctx.fillStyle = colour; ctx.strokeStyle = colour;
      ctx.beginPath();
      if (kind === 0 || kind === 2) {
        const ok = ellipse(V[o][0], V[o][1], Math.max(size, 1 / S));
        ctx.setTransform(1, 0, 0, 1, 0, 0);
        if (!ok) continue;
        ctx.lineWidth = Math.max(1, 0.01 * S);
        if (kind === 0 || a.filled[i]) ctx.fill(); else ctx.stroke();
      } else if (kind === 1 || kind === 3) {
        ctx.lineWidth = Math.max(1, size * S);
        for (let k = o; k < end; k += 1) { P(V[k][0], V[k][1]); if (k === o) ctx.moveTo(px, py); else ctx.lineTo(px, py); }
        if (kind === 3) ctx.closePath();
        if (kind === 3 && a.filled[i]) ctx.fill(); else ctx.stroke();
      } else if (kind === 4) {
        const [x, y] = V[o], e = 1e-3;
        P(x, y); const ax = px, ay = py;
        P(x + e, y); const bx = (px - ax) / e, by = (py - ay) / e;
        P(x, y + e); const dx = (px - ax) / e, dy = (py - ay) / e;
        ctx.setTransform(0.001 * bx, 0.001 * by, -0.001 * dx, -0.001 * dy, ax, ay);
        ctx.font = `${Math.max(1, Math.round(size * 1000))}px system-ui, sans-serif`;
        ctx.fillText(a.texts[i], 0, 0);
        ctx.setTransform(1, 0, 0, 1, 0, 0);
      }
    }
    ctx.restore();
  }

  function adapt(ms) {  // degrade by dropping layers, never by lagging
    ema = st.frames < 2 ? ms : 0.8 * ema + 0.2 * ms;
    if (ema > BUDGET_MS) {
      const next = DROP_ORDER.find((l) => !st.dropped.includes(l));
      if (next) { st.dropped.push(next); ema = BUDGET_MS / 2; }
    } else if (ema < BUDGET_MS / 4 && st.dropped.length && st.frames % 60 === 0) {
      st.dropped.pop();
    }
  }

  function tick() {
    if (pending && config) {
      const m = pending;
      pending = null;
      if (config.H) {
        const ms = draw(m);
        adapt(ms);
        const now = performance.timeOrigin + performance.now();
        st.frames += 1; st.seq = m.seq; st.tick = m.tick; st.lastDraw = now;
        st.drawn.push(now); st.latency.push(now - m.stamp); st.drawMs.push(ms);
        if (st.drawn.length > 2000) { st.drawn.shift(); st.latency.shift(); st.drawMs.shift(); }
      }
    }
    requestAnimationFrame(tick);
  }

  // Long poll: one request at a time, each answered with the newest config / Frame, asked again at once.
  let seqHave = 0, versionHave = -1, instance = "";
  async function poll() {
    for (;;) {
      try {
        const r = await fetch(`/projector/next?seq=${seqHave}&version=${versionHave}&instance=${instance}`,
                              { cache: "no-store" });
        if (!r.ok) throw new Error(`HTTP ${r.status}`);
        const answer = await r.json();
        if (!st.connected) { st.connected = true; if (config) applyConfig(config); }
        if (answer.config) {
          versionHave = answer.config.version; instance = answer.config.instance; applyConfig(answer.config);
        }
        if (answer.frame) {
          const m = answer.frame;
          seqHave = m.seq;
          last = pending = m;
        }
      } catch (err) {  // the console stopped or restarted: black, and say so; ask again in a second
        st.connected = false;
        seqHave = 0; versionHave = -1;  // a restarted console counts from 0 again
        warp.style.display = "none";
        say("swarmdeck projector: waiting for the console…");
        await new Promise((res) => setTimeout(res, 1000));
      }
    }
  }
  poll();
  say("swarmdeck projector: waiting for the console…");
  window.addEventListener("resize", () => { if (config) applyConfig(config); });
  requestAnimationFrame(tick);
})();
