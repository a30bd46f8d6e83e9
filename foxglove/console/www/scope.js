// The scope: strip charts on a canvas, one strip per unit (demand and
// feedback together, valve commands, pressures). Every sample is kept for
// the last 60 s (the record); drawing decimates to one min/max pair per
// pixel column, so a 60 s window at 400 Hz costs the same to draw as 1 s
// and the page never falls behind the telemetry.
"use strict";
window.rigctl = window.rigctl || {};

rigctl.Series = class {
  // 2^15 points: 60 s at 400 Hz (24000) with room to spare.
  // group: the strip it is drawn in (its unit, or "demand" for the setpoint
  // and its feedback); unit: its SI unit ("" when the message does not say).
  constructor(name, group, unit, capacity = 32768) {
    this.name = name;
    this.group = group;
    this.unit = unit;
    this.t = new Float64Array(capacity);
    this.v = new Float64Array(capacity);
    this.head = 0;   // next write
    this.count = 0;
    this.received = 0;
  }
  push(t, v) {
    this.t[this.head] = t;
    this.v[this.head] = v;
    this.head = (this.head + 1) % this.t.length;
    this.count = Math.min(this.count + 1, this.t.length);
    this.received += 1;
  }
  // Calls f(t, v) for every stored point with t >= from, oldest first.
  forEachSince(from, f) {
    const n = this.t.length;
    for (let k = 0; k < this.count; ++k) {
      const i = (this.head - this.count + k + n) % n;
      if (this.t[i] >= from) f(this.t[i], this.v[i]);
    }
  }
  last() { return this.count ? this.t[(this.head - 1 + this.t.length) % this.t.length] : NaN; }
};

rigctl.Scope = class {
  constructor(canvas) {
    this.canvas = canvas;
    this.series = new Map();     // name -> Series
    this.selected = new Set();
    this.windowS = 10;
    this.paused = false;
    this.frozenEnd = NaN;        // the end of the window while paused
    this.drawn = 0;              // frames drawn (the test watches it)
    this.colors = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"];
  }

  add(name, group, unit) {
    if (!this.series.has(name)) this.series.set(name, new rigctl.Series(name, group, unit));
    return this.series.get(name);
  }

  setPaused(paused) {
    this.paused = paused;
    this.frozenEnd = paused ? this.end() : NaN;
  }

  end() {
    let end = -Infinity;
    for (const s of this.series.values()) end = Math.max(end, s.last());
    return end;
  }

  strips() {
    const byUnit = new Map();
    for (const name of this.selected) {
      const s = this.series.get(name);
      if (!s) continue;
      if (!byUnit.has(s.group)) byUnit.set(s.group, []);
      byUnit.get(s.group).push(s);
    }
    // Each strip labelled with the unit its channels name.
    return [...byUnit.values()].map((list) => [(list.find((s) => s.unit) || { unit: "" }).unit, list]);
  }

  draw() {
    const ctx = this.canvas.getContext("2d");
    const dpr = window.devicePixelRatio || 1;
    const width = this.canvas.clientWidth, height = this.canvas.clientHeight;
    if (this.canvas.width !== Math.round(width * dpr)) this.canvas.width = Math.round(width * dpr);
    if (this.canvas.height !== Math.round(height * dpr)) this.canvas.height = Math.round(height * dpr);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, width, height);
    const end = this.paused ? this.frozenEnd : this.end();
    const strips = this.strips();
    if (!isFinite(end) || strips.length === 0) return;
    const start = end - this.windowS;
    const stripHeight = height / strips.length;
    strips.forEach(([unit, list], k) => this.drawStrip(ctx, unit, list, start, end, k * stripHeight, width, stripHeight));
    this.drawn += 1;
  }

  drawStrip(ctx, unit, list, start, end, top, width, height) {
    const left = 64, plotWidth = width - left - 8, pad = 14;
    const columns = list.map((s) => this.decimate(s, start, end, plotWidth));
    let lo = Infinity, hi = -Infinity;
    for (const c of columns) for (let i = 0; i < c.min.length; ++i) {
      if (c.min[i] < lo) lo = c.min[i];
      if (c.max[i] > hi) hi = c.max[i];
    }
    if (!isFinite(lo)) return;
    if (hi - lo < 1e-12) { hi += 0.5 * (Math.abs(hi) + 1e-9); lo -= 0.5 * (Math.abs(lo) + 1e-9); }
    const y = (v) => top + pad + (height - 2 * pad) * (1 - (v - lo) / (hi - lo));
    ctx.strokeStyle = "#ccc";
    ctx.strokeRect(left, top + pad, plotWidth, height - 2 * pad);
    ctx.fillStyle = "#444";
    ctx.font = "11px sans-serif";
    ctx.fillText(hi.toPrecision(4), 2, top + pad + 8);
    ctx.fillText(lo.toPrecision(4), 2, top + height - pad);
    ctx.fillText(unit ? "[" + unit + "]" : "", 2, top + height / 2);
    list.forEach((s, n) => {
      const color = this.colors[[...this.selected].indexOf(s.name) % this.colors.length];
      ctx.strokeStyle = color;
      ctx.fillStyle = color;
      ctx.fillText(s.name, left + 6 + 70 * n, top + pad - 3);
      const c = columns[n];
      ctx.beginPath();
      for (let x = 0; x < c.min.length; ++x) {
        if (!isFinite(c.min[x])) continue;
        ctx.moveTo(left + x + 0.5, y(c.max[x]) - 0.5);
        ctx.lineTo(left + x + 0.5, y(c.min[x]) + 0.5);
      }
      ctx.stroke();
    });
  }

  // One min/max pair per pixel column.
  decimate(series, start, end, columns) {
    const n = Math.max(1, Math.floor(columns));
    const min = new Float64Array(n).fill(Infinity), max = new Float64Array(n).fill(-Infinity);
    series.forEachSince(start, (t, v) => {
      if (t > end || !isFinite(v)) return;
      const x = Math.min(n - 1, Math.floor(((t - start) / (end - start)) * n));
      if (v < min[x]) min[x] = v;
      if (v > max[x]) max[x] = v;
    });
    return { min, max };
  }
};
