// Hostile and careless clients of the console's Foxglove server (npm `ws`,
// raw sockets where `ws` would not misbehave), for
// tests/system/foxglove/test_hostile_clients.cpp. Each scenario writes what
// it saw to --out as JSON; every wait is for an event (an answer, a status,
// a close), with a deadline only for what never happens.
//
//   node hostile_clients.cjs --scenario control --url ws://127.0.0.1:PORT --key HEX --out R.json
//     A takes control and drives the rig to running; B (no control) is
//     refused a start, then stops the rig; A releases; C takes control and
//     stops answering pings: B waits for control to be released and takes it.
//   node hostile_clients.cjs --scenario limits --url ... --max-clients N --out R.json
//     a cross-origin upgrade, an oversized message, a flood of requests
//     without reading, a frame sent a byte at a time, N+1 connections.
//   node hostile_clients.cjs --scenario flood-round --url ... --clients N --out R.json
//     N clients subscribe to everything, flood requests without reading, go.
//   node hostile_clients.cjs --scenario send --url ... --payloads FILE --out R.json
//     sends each line of FILE (console command JSON) and records the answers.
"use strict";
const fs = require("fs");
const net = require("net");
const path = require("path");
const vm = require("vm");
const WebSocket = require("ws");

const TIMEOUT_MS = 120000;  // a deadline for what never happens, on a loaded machine
const PROTOCOL = "foxglove.websocket.v1";
const COMMAND_TOPIC = "/rigctl/console/command";

function parseArgs(argv) {
  const args = {};
  for (let i = 2; i < argv.length; i += 2) args[argv[i].replace(/^--/, "").replace(/-([a-z])/g, (_, c) => c.toUpperCase())] = argv[i + 1];
  return args;
}

// The console page's own signing code (foxglove/console/www/signing.js), run with Node's WebCrypto.
function loadSigning() {
  const context = { TextEncoder, crypto: require("crypto").webcrypto, BigInt, Uint8Array, DataView, Array, Error };
  context.window = context;
  vm.createContext(context);
  const file = path.join(__dirname, "../../foxglove/console/www/signing.js");
  vm.runInContext(fs.readFileSync(file, "utf8"), context);
  return context.rigctl.signing;
}

function withDeadline(promise, what) {
  let timer;
  return Promise.race([promise, new Promise((_, reject) => { timer = setTimeout(() => reject(new Error("timed out: " + what)), TIMEOUT_MS); })])
    .finally(() => clearTimeout(timer));
}

// A console connection speaking the protocol by hand: subscribes to the
// console's answers, advertises the command topic, signs and sends commands.
class Console {
  constructor(url, sender, options = {}) {
    this.sender = sender;
    this.ws = new WebSocket(url, [PROTOCOL], options);
    this.answers = [];
    this.statuses = [];
    this.removed = [];
    this.waiters = [];
    this.sequence = 0;
    this.nextId = 1;
    this.ready = withDeadline(new Promise((resolve, reject) => {
      this.ws.on("error", reject);
      this.ws.on("message", (data, isBinary) => this.onMessage(data, isBinary, resolve));
    }), sender + " connects");
  }
  onMessage(data, isBinary, resolve) {
    if (isBinary) {
      if (data.readUInt8(0) === 1) this.answers.push(JSON.parse(data.subarray(13).toString("utf8")));
    } else {
      const m = JSON.parse(data.toString("utf8"));
      if (m.op === "status") this.statuses.push(m);
      if (m.op === "removeStatus") this.removed.push(...m.statusIds);
      if (m.op === "advertise") {
        const answers = m.channels.find((c) => c.topic === "/rigctl/console/answer");
        if (answers) {
          this.ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 1, channelId: answers.id }] }));
          this.ws.send(JSON.stringify({ op: "advertise", channels: [{ id: 1, topic: COMMAND_TOPIC, encoding: "json", schemaName: "c" }] }));
          resolve();
        }
      }
    }
    this.waiters = this.waiters.filter((w) => !w());
  }
  until(done, what) {
    return withDeadline(new Promise((resolve) => {
      const check = () => { if (done()) { resolve(); return true; } return false; };
      if (!check()) this.waiters.push(check);
    }), this.sender + ": " + what);
  }
  sendRaw(payload) {
    const body = Buffer.from(payload, "utf8");
    const frame = Buffer.alloc(5 + body.length);
    frame.writeUInt8(1, 0);
    frame.writeUInt32LE(1, 1);
    body.copy(frame, 5);
    this.ws.send(frame);
  }
  async command(signing, key, command, value = 0) {
    const now = BigInt(Date.now()) * 1000n;
    this.sequence = Math.max(this.sequence + 1, Number(now));
    const c = { version: 1, sender: this.sender, sequence: this.sequence, utime: Number(now), command, value };
    const id = this.nextId++;
    const tag = await signing.sign(key, c);
    const count = this.answers.length;
    this.sendRaw(JSON.stringify({ id, ...c, tag }));
    await this.until(() => this.answers.length > count, "answer to " + command);
    return this.answers[this.answers.length - 1];
  }
  state() {
    const s = this.statuses.filter((m) => m.id === "rig_state");
    const m = s.length ? /^rig state (\w+)/.exec(s[s.length - 1].message) : null;
    return m ? m[1] : "";
  }
  waitState(state) { return this.until(() => this.state() === state, "rig state " + state); }
  close() { this.ws.close(); }
}

