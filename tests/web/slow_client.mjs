// A client that stops reading (its socket paused: the bridge's TCP writes back up) next to one
// that keeps reading. The healthy one must keep getting LASER while the stalled one is stuck.
//   node slow_client.mjs --url ws://127.0.0.1:8765 [--seconds 8]
// Prints one JSON line: LASER and GRID_MAP messages the healthy client got after the stall began.
import wsProtocol from "@foxglove/ws-protocol";
import { WebSocket } from "ws";

const { FoxgloveClient } = wsProtocol;
function option(name, fallback) {
  const at = process.argv.indexOf("--" + name);
  return at > 0 ? process.argv[at + 1] : fallback;
}
const url = option("url", "ws://127.0.0.1:8765");
const seconds = Number(option("seconds", "8"));
const summary = { ok: false, laserAfterStall: 0, gridsAfterStall: 0, stalled: false };

function subscribeAll(client, wanted) {
  client.on("advertise", (channels) => {
    for (const c of channels) if (!wanted || wanted.includes(c.topic)) client.subscribe(c.id);
  });
}

const stalledSocket = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
const stalled = new FoxgloveClient({ ws: stalledSocket });
subscribeAll(stalled, null);
stalled.on("message", () => {
  if (summary.stalled) return;
  summary.stalled = true;
  stalledSocket._socket.pause();  // read nothing more: the kernel buffers fill, then the bridge's queue
  setTimeout(finish, seconds * 1000);
});

const healthy = new FoxgloveClient({ ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
const topics = new Map();
healthy.on("advertise", (channels) => {
  for (const c of channels) if (c.topic === "LASER" || c.topic === "GRID_MAP") topics.set(healthy.subscribe(c.id), c.topic);
});
healthy.on("message", ({ subscriptionId }) => {
  if (!summary.stalled) return;
  if (topics.get(subscriptionId) === "LASER") summary.laserAfterStall += 1;
  else summary.gridsAfterStall += 1;
});

function finish() {
  summary.ok = summary.stalled;
  console.log(JSON.stringify(summary));
  process.exit(0);
}
setTimeout(() => { console.log(JSON.stringify(summary)); process.exit(1); }, (seconds + 30) * 1000);
