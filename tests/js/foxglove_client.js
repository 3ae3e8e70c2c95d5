// The official Foxglove WebSocket client (@foxglove/ws-protocol) over the `ws` package:
//   node foxglove_client.js URL SUBPROTOCOL TOPIC COUNT
// connects with SUBPROTOCOL, subscribes to TOPIC once it is advertised and prints one JSON line per
// event: {"event":"open","protocol":...}, {"event":"channel",...} (the advertised channel), then COUNT
// {"event":"message","logTime":"<ns>","data":"<base64>"} lines; exits 0, or 1 with {"event":"error"}.
"use strict";
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");

const [url, subprotocol, topic, count] = process.argv.slice(2);
const out = (o) => process.stdout.write(JSON.stringify(o) + "\n");
const fail = (message) => { out({ event: "error", message: String(message) }); process.exit(1); };
setTimeout(() => fail("timed out"), 60000).unref();

const ws = new WebSocket(url, [subprotocol]);
ws.on("unexpected-response", (_req, res) => fail(`HTTP ${res.statusCode} ${res.statusMessage}`));
const client = new FoxgloveClient({ ws });
let sub = null;
let got = 0;
client.on("open", () => out({ event: "open", protocol: ws.protocol }));
client.on("error", (e) => fail(e && e.message ? e.message : e));
client.on("serverInfo", (info) => out({ event: "serverInfo", name: info.name }));
client.on("advertise", (channels) => {
  const ch = channels.find((c) => c.topic === topic);
  if (ch && sub === null) {
    out({ event: "channel", ...ch });
    sub = client.subscribe(ch.id);
  }
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  if (subscriptionId !== sub) return;
  const bytes = Buffer.from(data.buffer, data.byteOffset, data.byteLength);
  out({ event: "message", logTime: timestamp.toString(), data: bytes.toString("base64") });
  if (++got >= Number(count)) { client.close(); process.exit(0); }
});
