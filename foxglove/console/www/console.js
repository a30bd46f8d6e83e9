// The console's page: connects to the server it was loaded from, feeds the
// scope and the station panel, and sends signed commands (docs/console.md).
"use strict";

(() => {
  const $ = (id) => document.getElementById(id);
  const COMMANDS = ["reset", "hydraulics_low", "hydraulics_high", "arm", "start", "hold", "resume", "stop", "hydraulics_off",
                    "stop_at_block_end"];
  const COMMAND_TOPIC = "/rigctl/console/command";
  const scope = new rigctl.Scope($("scope"));
  const page = {
    station: null, safetyState: "", trips: new Map(), timing: null, driver: null, units: new Map(),
    holdsControl: false, lastSequence: 0, requestId: 0, lastSent: null, commandsOffered: false,
  };

  // --- telemetry -------------------------------------------------------------

  // Units from the schema's descriptions ("[m] ..."); "" when none.
  function unitsOf(channel) {
    if (!page.units.has(channel.id)) {
      const units = {};
      try {
        for (const [name, p] of Object.entries(JSON.parse(channel.schema).properties || {})) {
          const m = /^\[([^\]]+)\]/.exec(p.description || "");
          units[name] = m ? m[1] : "";
        }
      } catch (e) { /* a schema that does not parse: no units */ }
      page.units.set(channel.id, units);
    }
    return page.units.get(channel.id);
  }

  // The strip a channel goes in: the setpoint and its feedback share one
  // (the command message does not carry the setpoint's unit), the others
  // one per unit.
  // On a rig with several control channels each channel's demand and
  // feedback share a strip of their own (the station's demand pairs).
  function groupFor(name, units) {
    const demands = (page.station && page.station.demands) || [];
    const k = demands.findIndex((pair) => pair.includes(name));
    if (k >= 0) return k === 0 ? "demand" : "demand " + (k + 1);
    const scopeList = ((page.station && page.station.scope) || []).filter((n) => n);
    if (!demands.length && scopeList.length > 1 && (name === scopeList[0] || name === scopeList[1])) return "demand";
    return units[name] || "";
  }

  function addChannelToggle(name) {
    const scopeList = ((page.station && page.station.scope) || []).filter((n) => n);
    const on = scopeList.length ? scopeList.includes(name) : scope.selected.size < 4;
    if (on) scope.selected.add(name);
    const label = document.createElement("label");
    const box = document.createElement("input");
    box.type = "checkbox";
    box.checked = on;
    box.dataset.channel = name;
    box.onchange = () => (box.checked ? scope.selected.add(name) : scope.selected.delete(name));
    label.append(box, " " + name);
    $("channels").append(label);
  }

  // keep(name): the fields of the message to plot (default all numbers).
  function plot(channel, m, keep = () => true) {
    const units = unitsOf(channel);
    for (const [name, v] of Object.entries(m)) {
      if (name === "t" || name === "tick" || typeof v !== "number" || !keep(name)) continue;
      if (!scope.series.has(name)) {
        scope.add(name, groupFor(name, units), units[name] || "");
        addChannelToggle(name);
      }
      scope.series.get(name).push(m.t, v);
    }
    $("rig-time").textContent = "t = " + Number(m.t).toFixed(2) + " s";
  }

  function onState(m) {
    setSafetyState(m.safety_state);
    if (m.event) rigctl.station.addEvent(m);
  }

  function setSafetyState(state) {
    if (!state || state === page.safetyState) return;
    page.safetyState = state;
    $("safety-state").textContent = state;
    $("safety-state").dataset.state = state;
    rigctl.station.renderState(page.station, state);
    renderCommandButtons();
  }

  function onMessage(channel, m) {
    switch (channel.schemaName) {
      case "rigctl.Sample": case "rigctl.Command": plot(channel, m); break;
      // The further channels' demands (x_ref_2, ...); their feedbacks and
      // outputs come by their own names in Sample and Command.
      case "rigctl.Channels": plot(channel, m, (name) => !/^(measurement|output)_\d+$/.test(name)); break;
      case "rigctl.State": onState(m); break;
      case "rigctl.Timing": page.timing = m; rigctl.station.renderTiming(page.timing, page.driver); break;
      case "rigctl.DriverStatus": page.driver = m; rigctl.station.renderTiming(page.timing, page.driver); break;
      case "rigctl.ConsoleAnswer": showAnswer(m); break;
      case "rigctl.Procedure": rigctl.procedure.render(m); break;
    }
  }

  function onStatus(s) {
    if (s.id === "rig_state") {
      // "rig state holding (run running)": the state for a page that joins late.
      const m = /^rig state (\w+)/.exec(s.message);
      if (m) setSafetyState(m[1]);
    } else if (s.id === "console_control") {
      $("control").textContent = "control: " + s.message.replace(/^control held by /, "");
      $("control").className = "badge " + (page.holdsControl ? "mine" : "other");
    } else if (s.id && s.id.startsWith("trip:")) {
      page.trips.set(s.id, s.message);
      renderTrips();
    }
  }

  function onRemoveStatus(id) {
    if (id === "console_control") {
      page.holdsControl = false;
      $("control").textContent = "control: free";
      $("control").className = "badge";
      renderCommandButtons();
    } else if (page.trips.delete(id)) {
      renderTrips();
    }
  }

  function renderTrips() {
    rigctl.station.renderTrips(page.trips);
    rigctl.station.renderDetectors(page.station, page.trips);
  }

  // --- commands ---------------------------------------------------------------

  function renderCommandButtons() {
    const box = $("command-buttons");
    if (!box.children.length) {
      for (const c of COMMANDS) {
        const b = document.createElement("button");
        b.type = "button";
        b.textContent = c.replaceAll("_", " ");
        b.dataset.command = c;
        b.onclick = () => send(c);
        box.append(b);
      }
    }
    // Every command can be sent (the rig decides); those the state allows
    // now are marked, the others say why the rig would refuse them.
    const rules = rigctl.station.rules(page.station, page.safetyState);
    for (const b of box.children) {
      const r = rules[b.dataset.command];
      b.className = r && r.allowed ? "allowed" : "refused";
      b.title = r ? (r.allowed ? "\u2192 " + r.to : "refused now: " + r.refused) : "";
      b.disabled = !page.commandsOffered;
    }
    for (const id of ["take-control", "release-control", "send-setpoint"]) $(id).disabled = !page.commandsOffered;
  }

  // One line per command: "sent", then replaced by the rig's answer.
  function answerLine(text, reason, command, id) {
    const li = (id && document.querySelector(`#answers li[data-id="${id}"]`)) || document.createElement("li");
    if (id) li.dataset.id = String(id);
    li.textContent = text;
    li.dataset.reason = reason;
    li.dataset.command = command;
    li.className = reason === "accepted" ? "good" : reason === "pending" ? "muted" : "bad";
    if (!li.parentNode) $("answers").prepend(li);
    while ($("answers").children.length > 30) $("answers").lastChild.remove();
    return li;
  }

  function showAnswer(a) {
    if (a.command === "take_control" && a.accepted) page.holdsControl = true;
    if (a.command === "release_control" && a.accepted) page.holdsControl = false;
    answerLine("#" + a.id + " " + a.command + ": " + a.reason + (a.message ? " \u2014 " + a.message : ""), a.reason, a.command, a.id);
    $("control").className = "badge " + (page.holdsControl ? "mine" : $("control").textContent === "control: free" ? "" : "other");
  }

  // Signs and sends one command. opts.utimeOffsetUs dates it off the clock
  // (the tests' stale command); the sequence is max(last + 1, now in us), as
  // `rigctl cmd` makes it.
  async function send(command, value = 0, opts = {}) {
    if (!page.client || !page.client.open) return answerLine(command + ": not connected", "not_connected", command);
    const nowUs = Date.now() * 1000;
    const c = { version: 1, sender: $("sender").value.trim(), sequence: Math.max(page.lastSequence + 1, nowUs),
                utime: nowUs + (opts.utimeOffsetUs || 0), command, value: Number(value) };
    page.lastSequence = c.sequence;
    try {
      c.tag = await rigctl.signing.sign($("key").value, c);
    } catch (e) {
      return answerLine(command + ": not sent: " + e.message, "not_signed", command);
    }
    c.id = ++page.requestId;
    page.lastSent = c;
    page.client.publish(c);
    return answerLine("#" + c.id + " " + command + ": sent", "pending", command, c.id);
  }

  // Sends the last signed command again, byte for byte (a captured command
  // replayed): the rig must refuse it as replayed.
  function replayLast() {
    if (!page.lastSent) return;
    const c = Object.assign({}, page.lastSent, { id: ++page.requestId });
    page.client.publish(c);
    answerLine("#" + c.id + " " + c.command + " (again): sent", "pending", c.command, c.id);
  }

  function release() {
    if (!page.client || !page.client.open) return;
    const id = ++page.requestId;
    page.client.publish({ id, command: "release_control" });
    answerLine("#" + id + " release_control: sent", "pending", "release_control", id);
  }

  // --- wiring -----------------------------------------------------------------

  function connect() {
    const url = (location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/";
    page.client = new rigctl.FoxgloveClient(url, {
      open: () => { $("connection").textContent = "connected"; $("connection").className = "badge on"; },
      close: () => {
        $("connection").textContent = "disconnected";
        $("connection").className = "badge off";
        page.commandsOffered = false;
        renderCommandButtons();
      },
      serverInfo: (info) => {
        try { page.station = JSON.parse((info.metadata || {})["rigctl.station"] || "null"); } catch (e) { page.station = null; }
        $("rig").textContent = info.name || "rigctl";
        page.commandsOffered = !!(page.station && page.station.commands) && (info.capabilities || []).includes("clientPublish");
        $("commands-off").hidden = page.commandsOffered;
        if (page.commandsOffered) page.client.advertise(COMMAND_TOPIC, "rigctl.ConsoleCommand");
        if (!$("sender").value && page.station && page.station.senderHint) $("sender").value = page.station.senderHint;
        rigctl.station.renderState(page.station, page.safetyState);
        renderTrips();
        renderCommandButtons();
      },
      status: onStatus,
      removeStatus: onRemoveStatus,
      message: onMessage,
    });
  }

  function frame() {
    scope.draw();
    let n = 0;
    for (const s of scope.series.values()) n = Math.max(n, s.received);
    $("scope-stats").textContent = n + " samples";
    $("scope-stats").dataset.samples = String(n);
    requestAnimationFrame(frame);
  }

  $("pause").onclick = () => {
    scope.setPaused(!scope.paused);
    $("pause").textContent = scope.paused ? "Resume" : "Pause";
  };
  $("window").oninput = () => {
    scope.windowS = Number($("window").value);
    $("window-value").textContent = scope.windowS + " s";
  };
  $("take-control").onclick = () => send("take_control");
  $("release-control").onclick = release;
  $("send-setpoint").onclick = () => send("setpoint", $("setpoint").value);
  // Hold and stop from the keyboard, wherever the focus is but a text field.
  document.addEventListener("keydown", (e) => {
    if (e.target instanceof HTMLInputElement || e.ctrlKey || e.altKey || e.metaKey) return;
    if (e.key === "h" || e.key === "H") { e.preventDefault(); send("hold"); }
    if (e.key === "s" || e.key === "S") { e.preventDefault(); send("stop"); }
  });
  renderCommandButtons();
  connect();
  requestAnimationFrame(frame);
  // For the browser test and the curious: the same functions the buttons use.
  window.rigctlConsole = { send, replayLast, release, scope, disconnect: () => page.client.ws.close() };
})();
