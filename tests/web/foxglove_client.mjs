// Connects to polarslam-bridge with Foxglove's own client library (@foxglove/ws-protocol) and
// checks what a Foxglove user would get: every channel advertised with JSON encoding and the
// published foxglove.* schema (@foxglove/schemas), messages on the expected topics that
// validate against those published schemas, protocol errors answered with a status message
// (and the server still serving afterwards), and many clients served at once.
//   node foxglove_client.mjs --url ws://127.0.0.1:8765 --expect GRID_MAP,LASER,SLAM_POSE [--clients 12] [--timeout 30]
// Prints one JSON summary line; exit code 0 = every check passed.
import wsProtocol from "@foxglove/ws-protocol";
import * as officialSchemas from "@foxglove/schemas/jsonschema.js";
import Ajv from "ajv";
import { WebSocket } from "ws";

const { FoxgloveClient } = wsProtocol;

function option(name, fallback) {
  const at = process.argv.indexOf("--" + name);
  return at > 0 ? process.argv[at + 1] : fallback;
}
const url = option("url", "ws://127.0.0.1:8765");
const expected = option("expect", "GRID_MAP,LASER,SLAM_POSE").split(",");
const clientCount = Number(option("clients", "1"));
const timeoutSeconds = Number(option("timeout", "30"));

// What each polarslam channel must be advertised as.
const expectedSchemas = {
  GRID_MAP: "foxglove.Grid", PSM_GRID_MAP: "foxglove.Grid", LASER: "foxglove.LaserScan",
  SLAM_POSE: "foxglove.PoseInFrame", PSM_SLAM_POSE: "foxglove.PoseInFrame", GROUND_TRUTH: "foxglove.PoseInFrame",
  "SLAM_POSE/trajectory": "foxglove.PosesInFrame", PLANNED_PATH: "foxglove.PosesInFrame",
  "/tf": "foxglove.FrameTransform", SLAM_MAP: "foxglove.SceneUpdate", PSM_SLAM_GRAPH: "foxglove.SceneUpdate",
  "/log": "foxglove.Log",
};

const failures = [];
const fail = (text) => { if (failures.length < 50) failures.push(text); };
const ajv = new Ajv({ strict: false, allErrors: true });
const validators = {};
function validatorFor(schemaName) {
  const official = officialSchemas[schemaName.replace(/^foxglove\./, "")];
  if (!schemaName.startsWith("foxglove.") || !official) return null;
  validators[schemaName] ??= ajv.compile(official);
  return validators[schemaName];
}

/// The advertised schema must describe every field the published schema has, with the same type.
function compareSchemas(advertised, official, where) {
  for (const [key, property] of Object.entries(official.properties ?? {})) {
    const ours = advertised.properties?.[key];
    if (!ours) { fail(`${where}.${key}: missing from the advertised schema`); continue; }
    if (property.type !== ours.type) fail(`${where}.${key}: type ${ours.type}, published ${property.type}`);
    if (property.contentEncoding !== ours.contentEncoding) fail(`${where}.${key}: contentEncoding differs`);
    if (property.type === "object") compareSchemas(ours, property, `${where}.${key}`);
    if (property.type === "array" && property.items?.type === "object") compareSchemas(ours.items, property.items, `${where}.${key}[]`);
  }
}

/// Field names the published schema lists that a message lacks (the schemas require none, Foxglove reads them all).
function missingFields(message, schema, where, out) {
  if (schema.type !== "object" || typeof message !== "object" || message === null) return;
  for (const [key, property] of Object.entries(schema.properties ?? {})) {
    if (!(key in message)) { out.push(`${where}.${key}`); continue; }
    if (property.type === "object") missingFields(message[key], property, `${where}.${key}`, out);
    if (property.type === "array" && property.items?.type === "object")
      for (const item of message[key]) missingFields(item, property.items, `${where}.${key}[]`, out);
  }
}

function connect() {
  const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  return { ws, client: new FoxgloveClient({ ws }) };
}

const summary = { received: {}, statusErrors: 0, clientsWithLaser: 0, serverInfo: null, advertised: 0 };
const decoder = new TextDecoder();

