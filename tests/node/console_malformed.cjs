// A raw Foxglove client (npm ws) that sends the console's server what a
// broken or hostile client would: text that is not JSON, binary frames of an
// unknown opcode or for a channel never advertised, a channel on another
// topic, and unreadable commands on the console's topic. Resolves with the
// statuses and answers the server sent back.
"use strict";
const WebSocket = require("ws");

const TIMEOUT_MS = 120000;

function frame(channel, text) {
  const payload = Buffer.from(text, "utf8");
  const out = Buffer.alloc(5 + payload.length);
  out.writeUInt8(1, 0);
  out.writeUInt32LE(channel, 1);
  payload.copy(out, 5);
  return out;
}

function malformedClient(url) {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(url, ["foxglove.websocket.v1"]);
    const seen = { statuses: [], answers: [] };
    const timer = setTimeout(() => reject(new Error("malformed client: no answers within the time-out")), TIMEOUT_MS);
    const COMMANDS = 3;  // unreadable commands sent on the console's topic
    ws.on("message", (data, isBinary) => {
      if (isBinary) {
        if (data.readUInt8(0) !== 1) return;
        seen.answers.push(JSON.parse(data.subarray(13).toString("utf8")));
        if (seen.answers.length === COMMANDS) {
          clearTimeout(timer);
          ws.close();
          resolve(seen);
        }
        return;
      }
      const m = JSON.parse(data.toString("utf8"));
      if (m.op === "status") seen.statuses.push(m.id);
      if (m.op !== "advertise") return;
      const answers = m.channels.find((c) => c.topic === "/rigctl/console/answer");
      if (!answers) return;
      ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 1, channelId: answers.id }] }));
      ws.send("{not json");
      ws.send(Buffer.from([7, 1, 2]));                    // an unknown opcode
      ws.send(frame(9, "{}"));                            // a channel never advertised
      ws.send(JSON.stringify({ op: "advertise", channels: [{ id: 2, topic: "/hack", encoding: "json", schemaName: "x" }] }));
      ws.send(JSON.stringify({ op: "advertise", channels: [{ id: 1, topic: "/rigctl/console/command", encoding: "json", schemaName: "c" }] }));
      ws.send(frame(1, "not json"));
      ws.send(frame(1, JSON.stringify({ id: 2, command: "hold", sender: "mallory" })));  // no sequence, utime, tag
      ws.send(frame(1, JSON.stringify({ id: 3, command: "hold", sender: "mallory", sequence: 1, utime: 1, tag: "zz" })));
    });
    ws.on("error", (e) => { clearTimeout(timer); reject(e); });
  });
}

module.exports = { malformedClient };
