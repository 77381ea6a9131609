// The built-in page of polarslam-bridge: a Foxglove WebSocket client (foxglove.websocket.v1,
// JSON encoding) that draws what the bridge sends on one canvas, in the map frame.
"use strict";

const COLOURS = { SLAM: "#1e6bff", PSM: "#9b30d9", TRUTH: "#20a040", SCAN: "#e02020", PATH: "#ff8c00" };
const canvas = document.getElementById("map");
const ctx = canvas.getContext("2d");

const state = {
  socket: null,
  topics: {},          // channel id -> {topic, schemaName}
  subscriptions: {},   // subscription id -> topic
  metadata: {},
  canPublish: false,
  goalChannel: null,   // our client channel id once advertised
  grids: {},           // topic -> {image (canvas), x0, y0, width, height (m)}
  poses: {},           // topic -> {x, y, theta, frame}
  trajectories: {},    // pose topic -> [{x, y}]
  transforms: {},      // child frame -> {parent, x, y, theta}
  scan: null,
  scenes: {},          // entity id -> entity
  path: [],
  goal: null,
  processes: {},
  received: {},        // topic -> messages received (tests and curious users)
  view: null,          // {scale, cx, cy}: pixels per metre, map point at the canvas centre
  dirty: true,
};
window.polarslamPage = state;

function listTopics(key, fallback) {
  const value = state.metadata[key];
  return (value === undefined ? fallback : value).split(",").filter((t) => t.length > 0);
}

function yawOf(q) { return 2 * Math.atan2(q.z, q.w); }
function poseOf(p) { return { x: p.position.x, y: p.position.y, theta: yawOf(p.orientation) }; }
function compose(a, b) {
  const c = Math.cos(a.theta), s = Math.sin(a.theta);
  return { x: a.x + c * b.x - s * b.y, y: a.y + s * b.x + c * b.y, theta: a.theta + b.theta };
}

function connect() {
  const socket = new WebSocket("ws://" + location.host + "/", ["foxglove.websocket.v1"]);
  socket.binaryType = "arraybuffer";
  state.socket = socket;
  socket.onopen = () => setConnection("connected", true);
  socket.onclose = () => {
    setConnection("disconnected — retrying", false);
    state.topics = {}; state.subscriptions = {}; state.goalChannel = null;
    setTimeout(connect, 1000);
  };
  socket.onmessage = (event) => {
    if (typeof event.data === "string") onServerText(JSON.parse(event.data));
    else onServerBinary(new DataView(event.data));
  };
}

function setConnection(text, good) {
  const el = document.getElementById("connection");
  el.textContent = text;
  el.className = good ? "good" : "bad";
}

function onServerText(message) {
  if (message.op === "serverInfo") {
    state.metadata = message.metadata || {};
    state.canPublish = (message.capabilities || []).includes("clientPublish") && !!state.metadata.goal_topic;
    document.getElementById("hint").textContent = state.canPublish
      ? "click on the map to send a goal on " + state.metadata.goal_topic : "read-only";
    fillSelect("grid-source", listTopics("grid_topics", "GRID_MAP,PSM_GRID_MAP"));
    fillSelect("pose-source", listTopics("pose_topics", "SLAM_POSE,PSM_SLAM_POSE,GROUND_TRUTH").slice(0, 2));
  } else if (message.op === "advertise") {
    const subscriptions = [];
    for (const channel of message.channels) {
      if (channel.encoding !== "json") continue;
      state.topics[channel.id] = channel;
      const id = Object.keys(state.subscriptions).length + 1;
      state.subscriptions[id] = channel.topic;
      subscriptions.push({ id, channelId: channel.id });
    }
    state.socket.send(JSON.stringify({ op: "subscribe", subscriptions }));
  } else if (message.op === "status") {
    console.warn("bridge status", message.level, message.message);
  }
}

function fillSelect(id, topics) {
  const select = document.getElementById(id);
  if (select.options.length > 0) return;
  select.add(new Option("first available", ""));
  for (const topic of topics) select.add(new Option(topic, topic));
  select.onchange = () => { state.dirty = true; };
}

const decoder = new TextDecoder();
function onServerBinary(view) {
  if (view.byteLength < 13 || view.getUint8(0) !== 1) return;
  const topic = state.subscriptions[view.getUint32(1, true)];
  if (topic === undefined) return;
  const message = JSON.parse(decoder.decode(new Uint8Array(view.buffer, view.byteOffset + 13)));
  state.received[topic] = (state.received[topic] || 0) + 1;
  const schema = Object.values(state.topics).find((c) => c.topic === topic)?.schemaName;
  const handlers = {
    "foxglove.Grid": () => onGrid(topic, message),
    "foxglove.LaserScan": () => { state.scan = message; },
    "foxglove.PoseInFrame": () => { state.poses[topic] = { ...poseOf(message.pose), frame: message.frame_id }; },
    "foxglove.PosesInFrame": () => onPoses(topic, message),
    "foxglove.FrameTransform": () => {
      state.transforms[message.child_frame_id] = {
        parent: message.parent_frame_id, x: message.translation.x, y: message.translation.y,
        theta: yawOf(message.rotation) };
    },
    "foxglove.SceneUpdate": () => { for (const e of message.entities) state.scenes[e.id] = e; },
    "foxglove.Log": () => addLog(message),
    "polarslam.ProcessStatus": () => { state.processes[message.name + "@" + message.host + ":" + message.pid] = message; updateTable(); },
  };
  if (handlers[schema]) handlers[schema]();
  state.dirty = true;
}

