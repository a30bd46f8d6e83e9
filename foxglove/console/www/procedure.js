// The procedure panel: a test procedure's step, counts, time left,
// compensation error, the peak-valley detector's trend and the
// pseudo-damage, from RIGCTL_PROCEDURE (rigctl.Procedure; docs/procedures.md).
// Hidden until the first message: a run without a procedure shows nothing.
"use strict";
window.rigctl = window.rigctl || {};

rigctl.procedure = (() => {
  const $ = (id) => document.getElementById(id);
  const TREND_POINTS = 60;  // the last peak-valley changes shown as a sparkline
  const trend = [];
  let lastCycles = -1;

  function duration(s) {
    if (!(s >= 0)) return "-";
    const h = Math.floor(s / 3600), m = Math.floor((s % 3600) / 60), sec = Math.floor(s % 60);
    return (h ? h + " h " : "") + (h || m ? m + " min " : "") + sec + " s";
  }
  const pct = (f) => (Number.isFinite(f) ? (100 * f).toFixed(2) + " %" : "-");

  // The compensation's last error: amplitude and phase for a sine, the
  // peak and valley for peak_valley programs.
  function compensationText(m) {
    if (m.step_kind === "blocks" || (m.peak_error || m.valley_error)) {
      return "peak " + pct(m.peak_error) + ", valley " + pct(m.valley_error);
    }
    return "amplitude " + pct(m.amplitude_error) + ", phase " + (m.phase_error * 180 / Math.PI).toFixed(2) + " deg";
  }

  function sparkline(values) {
    if (!values.length) return "-";
    const bars = "\u2581\u2582\u2583\u2584\u2585\u2586\u2587\u2588";
    const hi = Math.max(...values.map(Math.abs), 1e-9);
    return values.map((v) => bars[Math.min(7, Math.floor((Math.abs(v) / hi) * 7.999))]).join("");
  }

  function set(id, value) {
    $(id).textContent = value;
  }

  function render(m) {
    $("procedure-panel").hidden = false;
    if (m.total_cycles !== lastCycles) {
      lastCycles = m.total_cycles;
      trend.push(m.pv_change || 0);
      while (trend.length > TREND_POINTS) trend.shift();
    }
    set("procedure-step", m.step_name + " (" + m.step_kind + ", " + m.phase + ")");
    set("procedure-cycles", m.total_cycles + " of " + m.programmed_cycles + " (step " + m.step_cycles +
        (m.step_kind === "blocks" ? ", row " + m.row + " cycle " + m.row_cycles + ", pass " + m.pass : "") + ")");
    $("procedure-cycles").dataset.total = String(m.total_cycles);
    set("procedure-time-left", duration(m.time_left));
    set("procedure-compensation", compensationText(m));
    set("procedure-pv", pct(m.pv_change) + " " + sparkline(trend));
    set("procedure-damage", Number(m.damage).toPrecision(4));
    set("procedure-request", m.stop_at_block_end ? "stop at the end of the block" : "-");
    $("procedure-request").dataset.stopAtBlockEnd = String(!!m.stop_at_block_end);
  }

  return { render };
})();