async function controlScenario(args, result) {
  const signing = loadSigning();
  const a = new Console(args.url, "alice");
  const b = new Console(args.url, "bob");
  await Promise.all([a.ready, b.ready]);
  result.takeControl = await a.command(signing, args.key, "take_control");
  for (const [command, to] of [["reset", "off"], ["hydraulics_low", "hydraulics_low"], ["hydraulics_high", "hydraulics_high"],
                               ["arm", "armed"], ["start", "running"]]) {
    result[command] = await a.command(signing, args.key, command);
    await a.waitState(to);
  }
  result.controlStatus = a.statuses.filter((m) => m.id === "console_control").map((m) => m.message);
  result.bStart = await b.command(signing, args.key, "start");       // B does not hold control
  result.bStop = await b.command(signing, args.key, "stop");         // but may always stop
  await b.until(() => ["stopping", "hydraulics_high"].includes(b.state()), "the rig stopping");
  result.stateAfterStop = b.state();
  result.aRelease = await (async () => { const n = a.answers.length; a.sendRaw(JSON.stringify({ id: 99, command: "release_control" }));
    await a.until(() => a.answers.length > n, "release"); return a.answers[a.answers.length - 1]; })();
  // C takes control, then answers no ping (its socket keeps reading otherwise).
  const c = new Console(args.url, "carol", { autoPong: false });
  await c.ready;
  result.cTakeControl = await c.command(signing, args.key, "take_control");
  const removedBefore = b.removed.filter((id) => id === "console_control").length;
  await b.until(() => b.removed.filter((id) => id === "console_control").length > removedBefore, "carol's control released");
  result.bTakeControl = await b.command(signing, args.key, "take_control");
  result.cStartAfter = await c.command(signing, args.key, "start");  // carol's console watches now
  for (const k of [a, b, c]) k.close();
}

// The upgrade's HTTP status, or 101 when it succeeded (the socket is closed again).
function upgradeStatus(url, options = {}) {
  return withDeadline(new Promise((resolve) => {
    const ws = new WebSocket(url, [PROTOCOL], options);
    ws.on("unexpected-response", (req, res) => { resolve(res.statusCode); req.destroy(); });
    ws.on("open", () => { resolve(101); ws.close(); });
    ws.on("error", () => resolve(-1));
  }), "upgrade");
}

// How the server ended a connection: the close code and reason the client saw.
function closed(ws) {
  return withDeadline(new Promise((resolve) => ws.on("close", (code, reason) => resolve({ code, reason: reason.toString() }))), "close");
}

async function opened(url, options = {}) {
  const ws = new WebSocket(url, [PROTOCOL], options);
  await withDeadline(new Promise((resolve, reject) => { ws.on("open", resolve); ws.on("error", reject); }), "open");
  return ws;
}

// Requests sent without reading the answers, until the server closes us.
async function floodWithoutReading(url) {
  const ws = await opened(url);
  const end = closed(ws);
  ws._socket.pause();  // stop reading: the answers pile up on the server's side
  let sent = 0;
  let done = false;
  end.then(() => { done = true; });
  while (!done && sent < 200000) {
    for (let i = 0; i < 500; ++i) ws.send('{"op":"getParameters","id":"flood"}');
    sent += 500;
    await new Promise((r) => setImmediate(r));
    if (sent % 20000 === 0) ws._socket.resume(), ws._socket.pause();  // let 'close' in once in a while
  }
  ws._socket.resume();
  const how = await end;
  return { sent, ...how };
}