function onGrid(topic, grid) {
  const bytes = Uint8Array.from(atob(grid.data), (c) => c.charCodeAt(0));
  const columns = grid.column_count, rows = Math.floor(bytes.length / grid.row_stride);
  const image = document.createElement("canvas");
  image.width = columns; image.height = rows;
  const g = image.getContext("2d");
  const pixels = g.createImageData(columns, rows);
  for (let row = 0; row < rows; ++row) {
    for (let col = 0; col < columns; ++col) {
      const value = (bytes[row * grid.row_stride + col * grid.cell_stride] << 24) >> 24;  // int8
      const at = ((rows - 1 - row) * columns + col) * 4;  // row 0 is the lowest y: bottom of the image
      if (value < 0) continue;  // unknown: transparent
      const grey = Math.round(255 * (1 - value / 100));
      pixels.data[at] = pixels.data[at + 1] = pixels.data[at + 2] = grey;
      pixels.data[at + 3] = 255;
    }
  }
  g.putImageData(pixels, 0, 0);
  state.grids[topic] = { image, x0: grid.pose.position.x, y0: grid.pose.position.y,
    width: columns * grid.cell_size.x, height: rows * grid.cell_size.y };
}

function onPoses(topic, message) {
  const points = message.poses.map((p) => ({ x: p.position.x, y: p.position.y }));
  if (topic === state.metadata.path_topic) state.path = points;
  else if (topic.endsWith("/trajectory")) state.trajectories[topic.slice(0, -"/trajectory".length)] = points;
}

function addLog(message) {
  const item = document.createElement("li");
  item.className = "level" + message.level;
  item.textContent = new Date(message.timestamp.sec * 1000).toLocaleTimeString() + " " + message.message;
  const list = document.getElementById("log");
  list.prepend(item);
  while (list.children.length > 50) list.lastChild.remove();
}

function updateTable() {
  const body = document.querySelector("#processes tbody");
  body.replaceChildren();
  const rows = Object.values(state.processes).sort((a, b) => a.name.localeCompare(b.name));
  for (const p of rows) {
    const row = body.insertRow();
    const cells = [p.name, p.host + ":" + p.pid, p.state, p.messages_handled, p.messages_rejected,
      p.messages_dropped, p.cpu_percent.toFixed(1), p.rss_mb.toFixed(0)];
    for (const text of cells) row.insertCell().textContent = text;
    row.cells[2].className = p.state;
  }
}

function chosen(selectId, candidates, available) {
  const choice = document.getElementById(selectId).value;
  if (choice) return available[choice] ? choice : null;
  return candidates.find((t) => available[t]) || null;
}
function currentGrid() { return chosen("grid-source", listTopics("grid_topics", ""), state.grids); }
function currentPoseTopic() { return chosen("pose-source", listTopics("pose_topics", "").slice(0, 2), state.poses); }

/// The view fits the grid (or, before one arrives, the trajectories) with a margin.
function fitView() {
  let box = null;
  const extend = (x, y) => {
    if (!box) box = { x0: x, y0: y, x1: x, y1: y };
    box.x0 = Math.min(box.x0, x); box.y0 = Math.min(box.y0, y);
    box.x1 = Math.max(box.x1, x); box.y1 = Math.max(box.y1, y);
  };
  const grid = state.grids[currentGrid()];
  if (grid) {
    extend(grid.x0, grid.y0); extend(grid.x0 + grid.width, grid.y0 + grid.height);
  } else {
    for (const points of Object.values(state.trajectories)) for (const p of points) extend(p.x, p.y);
    for (const p of Object.values(state.poses)) extend(p.x, p.y);
  }
  if (!box) box = { x0: -5, y0: -5, x1: 5, y1: 5 };
  const width = Math.max(box.x1 - box.x0, 1), height = Math.max(box.y1 - box.y0, 1);
  const scale = 0.95 * Math.min(canvas.width / width, canvas.height / height);
  state.view = { scale, cx: (box.x0 + box.x1) / 2, cy: (box.y0 + box.y1) / 2 };
}

function toCanvas(x, y) {
  const v = state.view;
  return [canvas.width / 2 + (x - v.cx) * v.scale, canvas.height / 2 - (y - v.cy) * v.scale];
}
function toMap(px, py) {
  const v = state.view;
  return { x: v.cx + (px - canvas.width / 2) / v.scale, y: v.cy - (py - canvas.height / 2) / v.scale };
}

function polyline(points, colour, width, closed) {
  if (points.length < 2) return;
  ctx.beginPath();
  points.forEach((p, i) => { const [x, y] = toCanvas(p.x, p.y); if (i === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y); });
  if (closed) ctx.closePath();
  ctx.strokeStyle = colour; ctx.lineWidth = width; ctx.stroke();
}

