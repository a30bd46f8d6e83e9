// A minimal Foxglove WebSocket protocol client (foxglove.websocket.v1) for
// the console: subscribes to every channel the server advertises, decodes
// JSON messages, keeps statuses, and publishes on one client channel.
"use strict";
window.rigctl = window.rigctl || {};

rigctl.FoxgloveClient = class {
  constructor(url, handlers) {
    this.handlers = handlers;
    this.channels = new Map();       // channel id -> channel
    this.subscriptions = new Map();  // subscription id -> channel
    this.nextSubscription = 1;
    this.clientChannel = null;       // our advertised channel id
    this.decoder = new TextDecoder();
    this.encoder = new TextEncoder();
    this.ws = new WebSocket(url, ["foxglove.websocket.v1"]);
    this.ws.binaryType = "arraybuffer";
    this.ws.onopen = () => handlers.open();
    this.ws.onclose = () => handlers.close();
    this.ws.onmessage = (e) => (typeof e.data === "string" ? this.onText(e.data) : this.onBinary(e.data));
  }

  onText(text) {
    const m = JSON.parse(text);
    if (m.op === "serverInfo") {
      this.handlers.serverInfo(m);
    } else if (m.op === "advertise") {
      const subscribe = [];
      for (const c of m.channels) {
        this.channels.set(c.id, c);
        const id = this.nextSubscription++;
        this.subscriptions.set(id, c);
        subscribe.push({ id, channelId: c.id });
      }
      this.ws.send(JSON.stringify({ op: "subscribe", subscriptions: subscribe }));
    } else if (m.op === "status") {
      this.handlers.status(m);
    } else if (m.op === "removeStatus") {
      for (const id of m.statusIds) this.handlers.removeStatus(id);
    }
  }

  onBinary(buffer) {
    const view = new DataView(buffer);
    if (buffer.byteLength < 13 || view.getUint8(0) !== 1) return;
    const channel = this.subscriptions.get(view.getUint32(1, true));
    if (!channel) return;
    const message = JSON.parse(this.decoder.decode(new Uint8Array(buffer, 13)));
    this.handlers.message(channel, message);
  }

  // Client publishing (the server offers it only for the console's topic).
  advertise(topic, schemaName) {
    this.clientChannel = 1;
    this.ws.send(JSON.stringify({ op: "advertise", channels: [{ id: 1, topic, encoding: "json", schemaName }] }));
  }

  publish(object) {
    const payload = this.encoder.encode(JSON.stringify(object));
    const frame = new Uint8Array(5 + payload.length);
    const view = new DataView(frame.buffer);
    view.setUint8(0, 1);
    view.setUint32(1, this.clientChannel, true);
    frame.set(payload, 5);
    this.ws.send(frame);
  }

  get open() { return this.ws.readyState === WebSocket.OPEN; }
};