// A frame header announcing 100 bytes, then one byte a second: never completed.
function slowFrame(url) {
  const u = new URL(url);
  return withDeadline(new Promise((resolve) => {
    const key = Buffer.from("0123456789abcdef").toString("base64");
    const s = net.connect(Number(u.port), u.hostname, () => {
      s.write(`GET / HTTP/1.1\r\nHost: ${u.host}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n` +
              `Sec-WebSocket-Key: ${key}\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: ${PROTOCOL}\r\n\r\n`);
    });
    let upgraded = false, timer = null, bytes = 0;
    const started = Date.now();
    s.on("data", (d) => {
      if (upgraded || !d.toString("latin1").startsWith("HTTP/1.1 101")) return;
      upgraded = true;
      s.write(Buffer.from([0x81, 0x80 | 100, 1, 2, 3, 4]));  // text, masked, 100 bytes to come
      timer = setInterval(() => { s.write(Buffer.from([0x41])); bytes++; }, 1000);
    });
    s.on("close", () => { clearInterval(timer); resolve({ upgraded, bytesSent: bytes, closedAfterS: (Date.now() - started) / 1000 }); });
    s.on("error", () => {});
  }), "slow frame closed");
}

async function limitsScenario(args, result) {
  const host = new URL(args.url).host;
  result.crossOrigin = await upgradeStatus(args.url, { origin: "http://evil.example" });
  result.sameOrigin = await upgradeStatus(args.url, { origin: "http://" + host });
  result.reboundHost = await upgradeStatus(args.url, { headers: { Host: "evil.example:" + new URL(args.url).port } });
  const big = await opened(args.url);
  const bigEnd = closed(big);
  big.send("x".repeat(1 << 20));
  result.oversized = await bigEnd;
  result.flood = await floodWithoutReading(args.url);
  result.slowFrame = await slowFrame(args.url);
  // Fill every slot but the well-behaved client's, then one more.
  const extra = [];
  for (let i = 0; i < Number(args.maxClients) - 1; ++i) extra.push(await opened(args.url));
  result.pastTheLimit = await upgradeStatus(args.url);
  result.pastTheLimitBody = "";
  for (const ws of extra) ws.close();
  await Promise.all(extra.map(closed));
  result.afterClosing = await upgradeStatus(args.url);
}

// One round of the memory test: N clients subscribe to everything, flood
// requests without reading, and go; resolves once all are closed.
async function floodRound(args, result) {
  const n = Number(args.clients);
  const clients = [];
  for (let i = 0; i < n; ++i) clients.push(await opened(args.url));
  const ends = clients.map(closed);
  for (const ws of clients) {
    ws.on("message", () => {});
    ws.send(JSON.stringify({ op: "subscribe", subscriptions: Array.from({ length: 8 }, (_, k) => ({ id: k + 1, channelId: k + 1 })) }));
    ws._socket.pause();
    for (let i = 0; i < 20000; ++i) ws.send('{"op":"getParameters","id":"flood"}');
  }
  await new Promise((r) => setTimeout(r, 200));  // the requests on the wire (a deadline is not needed: the server drops us)
  for (const ws of clients) { ws._socket.resume(); ws.terminate(); }
  result.closes = (await Promise.all(ends)).length;
}

async function sendScenario(args, result) {
  const k = new Console(args.url, "replayer");
  await k.ready;
  result.answers = [];
  for (const line of fs.readFileSync(args.payloads, "utf8").split("\n").filter((l) => l.trim())) {
    const n = k.answers.length;
    k.sendRaw(line);
    await k.until(() => k.answers.length > n, "answer");
    result.answers.push(k.answers[k.answers.length - 1]);
  }
  k.close();
}

async function main() {
  const args = parseArgs(process.argv);
  const result = {};
  let code = 0;
  try {
    const scenarios = { control: controlScenario, limits: limitsScenario, "flood-round": floodRound, send: sendScenario };
    await scenarios[args.scenario](args, result);
  } catch (e) {
    result.error = String(e && e.stack || e);
    code = 1;
  }
  fs.writeFileSync(args.out, JSON.stringify(result, null, 2));
  console.log(code === 0 ? "done" : "failed: " + result.error);
  process.exit(code);
}

main();
