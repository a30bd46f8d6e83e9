#!/usr/bin/python3
"""Plots a rig's parameter trends (rigctl health report --json) as one PNG.

    tools/plots/plot_health.py TRENDS.json --out health.png [--parameters R_l,beta]

One panel per parameter (default: those with alarms or a stands_for, then
the rest, at most eight): the calibrated value per window, +-2 standard
deviations (the chart's: the fit's widened by the reference's scatter),
the reference (dashed), alarms (red: raised, orange: since when), time in
hours from the first window. Uses Debian's python3-matplotlib and numpy.
"""
import argparse
import json

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def chosen(parameters, names):
    if names:
        wanted = names.split(",")
        return [p for p in parameters if p["name"] in wanted]
    ranked = sorted(parameters, key=lambda p: (not p["alarms"], not p["stands_for"]))
    return [p for p in ranked if p["points"]][:8]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("trends")
    ap.add_argument("--out", required=True)
    ap.add_argument("--parameters", default="")
    args = ap.parse_args()
    with open(args.trends, encoding="utf-8") as f:
        h = json.load(f)
    panels = chosen(h["parameters"], args.parameters)
    if not panels:
        raise SystemExit("plot_health: no trended parameter in " + args.trends)
    t_first = min(p["points"][0][0] for p in panels)
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.2 * len(panels)), sharex=True, squeeze=False)
    for ax, p in zip(axes[:, 0], panels):
        pts = np.array(p["points"])
        t = (pts[:, 0] - t_first) / 3600.0
        value, sigma = pts[:, 1], pts[:, 3]
        scale = abs(p["reference"]) if p["reference"] else 1.0
        ax.fill_between(t, (value - 2 * sigma) / scale, (value + 2 * sigma) / scale, color="#c6dbef", label="±2 sd")
        ax.plot(t, value / scale, color="#08519c", lw=1.2, label="calibrated")
        ax.axhline(1.0, color="#555", ls="--", lw=0.8, label="reference")
        for a in p["alarms"]:
            ax.axvline((a["since_utc_s"] - t_first) / 3600.0, color="#fd8d3c", ls=":", lw=1.2)
            ax.plot([(a["raised_utc_s"] - t_first) / 3600.0], [ax.get_ylim()[1]], "v", color="#d62728", ms=8)
        title = p["name"] + (" (" + p["stands_for"] + ")" if p["stands_for"] else "")
        ax.set_ylabel(p["name"] + " / ref")
        ax.set_title(title + ", %d alarm(s)" % len(p["alarms"]), fontsize=9, loc="left")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="best")
    axes[-1, 0].set_xlabel("time since the first window [h]")
    note = "" if h.get("temperature_measured") else " (no T_oil: temperature not separated)"
    fig.suptitle("Rig health: " + h["rig_name"] + note, fontsize=10)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)


if __name__ == "__main__":
    main()