function runMainClient(done) {
  const { ws, client } = connect();
  const channels = new Map();
  const topicOfSubscription = new Map();
  let probed = false;
  client.on("serverInfo", (info) => { summary.serverInfo = info; });
  client.on("status", (status) => { if (status.level === 2) summary.statusErrors += 1; });
  client.on("error", (error) => fail("client error: " + error));
  client.on("advertise", (list) => {
    for (const channel of list) {
      channels.set(channel.id, channel);
      summary.advertised += 1;
      if (channel.encoding !== "json") fail(`${channel.topic}: encoding ${channel.encoding}`);
      const wanted = expectedSchemas[channel.topic];
      if (wanted && channel.schemaName !== wanted) fail(`${channel.topic}: schema ${channel.schemaName}, expected ${wanted}`);
      let advertised = null;
      try { advertised = JSON.parse(channel.schema); } catch { fail(`${channel.topic}: schema is not JSON`); }
      const official = officialSchemas[channel.schemaName.replace(/^foxglove\./, "")];
      if (advertised && official && channel.schemaName.startsWith("foxglove."))
        compareSchemas(advertised, official, channel.schemaName);
      topicOfSubscription.set(client.subscribe(channel.id), channel);
    }
    for (const topic of Object.keys(expectedSchemas))
      if (![...channels.values()].some((c) => c.topic === topic)) fail(`${topic}: not advertised`);
  });
  client.on("message", ({ subscriptionId, data }) => {
    const channel = topicOfSubscription.get(subscriptionId);
    if (!channel) return fail(`message on unknown subscription ${subscriptionId}`);
    let message;
    try { message = JSON.parse(decoder.decode(data)); } catch { return fail(`${channel.topic}: payload is not JSON`); }
    const validate = validatorFor(channel.schemaName);
    if (validate && !validate(message)) fail(`${channel.topic}: ${ajv.errorsText(validate.errors)}`);
    const missing = [];
    if (validate) missingFields(message, officialSchemas[channel.schemaName.replace(/^foxglove\./, "")], channel.topic, missing);
    if (missing.length > 0) fail(`${channel.topic}: fields missing: ${missing.slice(0, 5).join(", ")}`);
    summary.received[channel.topic] = (summary.received[channel.topic] ?? 0) + 1;
    if (!probed && summary.received.LASER) {
      // Protocol errors must be answered, not fatal: garbage, an unknown op, an unadvertised publish.
      probed = true;
      ws.send("this is not JSON");
      client.getParameters(["nothing"]);
      ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 1, channelId: 424242 }] }));
      ws.send(Uint8Array.from([9, 9, 9]));
    }
    const afterProbe = summary.statusErrors >= 4;
    if (afterProbe) summary.laserAfterErrors = (summary.laserAfterErrors ?? 0) + (channel.topic === "LASER" ? 1 : 0);
    if (expected.every((t) => summary.received[t] > 0) && summary.laserAfterErrors >= 2) done(ws);
  });
}

function runExtraClient(done) {
  const { ws, client } = connect();
  let counted = false;
  client.on("advertise", (list) => {
    const laser = list.find((c) => c.topic === "LASER");
    if (laser) client.subscribe(laser.id);
  });
  client.on("message", () => {
    if (counted) return;
    counted = true;
    summary.clientsWithLaser += 1;
    done(ws);
  });
}

const sockets = [];
let pending = clientCount;
const timer = setTimeout(() => finish("timed out"), timeoutSeconds * 1000);
function oneDone(ws) {
  sockets.push(ws);
  if (--pending === 0) finish(null);
}
function finish(reason) {
  clearTimeout(timer);
  if (reason) fail(reason);
  if (summary.clientsWithLaser < clientCount - 1) fail(`only ${summary.clientsWithLaser} of ${clientCount - 1} extra clients got LASER`);
  if (summary.statusErrors < 4) fail(`${summary.statusErrors} error statuses for 4 bad requests`);
  for (const ws of sockets) ws.close();
  console.log(JSON.stringify({ ok: failures.length === 0, failures, ...summary }));
  process.exit(failures.length === 0 ? 0 : 1);
}

runMainClient(oneDone);
for (let i = 1; i < clientCount; ++i) runExtraClient(oneDone);
