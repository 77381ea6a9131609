// Publishes a goal the way a Foxglove client does (advertise a client channel, send message
// data on it) and reports whether the server offered clientPublish and how many error statuses
// came back. The read-only test expects no capability, errors, and no GOAL on LCM.
//   node publish_goal.mjs --url ws://127.0.0.1:8765 [--topic GOAL]
import wsProtocol from "@foxglove/ws-protocol";
import { WebSocket } from "ws";

const { FoxgloveClient } = wsProtocol;
function option(name, fallback) {
  const at = process.argv.indexOf("--" + name);
  return at > 0 ? process.argv[at + 1] : fallback;
}
const ws = new WebSocket(option("url", "ws://127.0.0.1:8765"), [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
const client = new FoxgloveClient({ ws });
const summary = { ok: true, clientPublish: null, statusErrors: 0 };
client.on("status", (status) => { if (status.level === 2) summary.statusErrors += 1; });
client.on("serverInfo", (info) => {
  summary.clientPublish = info.capabilities.includes("clientPublish");
  const channel = client.advertise({ topic: option("topic", "GOAL"), encoding: "json", schemaName: "polarslam.Goal" });
  client.sendMessage(channel, new TextEncoder().encode(JSON.stringify({ x: 1, y: 2 })));
  setTimeout(() => {
    client.close();
    console.log(JSON.stringify(summary));
    process.exit(0);
  }, 1500);
});
setTimeout(() => { console.log(JSON.stringify({ ok: false, reason: "no serverInfo" })); process.exit(1); }, 15000);
