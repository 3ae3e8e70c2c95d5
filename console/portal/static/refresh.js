// Keeps pages current without a framework: the jobs table updates its state cells in place; the job page and
// the operator page reload when what they show has changed (never while a form is being sent).
"use strict";
(() => {
  const PERIOD = 1500;
  let sending = false;
  document.addEventListener("submit", () => { sending = true; }, true);
  const get = async (url) => {
    const r = await fetch(url, { credentials: "same-origin", cache: "no-store" });
    if (r.status === 401) { location.href = "/signin"; return null; }
    return r.ok ? r.json() : null;
  };
  const every = (fn) => {
    const tick = async () => { if (!sending) { try { await fn(); } catch (e) { /* offline: try again */ } } setTimeout(tick, PERIOD); };
    setTimeout(tick, PERIOD);
  };
  document.addEventListener("DOMContentLoaded", () => {
    const table = document.querySelector("table[data-refresh]");
    if (table) every(async () => {
      const jobs = await get(table.dataset.refresh);
      if (!jobs) return;
      for (const j of jobs) {
        const row = table.querySelector(`tr[data-job="${j.id}"]`);
        if (!row) { location.reload(); return; }
        const state = row.querySelector('[data-field="state"]');
        if (state.textContent !== j.state) {
          state.textContent = j.state;
          state.className = "state state-" + j.state.replace(/ /g, "-");
        }
        row.querySelector('[data-field="verdict"]').textContent = j.verdict || "";
      }
    });
    const job = document.getElementById("job");
    if (job) every(async () => {
      // reload when the page would show other things (the verdict, the live view, the downloads); a job going
      // from "setting up" to "running" keeps its live view and only changes the state shown
      const j = await get(job.dataset.jobUrl);
      if (!j) return;
      if ((j.exports || "") !== job.dataset.exports) { location.reload(); return; }  // exports ready (or failed)
      if (j.exports === "writing") {  // the downloads appear one after another
        const files = await get(job.dataset.jobUrl + "/files");
        if (files && files.length !== Number(job.dataset.files)) { location.reload(); return; }
      }
      if (j.state === job.dataset.state) return;
      const kind = (state) => (job.dataset.liveStates.split(",").includes(state) ? "live"
        : job.dataset.finalStates.split(",").includes(state) ? "final" : "waiting");
      if (kind(j.state) !== kind(job.dataset.state) || (j.verdict || "") !== job.dataset.verdict) { location.reload(); return; }
      job.dataset.state = j.state;
      const shown = document.getElementById("state");
      shown.textContent = j.state;
      shown.className = "state state-" + j.state.replace(/ /g, "-");
    });
    const arena = document.getElementById("arena");
    if (arena) every(async () => {
      const [a, jobs] = await Promise.all([get(arena.dataset.arenaUrl), get("/api/jobs")]);
      if (!a || !jobs) return;
      const sig = [a.stopped, a.manual_approval, (a.running || {}).id, (a.running || {}).state,
                   a.queue.map((j) => j.id).join(","), jobs.map((j) => `${j.id}:${j.state}`).join(","),
                   ((a.alerts || {}).messages || []).length].join("|");
      if (arena.dataset.sig !== sig) { location.reload(); return; }  // data-sig: the same summary, made by the server
      const fleet = document.getElementById("fleet");
      for (const r of (a.fleet && fleet ? a.fleet.robots : [])) {  // the fleet table: states and charges in place
        const row = fleet.querySelector(`tr[data-robot="${r.id}"]`);
        if (!row) continue;
        row.querySelector('[data-field="state"]').textContent = r.state + (r.job !== null ? ` to job ${r.job}` : "");
        row.querySelector('[data-field="charge"]').textContent = r.charge !== null ? `${Math.round(100 * r.charge)} %` : "unknown";
        row.querySelector('[data-field="slot"]').textContent = r.slot !== null ? r.slot : (r.state === "missing" ? "–" : "floor");
      }
      const map = document.getElementById("arena-map");  // the fleet's poses, drawn in place
      for (const r of (a.fleet && map ? a.fleet.robots : [])) {
        const g = map.querySelector(`g[data-robot="${r.id}"]`);
        if (!g || r.x === null) continue;
        g.setAttribute("transform", `translate(${r.x.toFixed(4)} ${(-r.y).toFixed(4)}) rotate(${(-r.theta * 57.29578).toFixed(2)})`);
        g.setAttribute("class", "robot robot-" + r.state.replace(/ /g, "-"));
      }
      const ready = document.getElementById("fleet-ready");
      if (ready && a.fleet) ready.firstChild.textContent = a.fleet.ready
        ? "Arena ready: every robot is docked or assigned to a job." : "Arena NOT ready: robots are away from the chargers.";
    });
  });
})();
