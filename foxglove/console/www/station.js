// The station panel: the rig state and the commands it allows now (from the
// server's copy of the state machine's table), every limit detector with
// its threshold, action and state, the active trips, the tail of the event
// log, loop timing and driver status.
"use strict";
window.rigctl = window.rigctl || {};

rigctl.station = (() => {
  const $ = (id) => document.getElementById(id);
  // The event a detector kind raises when it trips (rt/telemetry_record.hpp).
  const EVENT_OF_KIND = {
    range: "limit_tripped", rate: "rate_limit", tracking_error: "tracking_error",
    valve_saturation: "valve_saturated", sample_age: "sample_stale", overruns: "overruns",
    open_circuit: "open_circuit", stuck: "sensor_stuck",
  };
  const MAX_EVENTS = 40;

  function text(tag, content, className) {
    const e = document.createElement(tag);
    e.textContent = content;
    if (className) e.className = className;
    return e;
  }

  // {command: rule} of the state, from serverInfo's station table.
  function rules(station, state) {
    return (station && station.states && station.states[state]) || {};
  }

  function renderState(station, state) {
    $("station-state").textContent = state || "?";
    $("station-state").dataset.state = state || "";
    const allowed = Object.entries(rules(station, state)).filter(([, r]) => r.allowed);
    $("allowed").textContent = allowed.length ? allowed.map(([c, r]) => c + " \u2192 " + r.to).join(", ") : "-";
  }

  // trips: Map status id -> message. A detector is tripped when an active
  // trip is of its kind's event and names its channel.
  function renderDetectors(station, trips) {
    const body = $("detectors").tBodies[0];
    body.replaceChildren();
    for (const d of (station && station.detectors) || []) {
      const id = "trip:" + EVENT_OF_KIND[d.kind] + ":";
      const tripped = [...trips.keys()].some((t) => t === id + d.channel || (t.startsWith(id) && !d.channel));
      const row = document.createElement("tr");
      row.className = tripped ? "tripped" : "";
      for (const v of [d.name, d.channel, d.threshold, d.action]) row.append(text("td", v));
      row.append(text("td", tripped ? "TRIPPED" : "ok", tripped ? "bad" : "good"));
      body.append(row);
    }
  }

  function renderTrips(trips) {
    const list = $("trips");
    list.replaceChildren();
    if (trips.size === 0) list.append(text("li", "none", "muted"));
    for (const message of trips.values()) list.append(text("li", message, "bad"));
  }

  function addEvent(m) {
    const list = $("events");
    const line = "t=" + Number(m.t).toFixed(3) + " " + m.safety_state + " " + m.event + (m.message ? ": " + m.message : "");
    const cls = m.event === "command_rejected" ? "warn" : /trip|invalid|stale|open_circuit|stuck|saturated|rate_limit|tracking/.test(m.event) ? "bad" : "";
    list.prepend(text("li", line, cls));
    while (list.children.length > MAX_EVENTS) list.lastChild.remove();
  }

  function ms(seconds) { return (1000 * seconds).toFixed(3) + " ms"; }

  function renderTiming(timing, driver) {
    const body = $("timing").tBodies[0];
    body.replaceChildren();
    const rows = [];
    if (timing) {
      rows.push(["wake-up latency p99", ms(timing.wakeup_latency_p99)], ["compute p99", ms(timing.compute_p99)],
                ["overruns", timing.overruns + " (missed ticks " + timing.missed_ticks + ")"],
                ["dropped records", String(timing.dropped_records)]);
    }
    if (driver) {
      rows.push(["driver", driver.driver]);
      for (const [name, value] of Object.entries(driver.counters || {})) rows.push(["  " + name, String(value)]);
      if (driver.events && driver.events.length) rows.push(["driver events", driver.events.join("; ")]);
    }
    for (const [k, v] of rows) {
      const row = document.createElement("tr");
      row.append(text("th", k), text("td", v));
      body.append(row);
    }
  }

  return { rules, renderState, renderDetectors, renderTrips, addEvent, renderTiming };
})();
