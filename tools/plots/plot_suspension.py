#!/usr/bin/python3
"""Passive vs active responses of the half car, in the spirit of seed 001's Figs. 6-27.

    tools/plots/plot_suspension.py DIR [--out FIGDIR] [--window T0 T1] [--zoom T0 T1] [--title TEXT]

DIR holds the run files of `rigctl compare` (passive.csv, fuzzy.csv,
skyhook.csv, lqr.csv; docs/run-files.md, half_car columns) and
its metrics.json. One PNG per figure group goes to FIGDIR (default DIR);
with --zoom each figure gets a second column showing that interval:

  fig02_road.png                 road under the wheels (Fig. 2)
  fig06_body_displacement.png    body heave z_s (Figs. 6-7)
  fig08_angle.png                pitch (or roll) angle (Figs. 8-9)
  fig10_body_acceleration.png    body heave acceleration (Figs. 10-11)
  fig12_angle_acceleration.png   pitch (or roll) acceleration (Figs. 12-13)
  fig14_suspension_travel.png    suspension travel per corner (Figs. 14-17)
  fig18_tyre_deflection.png      tyre deflection z_r - z_u per corner (Figs. 18-21)
  fig22_jerk.png                 body jerk (Figs. 22-23)
  fig24_actuator_forces.png      actuator force per corner (Figs. 24-27)

The paper has four corners (a full car); the half car has two: wheel 1
(front, or right in the roll plane) and wheel 2 (rear, or left).
Uses Debian's python3-matplotlib (run with /usr/bin/python3).
"""
import argparse
import json
import os
import sys

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_run import read_run  # noqa: E402

RUNS = [("passive", "passive", dict(color="0.25", lw=1.6)),
        ("fuzzy", "fuzzy (paper)", dict(color="tab:red", lw=1.4)),
        ("skyhook", "skyhook", dict(color="tab:blue", lw=1.0, ls="--")),
        ("lqr", "LQR", dict(color="tab:green", lw=1.0, ls="-."))]


def corner_names(plane):
    return ("front", "rear") if plane == "pitch" else ("right", "left")


def load(folder):
    runs = []
    for name, label, style in RUNS:
        path = os.path.join(folder, name + ".csv")
        if not os.path.exists(path):
            sys.exit(f"plot_suspension: {path} is missing (run `rigctl compare ... --out {folder}` first)")
        meta, c = read_run(path)
        for col in ("t", "z_r1", "z_r2", "z_s", "phi", "z_u1", "z_u2", "f_1", "f_2", "z_s_ddot", "phi_ddot",
                    "susp_travel_1", "susp_travel_2"):
            if col not in c:
                sys.exit(f"{path}: column '{col}' is required")
        runs.append((name, label, style, c))
    metrics = {}
    mpath = os.path.join(folder, "metrics.json")
    if os.path.exists(mpath):
        with open(mpath, encoding="utf-8") as f:
            metrics = json.load(f)
    return runs, metrics


def window(c, t0, t1):
    t = c["t"]
    return (t >= t0) & (t <= t1)


def save(fig, out, name):
    fig.tight_layout()
    target = os.path.join(out, name)
    fig.savefig(target, dpi=100)
    plt.close(fig)
    print(target)


