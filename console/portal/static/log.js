// The script's output on the job page, while the job runs: polls /api/jobs/{id}/log?since=N and appends what is
// new (the job's owner and operators only: the API checks). Stops once the job is no longer live.
"use strict";
document.addEventListener("DOMContentLoaded", () => {
  const pre = document.getElementById("script-log");
  if (!pre) return;
  let next = 0;
  const poll = async () => {
    let live = true;
    try {
      const r = await fetch(`${pre.dataset.logUrl}?since=${next}`, { credentials: "same-origin", cache: "no-store" });
      if (r.ok) {
        const d = await r.json();
        if (d.text) {
          const atEnd = pre.scrollTop + pre.clientHeight >= pre.scrollHeight - 4;
          pre.textContent += d.text;
          if (atEnd) pre.scrollTop = pre.scrollHeight;  // follow the end unless the reader scrolled up
        }
        next = d.next;
        live = d.live;
        pre.dataset.next = String(next);
        document.getElementById("script-log-state").textContent = live ? "live" : "the run has ended";
      }
    } catch (e) { /* offline: try again */ }
    if (live) setTimeout(poll, 1000);
  };
  poll();
});
