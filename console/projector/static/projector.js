// The projector page: the arena drawn top-down on a canvas in floor metres, warped onto the projector's image
// by the floor → projector homography H (a CSS matrix3d), fed by the console (a long poll of /projector/next, one
// request at a time: the config — H, the projector's size, the layers, brightness and blackout — and the newest
// Frame's picture, swarmdeck.console.projector.message). Messages are only stored; one requestAnimationFrame draws the
// newest, so a slow page skips frames and never lags. If drawing takes longer than BUDGET_MS the page drops
// layers (DROP_ORDER) until it fits, and takes them back when there is room. Without H it writes
// "no homography — run swarmdeck calibrate projector" across the screen. window.swarmdeckProjector tells tests
// and the bench what was drawn and when.
"use strict";
(() => {
  const floor = document.getElementById("floor");
  const warp = document.getElementById("warp");
  const heatCanvas = document.getElementById("heat");
  const hctx = heatCanvas.getContext("2d");
  const notice = document.getElementById("notice");
  const ctx = floor.getContext("2d");
  const nctx = notice.getContext("2d");
  let PX_PER_M = 400;             // the floor canvas's resolution before the warp (lowered on big arenas)
  let K = 1;                      // line widths and glyph sizes × K (drawn at 400 px/m)
  const BUDGET_MS = 20;           // a frame's drawing budget (30 frames/s with room for the browser)
  const DROP_ORDER = ["safety", "halos", "graph", "centroids", "annotations", "cells", "goals"];
  const st = (window.swarmdeckProjector = {
    frames: 0, seq: null, tick: null, config: null, drawn: [], latency: [], drawMs: [], dropped: [],
    message: "", connected: false, lastDraw: null, layersDrawn: [], annotationsDrawn: 0,
  });
  let config = null, pending = null, last = null, ema = 0;

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

  function applyConfig(c) {
    config = c;
    st.config = c;
    const [x0, x1, y0, y1] = c.bounds;
    const asked = Number(new URLSearchParams(location.search).get("ppm"));  // ?ppm=N: another resolution
    PX_PER_M = asked > 0 ? Math.min(asked, 800) : Math.min(400, 1600 / Math.max(x1 - x0, y1 - y0));
    K = PX_PER_M / 400;
    floor.width = Math.round((x1 - x0) * PX_PER_M); floor.height = Math.round((y1 - y0) * PX_PER_M);
    floor.style.width = floor.width + "px"; floor.style.height = floor.height + "px";
    heatCanvas.style.width = floor.style.width; heatCanvas.style.height = floor.style.height;
    warp.style.opacity = String(c.settings.opacity);
    if (!c.H) {
      warp.style.display = "none";
      say("no homography — run swarmdeck calibrate projector");
      return;
    }
    // CSS px (edge coordinates) of the floor canvas → metres → projector px (centres) → CSS px of the page
    const s = 1 / PX_PER_M, dpr = window.devicePixelRatio || 1;
    const A = [[s, 0, x0], [0, -s, y1], [0, 0, 1]];
    const T = [[1 / dpr, 0, 0.5 / dpr], [0, 1 / dpr, 0.5 / dpr], [0, 0, 1]];
    const mul = (P, Q) => P.map((r) => [0, 1, 2].map((j) => r[0] * Q[0][j] + r[1] * Q[1][j] + r[2] * Q[2][j]));
    const M = mul(T, mul(c.H, A));
    warp.style.transform = `matrix3d(${M[0][0]},${M[1][0]},0,${M[2][0]},${M[0][1]},${M[1][1]},0,${M[2][1]},` +
      `0,0,1,0,${M[0][2]},${M[1][2]},0,${M[2][2]})`;
    warp.style.display = c.settings.blackout ? "none" : "block";
    say("");
    if (last) pending = last;
  }

  function on(layer) {
    return config && config.settings[layer] && !st.dropped.includes(layer);
  }

  function draw(m) {
    const t0 = performance.now();
    const [x0, x1, y0, y1] = m.bounds;
    const X = (x) => (x - x0) * PX_PER_M, Y = (y) => (y1 - y) * PX_PER_M;
    const P = m.palette, W = floor.width, H = floor.height;
    const drawnLayers = [];
    ctx.clearRect(0, 0, W, H);
    if (config.settings.blackout) { st.layersDrawn = []; return performance.now() - t0; }
    if (m.density && config.settings.density) {  // raw RGB, a few thousand pixels: the compositor smooths it up
      const d = m.density, raw = atob(d.rgb), n = d.w * d.h;
      if (heatCanvas.width !== d.w || heatCanvas.height !== d.h) { heatCanvas.width = d.w; heatCanvas.height = d.h; }
      const img = hctx.createImageData(d.w, d.h), px = img.data;
      for (let i = 0, j = 0; i < n; i += 1, j += 3) {
        px[4 * i] = raw.charCodeAt(j); px[4 * i + 1] = raw.charCodeAt(j + 1); px[4 * i + 2] = raw.charCodeAt(j + 2);
        px[4 * i + 3] = 255;
      }
      hctx.putImageData(img, 0, 0);
      heatCanvas.style.display = "block";
      drawnLayers.push("density");
    } else {
      heatCanvas.style.display = "none";
    }
    if (on("cells") && m.edges.length) {
      ctx.strokeStyle = P.voronoi; ctx.lineWidth = 4 * K;
      ctx.beginPath();
      for (const [[ax, ay], [bx, by]] of m.edges) { ctx.moveTo(X(ax), Y(ay)); ctx.lineTo(X(bx), Y(by)); }
      ctx.stroke();
      drawnLayers.push("cells");
    }
    if (on("centroids") && m.centroids.length) {
      ctx.fillStyle = P.centroid;
      for (const [cx, cy] of m.centroids) ctx.fillRect(X(cx) - 8 * K, Y(cy) - 8 * K, 16 * K, 16 * K);
      drawnLayers.push("centroids");
    }
    if (on("goals") && m.goals.length) {
      ctx.strokeStyle = "#ffffff"; ctx.lineWidth = 4 * K;
      ctx.beginPath();
      for (const [gx, gy] of m.goals) { ctx.moveTo(X(gx) - 12, Y(gy) - 12); ctx.lineTo(X(gx) + 12, Y(gy) + 12);
        ctx.moveTo(X(gx) - 12, Y(gy) + 12); ctx.lineTo(X(gx) + 12, Y(gy) - 12); }
      ctx.stroke();
      drawnLayers.push("goals");
    }
    if (on("graph") && m.graph) {  // the communication graph: one segment per linked pair, coloured by traffic
      ctx.lineWidth = 3 * K;
      m.graph.segments.forEach(([[ax, ay], [bx, by]], i) => {
        ctx.strokeStyle = m.graph.colours[i];
        ctx.beginPath(); ctx.moveTo(X(ax), Y(ay)); ctx.lineTo(X(bx), Y(by)); ctx.stroke();
      });
      drawnLayers.push("graph");
    }
    if (on("safety") && m.safety) {
      const r = m.safety.radius * PX_PER_M;
      ctx.strokeStyle = P.changed; ctx.lineWidth = 3 * K;
      ctx.beginPath();
      for (const [px, py] of m.safety.xy) { ctx.moveTo(X(px) + r, Y(py)); ctx.arc(X(px), Y(py), r, 0, 2 * Math.PI); }
      ctx.stroke();
      drawnLayers.push("safety");
    }
    if (on("halos") && m.halos) {
      const r = m.halos.radius * PX_PER_M;
      ctx.lineWidth = 6 * K;
      m.halos.palette.forEach((colour, c) => {  // one path per colour
        ctx.strokeStyle = colour;
        ctx.beginPath();
        m.halos.xy.forEach(([px, py], i) => {
          if (m.halos.colour[i] === c) { ctx.moveTo(X(px) + r, Y(py)); ctx.arc(X(px), Y(py), r, 0, 2 * Math.PI); }
        });
        ctx.stroke();
      });
      drawnLayers.push("halos");
    }
    if (on("annotations") && m.annotations) {
      drawAnnotations(m.annotations, X, Y);
      st.annotationsDrawn = m.annotations.kinds.length;
      drawnLayers.push("annotations");
    }
    ctx.strokeStyle = P.boundary; ctx.lineWidth = 4 * K;
    ctx.strokeRect(2, 2, W - 4, H - 4);
    if (m.run_state === "estop") {
      ctx.strokeStyle = P.stopped; ctx.lineWidth = 24 * K; ctx.strokeRect(12 * K, 12 * K, W - 24 * K, H - 24 * K);
    }
    st.layersDrawn = drawnLayers;
    return performance.now() - t0;
  }

  // What the experiment drew (console.picture.annotations.annotations_json, as the portal's live view draws it):
  // kinds 0 point, 1 polyline, 2 circle, 3 polygon, 4 text; vertices and sizes (radius, line width, text height)
  // in metres, colours given.
  function drawAnnotations(a, X, Y) {
    const s = PX_PER_M;
    ctx.save();
    ctx.lineCap = "round"; ctx.lineJoin = "round"; ctx.textAlign = "center"; ctx.textBaseline = "middle";
    a.kinds.forEach((kind, i) => {
      const v = a.vertices.slice(a.offsets[i], a.offsets[i + 1]), size = a.sizes[i], colour = a.colours[i];
      ctx.fillStyle = colour; ctx.strokeStyle = colour;
      ctx.lineWidth = Math.max(1, size * s);
      ctx.beginPath();
      if (kind === 0 || kind === 2) {
        ctx.lineWidth = Math.max(1, 0.01 * s);
        ctx.arc(X(v[0][0]), Y(v[0][1]), Math.max(1, size * s), 0, 2 * Math.PI);
        if (kind === 0 || a.filled[i]) ctx.fill(); else ctx.stroke();
      } else if (kind === 1 || kind === 3) {
        v.forEach(([x, y], k) => (k ? ctx.lineTo(X(x), Y(y)) : ctx.moveTo(X(x), Y(y))));
        if (kind === 3) ctx.closePath();
        if (kind === 3 && a.filled[i]) ctx.fill(); else ctx.stroke();
      } else if (kind === 4) {
        ctx.font = `${Math.max(8, Math.round(size * s))}px system-ui, sans-serif`;
        ctx.fillText(a.texts[i], X(v[0][0]), Y(v[0][1]));
      }
    });
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