def overlay(ax, runs, t0, t1, get, scale=1.0):
    for _, label, style, c in runs:
        m = window(c, t0, t1)
        ax.plot(c["t"][m], scale * get(c)[m], label=label, **style)
    ax.grid(True, alpha=0.4)
    ax.set_xlim(t0, t1)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder", help="output folder of rigctl compare")
    ap.add_argument("--out", default=None, help="figure folder (default: the input folder)")
    ap.add_argument("--window", nargs=2, type=float, metavar=("T0", "T1"), default=None,
                    help="time window [s] (default: the whole run)")
    ap.add_argument("--zoom", nargs=2, type=float, metavar=("T0", "T1"), default=None,
                    help="also show this interval [s] beside the window (the fast part of the response)")
    ap.add_argument("--title", default="", help="first line of every figure's title")
    args = ap.parse_args()
    out = args.out or args.folder
    os.makedirs(out, exist_ok=True)
    runs, metrics = load(args.folder)
    t_all = runs[0][3]["t"]
    t0, t1 = args.window if args.window else (t_all[0], t_all[-1])
    plane = metrics.get("plane", "pitch")
    corners = corner_names(plane)
    angle = "pitch" if plane == "pitch" else "roll"
    road = metrics.get("road", "")
    limit = metrics.get("force_limit_n")
    head = (args.title + "\n" if args.title else "") + road

    def title(fig, what):
        fig.suptitle(f"{what}\n{head}", fontsize=10)

    spans = [(t0, t1)] + ([tuple(args.zoom)] if args.zoom else [])
    width = 8 if len(spans) == 1 else 12
    ratios = {"width_ratios": [3, 2][:len(spans)]}

    # Road (Fig. 2).
    fig, axes = plt.subplots(1, len(spans), figsize=(width, 3.4), squeeze=False, gridspec_kw=ratios)
    c = runs[0][3]
    for k, (a, b) in enumerate(spans):
        ax = axes[0][k]
        m = window(c, a, b)
        ax.plot(c["t"][m], 1e3 * c["z_r1"][m], color="k", lw=1.2, marker="." if k else None, ms=3,
                label=f"z_r1 ({corners[0]} wheel)")
        ax.plot(c["t"][m], 1e3 * c["z_r2"][m], color="tab:orange", lw=1.0, ls="--", marker="." if k else None, ms=3,
                label=f"z_r2 ({corners[1]} wheel)")
        ax.set(xlabel="t [s]", ylabel="road [mm]" if k == 0 else "", xlim=(a, b))
        ax.grid(True, alpha=0.4)
        if k == 1:
            ax.set_title("zoom (dots: the loop's samples)", fontsize=9)
    axes[0][0].legend(fontsize=8)
    title(fig, "Road input under the wheels (Fig. 2)")
    save(fig, out, "fig02_road.png")

    singles = [
        ("fig06_body_displacement.png", "Body displacement z_s (Figs. 6-7)", "z_s [mm]", 1e3, lambda c: c["z_s"]),
        ("fig08_angle.png", f"Body {angle} angle (Figs. 8-9)", f"{angle} [deg]", 180.0 / np.pi, lambda c: c["phi"]),
        ("fig10_body_acceleration.png", "Body acceleration z_s'' (Figs. 10-11)", "z_s'' [m/s^2]", 1.0,
         lambda c: c["z_s_ddot"]),
        ("fig12_angle_acceleration.png", f"Body {angle} acceleration (Figs. 12-13)", f"{angle}'' [rad/s^2]", 1.0,
         lambda c: c["phi_ddot"]),
        ("fig22_jerk.png", "Body jerk dz_s''/dt (Figs. 22-23)", "jerk [m/s^3]", 1.0,
         lambda c: np.gradient(c["z_s_ddot"], c["t"])),
    ]
    for name, what, ylabel, scale, get in singles:
        fig, axes = plt.subplots(1, len(spans), figsize=(width, 3.8), squeeze=False,
                                 gridspec_kw={"width_ratios": [3, 2][:len(spans)]})
        for k, (a, b) in enumerate(spans):
            ax = axes[0][k]
            overlay(ax, runs, a, b, get, scale)
            ax.set(xlabel="t [s]", ylabel=ylabel if k == 0 else "")
            if k == 1:
                ax.set_title("zoom", fontsize=9)
        axes[0][0].legend(fontsize=8, ncol=2)
        title(fig, what)
        save(fig, out, name)

    pairs = [
        ("fig14_suspension_travel.png", "Suspension travel z_s + l_i phi - z_ui, + = extended (Figs. 14-17)",
         "travel [mm]", 1e3, (lambda c: c["susp_travel_1"], lambda c: c["susp_travel_2"])),
        ("fig18_tyre_deflection.png", "Tyre deflection z_ri - z_ui, + = compressed (Figs. 18-21)",
         "deflection [mm]", 1e3, (lambda c: c["z_r1"] - c["z_u1"], lambda c: c["z_r2"] - c["z_u2"])),
        ("fig24_actuator_forces.png", "Actuator forces (Figs. 24-27)", "force [N]", 1.0,
         (lambda c: c["f_1"], lambda c: c["f_2"])),
    ]
    for name, what, ylabel, scale, gets in pairs:
        fig, axes = plt.subplots(2, len(spans), figsize=(width, 6), squeeze=False,
                                 gridspec_kw={"width_ratios": [3, 2][:len(spans)]})
        for i, get in enumerate(gets):
            for k, (a, b) in enumerate(spans):
                ax = axes[i][k]
                overlay(ax, runs, a, b, get, scale)
                if name.startswith("fig24") and limit:
                    for sgn in (-1, 1):
                        ax.axhline(sgn * limit, color="k", lw=0.8, ls=":")
                if k == 0:
                    ax.set(ylabel=f"wheel {i + 1} ({corners[i]})\n{ylabel}")
                if i == 0 and k == 1:
                    ax.set_title("zoom", fontsize=9)
                if i == 1:
                    ax.set_xlabel("t [s]")
        axes[0][0].legend(fontsize=8, ncol=2)
        title(fig, what + (" (dotted: the force limit)" if name.startswith("fig24") and limit else ""))
        save(fig, out, name)

if __name__ == "__main__":
    main()
