// Starts Swagger UI on the API page (/docs): served from this server, no inline script (the page's CSP).
window.addEventListener("load", function () {
  var el = document.getElementById("swagger-ui");
  window.ui = SwaggerUIBundle({url: el.dataset.url, dom_id: "#swagger-ui", deepLinking: true});
});
