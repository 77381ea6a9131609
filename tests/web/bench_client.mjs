// One benchmark client for scripts/bench-bridge: subscribes to every channel with Foxglove's
// client library and, for each LASER message, the latency from the bridge receiving it on LCM
// (the message header's receive time, wall clock ns) to this client parsing it. Runs until
// SIGINT/SIGTERM, then prints one JSON line: messages and bytes per topic, LASER latency p50/p99/max (ms).
//   node bench_client.mjs --url ws://127.0.0.1:8765
import wsProtocol from "@foxglove/ws-protocol";
import { WebSocket } from "ws";

const { FoxgloveClient } = wsProtocol;
const at = process.argv.indexOf("--url");
const url = at > 0 ? process.argv[at + 1] : "ws://127.0.0.1:8765";
const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
const client = new FoxgloveClient({ ws });
const topics = new Map();
const counts = {};
let bytes = 0;
const latencies = [];
const decoder = new TextDecoder();

client.on("advertise", (channels) => {
  for (const channel of channels) topics.set(client.subscribe(channel.id), channel.topic);
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const topic = topics.get(subscriptionId);
  JSON.parse(decoder.decode(data));  // a client that uses the data parses it
  const nowMs = performance.timeOrigin + performance.now();
  counts[topic] = (counts[topic] ?? 0) + 1;
  bytes += data.byteLength;
  if (topic === "LASER") latencies.push(nowMs - Number(timestamp / 1000n) / 1000);
});

function percentile(sorted, p) {
  return sorted.length === 0 ? null : sorted[Math.min(sorted.length - 1, Math.floor(p * sorted.length))];
}
function finish() {
  const sorted = [...latencies].sort((a, b) => a - b);
  console.log(JSON.stringify({ counts, bytes, laser: sorted.length, p50_ms: percentile(sorted, 0.5),
    p99_ms: percentile(sorted, 0.99), max_ms: sorted.at(-1) ?? null, latencies_ms: latencies }));
  process.exit(0);
}
process.on("SIGINT", finish);
process.on("SIGTERM", finish);
