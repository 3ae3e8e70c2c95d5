// Two jobs overlaid on one canvas (compare.html): the first run solid, the others translucent "ghosts" in a
// colour each, with their paths so far; a slider and Play move both along one timeline (aligned at start).
(function () {
  "use strict";
  const canvas = document.getElementById("compare");
  const data = document.getElementById("compare-tracks");
  if (!canvas || !data) return;
  const runs = JSON.parse(data.textContent);
  const colours = ["#1446aa", "#d62728", "#2ca02c", "#9467bd"];
  const slider = document.getElementById("compare-t"), label = document.getElementById("compare-time");
  const button = document.getElementById("compare-play");
  const ctx = canvas.getContext("2d");
  const x0 = Math.min(...runs.map((r) => r.bounds[0])), x1 = Math.max(...runs.map((r) => r.bounds[1]));
  const y0 = Math.min(...runs.map((r) => r.bounds[2])), y1 = Math.max(...runs.map((r) => r.bounds[3]));
  const end = Math.max(...runs.map((r) => r.t[r.t.length - 1] || 0));
  const pad = 12, s = Math.min((canvas.width - 2 * pad) / (x1 - x0), (canvas.height - 2 * pad) / (y1 - y0));
  const X = (x) => pad + (x - x0) * s, Y = (y) => pad + (y1 - y) * s;
  const index = (r, t) => {  // the last sample at or before t
    let lo = 0, hi = r.t.length - 1;
    if (t <= r.t[0]) return 0;
    while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (r.t[mid] <= t) lo = mid; else hi = mid - 1; }
    return lo;
  };
  function draw(t) {
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    runs.forEach((r) => {
      ctx.strokeStyle = "#333"; ctx.lineWidth = 1.5;
      ctx.strokeRect(X(r.bounds[0]), Y(r.bounds[3]), (r.bounds[1] - r.bounds[0]) * s, (r.bounds[3] - r.bounds[2]) * s);
    });
    runs.forEach((r, k) => {
      const c = colours[k % colours.length], i = index(r, t), now = r.poses[i];
      ctx.globalAlpha = k ? 0.35 : 0.5; ctx.strokeStyle = c; ctx.lineWidth = 1;
      for (let j = 0; j < now.length; j++) {  // paths so far
        ctx.beginPath();
        for (let q = 0; q <= i; q++) { const p = r.poses[q][j]; if (!p) continue; if (q) ctx.lineTo(X(p[0]), Y(p[1])); else ctx.moveTo(X(p[0]), Y(p[1])); }
        ctx.stroke();
      }
      ctx.globalAlpha = k ? 0.5 : 1; ctx.fillStyle = c;
      const rad = Math.max(3, 0.055 * s);
      now.forEach((p) => {
        ctx.beginPath(); ctx.arc(X(p[0]), Y(p[1]), rad, 0, 2 * Math.PI); ctx.fill();
        ctx.beginPath(); ctx.moveTo(X(p[0]), Y(p[1]));
        ctx.lineTo(X(p[0] + 0.07 * Math.cos(p[2])), Y(p[1] + 0.07 * Math.sin(p[2]))); ctx.strokeStyle = "#fff"; ctx.globalAlpha = 1; ctx.stroke();
        ctx.globalAlpha = k ? 0.5 : 1;
      });
    });
    ctx.globalAlpha = 1;
    label.textContent = "t = " + t.toFixed(1) + " s";
    canvas.dataset.t = t.toFixed(2);
  }
  let playing = null;
  const tOf = () => (slider.value / 1000) * end;
  slider.addEventListener("input", () => draw(tOf()));
  button.addEventListener("click", () => {
    if (playing) { clearInterval(playing); playing = null; button.textContent = "Play"; return; }
    button.textContent = "Pause";
    playing = setInterval(() => {
      const v = Math.min(1000, Number(slider.value) + 1000 * 0.1 / Math.max(end, 0.1));
      slider.value = v; draw(tOf());
      if (v >= 1000) { clearInterval(playing); playing = null; button.textContent = "Play"; }
    }, 100);
  });
  draw(0);
  canvas.dataset.runs = String(runs.length);
})();
