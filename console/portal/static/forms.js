// The upload form: refuse a file over the portal's limit before sending it (the server refuses it too).
"use strict";
document.addEventListener("DOMContentLoaded", () => {
  const form = document.getElementById("submit-form");
  const input = document.getElementById("script");
  const out = document.getElementById("script-error");
  if (!form || !input || !out) return;
  const max = Number(input.dataset.maxBytes);
  const check = () => {
    const f = input.files && input.files[0];
    const bad = f && f.size > max ? `${f.name} is ${(f.size / 1048576).toFixed(1)} MB: the limit is ${(max / 1048576).toFixed(1)} MB` : "";
    out.textContent = bad;
    out.classList.toggle("hidden", !bad);
    input.classList.toggle("bad", Boolean(bad));
    return !bad;
  };
  input.addEventListener("change", check);
  form.addEventListener("submit", (ev) => { if (!check()) ev.preventDefault(); });
});
