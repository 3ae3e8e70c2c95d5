// The upload form: refuse a file over the portal's limit before sending it (the server refuses it too), and send
// the form in the background so that, when the server finds mistakes, they are shown on this page with the chosen
// file still chosen (a page the server sends back cannot refill a file input). Without JavaScript the form posts
// normally and the page names the file to choose again.
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
  const showErrors = (doc) => {  // the errors of the page the server sent back, in this page
    const old = document.getElementById("form-errors");
    const fresh = doc.getElementById("form-errors");
    if (old) old.remove();
    if (fresh) form.before(document.importNode(fresh, true));
    else {  // refused before the form was read (an expired session, a wrong CSRF token): say what the server said
      const box = document.createElement("div");
      box.id = "form-errors"; box.className = "error"; box.setAttribute("role", "alert");
      const said = doc.querySelector("[role=alert]") || doc.querySelector("main") || doc.body;
      box.textContent = (said ? said.textContent : "").trim().slice(0, 500) || "the server refused the form";
      form.before(box);
    }
    for (const el of form.querySelectorAll("input[id], textarea[id]")) {
      const twin = doc.getElementById(el.id);
      el.classList.toggle("bad", Boolean(twin && twin.classList.contains("bad")));
    }
    const again = document.getElementById("script-again");
    if (again) again.remove();  // the file is still chosen here
    (document.getElementById("form-errors") || form).scrollIntoView({ block: "start" });
  };
  form.addEventListener("submit", async (ev) => {
    if (!check()) { ev.preventDefault(); return; }
    if (!window.fetch || !window.DOMParser || !window.FormData) return;  // the plain post
    ev.preventDefault();
    const button = form.querySelector("button[type=submit]");
    button.disabled = true;
    try {
      const r = await fetch(form.action, { method: "POST", body: new FormData(form), credentials: "same-origin" });
      if (r.redirected) { location.href = r.url; return; }  // submitted: the job's page
      showErrors(new DOMParser().parseFromString(await r.text(), "text/html"));
    } catch (e) {
      form.submit();  // the network failed: post the plain way (the browser shows what went wrong)
    } finally {
      button.disabled = false;
    }
  });
});