function rgba(c) { return `rgba(${Math.round(c.r * 255)},${Math.round(c.g * 255)},${Math.round(c.b * 255)},${c.a})`; }

function drawScenes() {
  for (const entity of Object.values(state.scenes)) {
    for (const line of entity.lines) {
      const colour = rgba(line.color), width = Math.max(1, line.thickness * state.view.scale);
      if (line.type === 2) {
        for (let i = 0; i + 1 < line.points.length; i += 2) polyline([line.points[i], line.points[i + 1]], colour, width);
      } else {
        polyline(line.points, colour, width, line.type === 1);
      }
    }
    for (const sphere of entity.spheres) {
      const [x, y] = toCanvas(sphere.pose.position.x, sphere.pose.position.y);
      ctx.beginPath();
      ctx.arc(x, y, Math.max(2, sphere.size.x * state.view.scale / 2), 0, 2 * Math.PI);
      ctx.fillStyle = rgba(sphere.color); ctx.fill();
    }
  }
}

function drawRobot(pose, colour) {
  const [x, y] = toCanvas(pose.x, pose.y);
  const length = Math.max(12, 0.4 * state.view.scale);
  ctx.save();
  ctx.translate(x, y); ctx.rotate(-pose.theta);
  ctx.beginPath(); ctx.moveTo(length, 0); ctx.lineTo(-length / 2, length / 2.5); ctx.lineTo(-length / 2, -length / 2.5);
  ctx.closePath(); ctx.fillStyle = colour; ctx.fill();
  ctx.restore();
}

/// The scan in the map frame: robot pose (the chosen SLAM pose) ⊕ laser mount (/tf base_link→laser).
function drawScan() {
  const topic = currentPoseTopic();
  const mount = state.transforms[state.scan?.frame_id];
  if (!state.scan || !topic || !mount) return;
  const laser = compose(state.poses[topic], mount);
  const scan = state.scan, n = scan.ranges.length;
  const step = n > 1 ? (scan.end_angle - scan.start_angle) / (n - 1) : 0;
  ctx.fillStyle = COLOURS.SCAN;
  for (let i = 0; i < n; ++i) {
    const r = scan.ranges[i];
    if (!(r > 0)) continue;
    const a = laser.theta + scan.start_angle + i * step;
    const [x, y] = toCanvas(laser.x + r * Math.cos(a), laser.y + r * Math.sin(a));
    ctx.fillRect(x - 1.5, y - 1.5, 3, 3);
  }
}

function draw() {
  fitView();
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  const grid = state.grids[currentGrid()];
  if (grid) {
    const [x, y] = toCanvas(grid.x0, grid.y0 + grid.height);
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(grid.image, x, y, grid.width * state.view.scale, grid.height * state.view.scale);
  }
  drawScenes();
  const topics = listTopics("pose_topics", "SLAM_POSE,PSM_SLAM_POSE,GROUND_TRUTH");
  const colours = [COLOURS.SLAM, COLOURS.PSM, COLOURS.TRUTH];
  topics.forEach((t, i) => { if (state.trajectories[t]) polyline(state.trajectories[t], colours[i % 3], 2); });
  drawScan();
  polyline(state.path, COLOURS.PATH, 3);
  topics.forEach((t, i) => { if (state.poses[t]) drawRobot(state.poses[t], colours[i % 3]); });
  if (state.goal) {
    const [x, y] = toCanvas(state.goal.x, state.goal.y);
    ctx.beginPath(); ctx.arc(x, y, 7, 0, 2 * Math.PI); ctx.strokeStyle = COLOURS.PATH; ctx.lineWidth = 3; ctx.stroke();
  }
}

function frame() {
  if (state.dirty) { state.dirty = false; draw(); }
  requestAnimationFrame(frame);
}

const encoder = new TextEncoder();
function sendGoal(goal) {
  if (!state.canPublish || !state.socket || state.socket.readyState !== WebSocket.OPEN) return;
  if (state.goalChannel === null) {
    state.goalChannel = 1;
    state.socket.send(JSON.stringify({ op: "advertise", channels: [
      { id: state.goalChannel, topic: state.metadata.goal_topic, encoding: "json", schemaName: "polarslam.Goal" }] }));
  }
  const payload = encoder.encode(JSON.stringify({ x: goal.x, y: goal.y }));
  const frameBytes = new Uint8Array(5 + payload.length);
  frameBytes[0] = 1;
  new DataView(frameBytes.buffer).setUint32(1, state.goalChannel, true);
  frameBytes.set(payload, 5);
  state.socket.send(frameBytes);
  state.goal = goal;
  state.dirty = true;
}

canvas.addEventListener("click", (event) => {
  if (!state.view) return;
  const box = canvas.getBoundingClientRect();
  const px = (event.clientX - box.left) * canvas.width / box.width;
  const py = (event.clientY - box.top) * canvas.height / box.height;
  sendGoal(toMap(px, py));
});

connect();
requestAnimationFrame(frame);
