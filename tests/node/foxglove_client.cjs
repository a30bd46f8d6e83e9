// A real Foxglove client for rigctl's tests: @foxglove/ws-protocol's
// FoxgloveClient over the `ws` package (Node 20 has no global WebSocket).
// It connects (retrying while the server is not up yet), checks the
// subprotocol the server chose, subscribes to a topic, validates every
// message against the schema the server advertised (ajv), and writes what it
// saw as JSON for the C++ test to judge.
//
//   node foxglove_client.cjs --url ws://127.0.0.1:PORT --subprotocol foxglove.websocket.v1
//        --topic RIGCTL_SAMPLE --count N --out RESULT.json
//        [--subscribe-all] [--stall] [--until-status PREFIX] [--until-removed PREFIX]
//        [--probe-read-only] [--connect-timeout-s 120]
//
// --stall: after the first message, stop reading the socket (a client that
// hangs); the script then waits for the server to close the connection.
// --until-status PREFIX: done once a status whose id starts with PREFIX came.
// --until-removed PREFIX: done once such a status was removed (removeStatus).
// --probe-read-only: also try to set a parameter and to publish (advertise a
// client channel); the answers go into the result.
// Prints "started", "connected", "subscribed" as it gets there.
"use strict";
const fs = require("fs");
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");
const Ajv = require("ajv");

function parseArgs(argv) {
  const args = { count: 0, connectTimeoutS: 120, subscribeAll: false, stall: false, untilStatus: "", untilRemoved: "", probeReadOnly: false };
  for (let i = 2; i < argv.length; i++) {
    const key = argv[i];
    const next = () => argv[++i];
    if (key === "--url") args.url = next();
    else if (key === "--subprotocol") args.subprotocol = next();
    else if (key === "--topic") args.topic = next();
    else if (key === "--count") args.count = Number(next());
    else if (key === "--out") args.out = next();
    else if (key === "--subscribe-all") args.subscribeAll = true;
    else if (key === "--stall") args.stall = true;
    else if (key === "--until-status") args.untilStatus = next();
    else if (key === "--until-removed") args.untilRemoved = next();
    else if (key === "--probe-read-only") args.probeReadOnly = true;
    else if (key === "--connect-timeout-s") args.connectTimeoutS = Number(next());
    else throw new Error(`unknown argument ${key}`);
  }
  for (const required of ["url", "subprotocol", "topic", "out"]) {
    if (!args[required]) throw new Error(`--${required} is required`);
  }
  return args;
}

const args = parseArgs(process.argv);
const result = {
  subprotocol: null, serverInfo: null, channels: [], schemaFields: [], received: 0, firstTick: null,
  lastTick: null, gaps: 0, outOfOrder: 0, invalid: 0, validationErrors: [], timeOffsetSpreadNs: 0,
  statuses: [], removedStatuses: [], messages: [], parameters: null, parametersAfterSet: null, closed: false,
  errors: [],
};
const ajv = new Ajv({ allErrors: true });
const validators = new Map();  // channel id -> validate function
let targetChannel = null;
let minOffset = null, maxOffset = null;
let finished = false;

function finish(code) {
  if (finished) return;
  finished = true;
  result.timeOffsetSpreadNs = minOffset === null ? 0 : Number(maxOffset - minOffset);
  fs.writeFileSync(args.out, JSON.stringify(result));
  process.exit(code);
}

function onSample(channelId, message) {
  const text = new TextDecoder().decode(message.data);
  const value = JSON.parse(text);
  const validate = validators.get(channelId);
  if (!validate(value)) {
    result.invalid++;
    if (result.validationErrors.length < 5) result.validationErrors.push(ajv.errorsText(validate.errors));
  }
  if (channelId !== targetChannel) return;
  if (result.lastTick !== null) {
    if (value.tick <= result.lastTick) result.outOfOrder++;
    else if (value.tick !== result.lastTick + 1) result.gaps++;
  }
  if (result.firstTick === null) result.firstTick = value.tick;
  result.lastTick = value.tick;
  result.received++;
  result.messages.push(value);
  // The message's time stamp is the sample's: start of the run + t.
  const offset = message.timestamp - BigInt(Math.round(value.t * 1e9));
  if (minOffset === null || offset < minOffset) minOffset = offset;
  if (maxOffset === null || offset > maxOffset) maxOffset = offset;
}

function connect(deadline) {
  const ws = new WebSocket(args.url, [args.subprotocol]);
  const client = new FoxgloveClient({ ws });
  let opened = false;
  // FoxgloveClient numbers subscriptions itself: remember which is which.
  const subscriptionChannel = new Map();
  const subscribe = client.subscribe.bind(client);
  client.subscribe = (channelId) => {
    const id = subscribe(channelId);
    subscriptionChannel.set(id, channelId);
    return id;
  };
  client.on("open", () => {
    opened = true;
    result.subprotocol = ws.protocol;
    console.log("connected");
  });
  client.on("serverInfo", (info) => {
    result.serverInfo = info;
    if (info.capabilities.includes("parameters")) client.getParameters([], "all");
    if (args.probeReadOnly) {
      client.setParameters([{ name: "controller.kp", value: 1.0 }], "set");
      client.advertise({ topic: "/hack", encoding: "json", schemaName: "x" });
    }
  });
  client.on("parameterValues", (p) => {
    if (p.id === "set") result.parametersAfterSet = p.parameters;
    else result.parameters = p.parameters;
  });
  client.on("status", (s) => {
    result.statuses.push(s);
    if (args.untilStatus && s.id && s.id.startsWith(args.untilStatus)) finish(0);
  });
  client.on("removeStatus", (r) => {
    result.removedStatuses.push(...r.statusIds);
    if (args.untilRemoved && r.statusIds.some((id) => id.startsWith(args.untilRemoved))) finish(0);
  });
  client.on("advertise", (channels) => {
    for (const c of channels) {
      result.channels.push({ id: c.id, topic: c.topic, encoding: c.encoding, schemaName: c.schemaName,
                             schemaEncoding: c.schemaEncoding });
      validators.set(c.id, ajv.compile(JSON.parse(c.schema)));
      if (c.topic === args.topic) {
        targetChannel = c.id;
        result.schemaFields = Object.keys(JSON.parse(c.schema).properties);
      }
      if (c.topic === args.topic || args.subscribeAll) {
        client.subscribe(c.id);
        if (c.topic === args.topic) console.log("subscribed");
      }
    }
  });
  client.on("message", (m) => {
    onSample(subscriptionChannel.get(m.subscriptionId), m);
    if (args.stall) {
      ws.pause();  // stop reading the socket: the server's buffers fill
      // A socket that is not read keeps no event loop alive: this does, until the test stops us.
      setInterval(() => {}, 1000);
      args.stall = false;
      console.log("stalled");
    }
    if (args.count > 0 && result.received >= args.count && !args.untilStatus && !args.untilRemoved) finish(0);
  });
  client.on("error", (e) => {
    if (!opened && Date.now() < deadline) return;  // the server is not up yet
    result.errors.push(String(e && e.message ? e.message : e));
  });
  client.on("close", () => {
    if (!opened && Date.now() < deadline) {
      setTimeout(() => connect(deadline), 100);
      return;
    }
    result.closed = true;
    finish(opened ? 0 : 1);
  });
}

console.log("started");
connect(Date.now() + args.connectTimeoutS * 1000);
