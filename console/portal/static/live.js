// The live view: the running job drawn top-down on a canvas from the portal's stream (Server-Sent Events of
// the arena's newest Frame, at most 10 a second). Read-only: the console's picture, no controls. Each message
// is the renderer-neutral picture of the Frame (swarmdeck.console.picture, serialised by portal/live.py):
// robot colours, changed robots, active pairs and their colours, the palette and the glyph sizes all come
// from the server, so this canvas draws what the console, the video and Foxglove draw. window.swarmdeckLive
// tells tests what was drawn.
"use strict";
document.addEventListener("DOMContentLoaded", () => {
  const canvas = document.getElementById("live");
  const status = document.getElementById("live-status");
  if (!canvas) return;
  const ctx = canvas.getContext("2d");
  const drawn = (window.swarmdeckLive = { frames: 0, seq: null, tick: null, poses: null, runState: null, state: null, ended: false, links: 0, rays: 0, annotations: 0, texts: [] });
  const heat = new Image();
  let last = null;
  heat.onload = () => { if (last) draw(last); };

  function draw(m) {
    const [x0, x1, y0, y1] = m.bounds;
    const W = canvas.width, H = canvas.height;
    const s = Math.min(W / (x1 - x0), H / (y1 - y0));
    const ox = (W - s * (x1 - x0)) / 2, oy = (H - s * (y1 - y0)) / 2;
    const X = (x) => ox + (x - x0) * s, Y = (y) => oy + (y1 - y) * s;
    const P = m.palette, r = m.robot_radius * s;
    ctx.fillStyle = P.floor;
    ctx.fillRect(0, 0, W, H);
    if (m.density && heat.complete && heat.naturalWidth) {
      ctx.imageSmoothingEnabled = true;
      ctx.drawImage(heat, X(x0), Y(y1), s * (x1 - x0), s * (y1 - y0));
    }
    ctx.strokeStyle = P.grid; ctx.globalAlpha = 0.35; ctx.lineWidth = 1;  // floor grid, 0.5 m
    ctx.beginPath();
    for (let x = Math.ceil(x0 / 0.5) * 0.5; x <= x1 + 1e-9; x += 0.5) { ctx.moveTo(X(x), Y(y0)); ctx.lineTo(X(x), Y(y1)); }
    for (let y = Math.ceil(y0 / 0.5) * 0.5; y <= y1 + 1e-9; y += 0.5) { ctx.moveTo(X(x0), Y(y)); ctx.lineTo(X(x1), Y(y)); }
    ctx.stroke();
    ctx.globalAlpha = 1;
    ctx.strokeStyle = P.voronoi; ctx.lineWidth = 1.2;  // Voronoi cells
    ctx.beginPath();
    for (const [[ax, ay], [bx, by]] of m.edges) { ctx.moveTo(X(ax), Y(ay)); ctx.lineTo(X(bx), Y(by)); }
    ctx.stroke();
    if (m.obstacles && m.obstacles.length) {  // line-segment obstacles, 3 cm thick
      ctx.strokeStyle = P.obstacle; ctx.lineWidth = Math.max(2, 0.03 * s); ctx.lineCap = "round";
      ctx.beginPath();
      for (const [[ax, ay], [bx, by]] of m.obstacles) { ctx.moveTo(X(ax), Y(ay)); ctx.lineTo(X(bx), Y(by)); }
      ctx.stroke();
      ctx.lineCap = "butt";
    }
    ctx.fillStyle = P.centroid;
    for (const [cx, cy] of m.centroids) ctx.fillRect(X(cx) - 3, Y(cy) - 3, 6, 6);
    const links = document.getElementById("live-network");
    if (m.links && m.links.length && (!links || links.checked)) {  // communication links, idle → busy
      ctx.lineWidth = 1.5;
      m.links.forEach(([i, j], k) => {
        ctx.strokeStyle = m.link_colours[k];
        ctx.beginPath(); ctx.moveTo(X(m.poses[i][0]), Y(m.poses[i][1])); ctx.lineTo(X(m.poses[j][0]), Y(m.poses[j][1])); ctx.stroke();
      });
      drawn.links = m.links.length;
    } else drawn.links = 0;
    ctx.lineWidth = 3;  // active barrier pairs, coloured by h
    m.pairs.forEach(([i, j], k) => {
      ctx.strokeStyle = m.pair_colours[k];
      ctx.beginPath(); ctx.moveTo(X(m.points[i][0]), Y(m.points[i][1])); ctx.lineTo(X(m.points[j][0]), Y(m.points[j][1])); ctx.stroke();
    });
    drawn.rays = m.sensors ? m.sensors.rays.length : 0;
    if (m.sensors) {  // the sensors' layer: ToF rays to their end points
      ctx.strokeStyle = P.sensor_ray; ctx.lineWidth = 1;
      ctx.beginPath();
      for (const [[ax, ay], [bx, by]] of m.sensors.rays) { ctx.moveTo(X(ax), Y(ay)); ctx.lineTo(X(bx), Y(by)); }
      ctx.stroke();
      ctx.fillStyle = P.sensor_hit;
      for (const [, [bx, by]] of m.sensors.rays) ctx.fillRect(X(bx) - 2, Y(by) - 2, 4, 4);
    }
    drawAnnotations(m.annotations, X, Y, s);
    ctx.strokeStyle = P.changed; ctx.lineWidth = 2;  // robots whose command the filter changed
    for (const i of m.moved) { ctx.beginPath(); ctx.arc(X(m.poses[i][0]), Y(m.poses[i][1]), m.rings.changed * r, 0, 2 * Math.PI); ctx.stroke(); }
    const rv = m.rings.virtual * r, dash = (2 * Math.PI * rv) / 16;  // virtual robots: every other of 16 arcs
    ctx.strokeStyle = P.virtual; ctx.setLineDash([dash, dash]);
    for (const i of m.virtual) { ctx.beginPath(); ctx.arc(X(m.poses[i][0]), Y(m.poses[i][1]), rv, 0, 2 * Math.PI); ctx.stroke(); }
    ctx.setLineDash([]);
    ctx.font = `${Math.max(10, Math.round(r * 1.1))}px system-ui, sans-serif`;
    ctx.textAlign = "center"; ctx.textBaseline = "bottom";
    m.poses.forEach(([x, y, th], i) => {
      const px = X(x), py = Y(y);
      ctx.fillStyle = m.colours[i];
      ctx.beginPath(); ctx.arc(px, py, r, 0, 2 * Math.PI); ctx.fill();
      ctx.strokeStyle = P.heading; ctx.lineWidth = 2;  // heading
      ctx.beginPath(); ctx.moveTo(px + 0.2 * r * Math.cos(th), py - 0.2 * r * Math.sin(th));
      ctx.lineTo(px + 1.4 * r * Math.cos(th), py - 1.4 * r * Math.sin(th)); ctx.stroke();
      const led = m.sensors && m.sensors.leds ? m.sensors.leds[i] : null;
      if (led) { ctx.fillStyle = led; ctx.beginPath(); ctx.arc(px, py, 0.45 * r, 0, 2 * Math.PI); ctx.fill(); }
      ctx.fillStyle = P.label;
      ctx.fillText(String(m.ids[i]), px, py - 1.2 * r);
    });
    ctx.strokeStyle = P.boundary; ctx.lineWidth = 2;
    ctx.strokeRect(X(x0), Y(y1), s * (x1 - x0), s * (y1 - y0));
    if (m.run_state === "estop") {
      ctx.strokeStyle = P.stopped; ctx.lineWidth = 8; ctx.strokeRect(4, 4, W - 8, H - 8);
      ctx.fillStyle = P.stopped; ctx.font = "bold 22px system-ui, sans-serif"; ctx.textAlign = "right"; ctx.textBaseline = "top";
      ctx.fillText("EMERGENCY STOP", W - 16, 14);
    }
  }

  // What the experiment drew (portal/live.py annotations_message): kinds 0 point, 1 polyline, 2 circle,
  // 3 polygon, 4 text; vertices in metres, sizes in metres (radius, line width, text height), colours given.
  function drawAnnotations(a, X, Y, s) {
    drawn.annotations = a ? a.kinds.length : 0;
    drawn.texts = [];
    if (!a) return;
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
        drawn.texts.push(a.texts[i]);
      }
    });
    ctx.restore();
  }

  function show(text) { status.textContent = text; }
  const source = new EventSource(canvas.dataset.stream);
  source.addEventListener("frame", (ev) => {
    const m = JSON.parse(ev.data);
    last = m;
    if (m.density && heat.src !== m.density) heat.src = m.density;
    draw(m);
    Object.assign(drawn, { frames: drawn.frames + 1, seq: m.seq, tick: m.tick, poses: m.poses, runState: m.run_state,
                           obstacles: (m.obstacles || []).length });
    const b = m.barrier;
    show(`t ${m.t.toFixed(2)} s · ${m.poses.length} robots · ${m.run_state}` +
         (b ? (b.enabled ? ` · barrier: ${b.n_active} active` + (b.min_distance !== null ? `, d_min ${b.min_distance.toFixed(3)} m` : "") : " · barrier OFF") : "") +
         (m.events.length ? ` · ${m.events.join("; ")}` : ""));
  });
  source.addEventListener("state", (ev) => {
    const st = JSON.parse(ev.data);
    drawn.state = st.state;
    if (st.final) {
      drawn.ended = true;
      source.close();
      show(`the run has ended (${st.state})` + (st.message ? `: ${st.message}` : ""));
    }
  });
  source.onerror = () => { if (!drawn.ended) show("connection lost: reconnecting…"); };
});
