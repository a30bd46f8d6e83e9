#!/usr/bin/python3
"""Plots a quarter-car run file like seed paper 000's Figs. 4-11.

    tools/plots/plot_run.py RUN.csv [--out DIR] [--step-window T0 T1]

Reads a run file of docs/run-files.md (as written by
`rigctl run --csv` or `rigctl log2csv`) and writes PNGs into DIR:
  fig04_road.png      demand x_ref and road actuator x_r        (paper Fig. 4)
  fig05_control.png   tracking error and valve command u         (Fig. 5)
  fig06_pressure.png  chamber pressures p1, p2                   (Fig. 6)
  fig07_wheel_body.png wheel and body displacement               (Fig. 7)
  fig09_body_velocity.png body velocity                          (Fig. 9)
  fig10_suspension.png wheel minus body displacement x_w - x_b   (Fig. 10)
  fig11_friction.png  bearing friction against body velocity     (Fig. 11)
Fig. 11 uses the simulator's truth columns sim_f_bearing (and the true body
velocity derived from x_b) when present; for measured data it estimates the
friction from Newton's law on the body, F = ks (x_w - x_b) + bd (v_w - v_b)
- Mb dv_b/dt, with the nominal ks, bd, Mb (override with --ks --bd --mb).
Uses Debian's python3-matplotlib and python3-numpy (run with /usr/bin/python3).
"""
import argparse
import os
import sys

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_run(path):
    meta = {}
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    i = 0
    while i < len(lines) and lines[i].startswith("#"):
        key, _, value = lines[i][1:].partition(":")
        meta[key.strip()] = value.strip()
        i += 1
    if i >= len(lines):
        sys.exit(f"{path}: no header row")
    names = [c.strip() for c in lines[i].split(",")]
    try:
        data = np.array([[float(c) for c in row.split(",")] for row in lines[i + 1:] if row.strip()])
    except ValueError as e:
        sys.exit(f"{path}: {e}")
    if data.ndim != 2 or data.shape[1] != len(names):
        sys.exit(f"{path}: rows do not match the header ({len(names)} columns)")
    return meta, {n: data[:, k] for k, n in enumerate(names)}


def require(cols, names, path):
    for n in names:
        if n not in cols:
            sys.exit(f"{path}: column '{n}' is required for these plots")


def save(fig, out, name):
    fig.tight_layout()
    target = os.path.join(out, name)
    fig.savefig(target, dpi=110)
    plt.close(fig)
    print(target)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--out", default=None, help="output folder (default: next to the CSV)")
    ap.add_argument("--ks", type=float, default=2.89e4, help="spring stiffness [N/m] for the friction estimate")
    ap.add_argument("--bd", type=float, default=260.0, help="damper [N s/m] for the friction estimate")
    ap.add_argument("--mb", type=float, default=240.0, help="body mass [kg] for the friction estimate")
    args = ap.parse_args()

    meta, c = read_run(args.csv)
    require(c, ["t", "x_ref", "u", "x_r", "x_w", "x_b"], args.csv)
    out = args.out or os.path.splitext(args.csv)[0] + "-plots"
    os.makedirs(out, exist_ok=True)
    t = c["t"]
    mm = 1e3
    title = f"{meta.get('rig', 'quarter_car')}: {os.path.basename(args.csv)}"

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, c["x_ref"] * mm, label="demand $x_{ref}$")
    ax.plot(t, c["x_r"] * mm, "--", label="road actuator $x_r$")
    ax.set(xlabel="t [s]", ylabel="displacement [mm]", title="Fig. 4: road input " + title)
    ax.legend()
    ax.grid(True)
    save(fig, out, "fig04_road.png")

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    a1.plot(t, (c["x_ref"] - c["x_r"]) * mm)
    a1.set(ylabel="error $x_{ref}-x_r$ [mm]", title="Fig. 5: tracking error and valve command")
    a1.grid(True)
    a2.plot(t, c["u"])
    a2.set(xlabel="t [s]", ylabel="u [fraction of rated current]")
    a2.grid(True)
    save(fig, out, "fig05_control.png")

    if "p1" in c and "p2" in c:
        fig, ax = plt.subplots(figsize=(8, 4))
        ax.plot(t, c["p1"] / 1e5, label="cap side $p_1$")
        ax.plot(t, c["p2"] / 1e5, label="rod side $p_2$")
        ax.set(xlabel="t [s]", ylabel="pressure [bar gauge]", title="Fig. 6: actuator chamber pressures")
        ax.legend()
        ax.grid(True)
        save(fig, out, "fig06_pressure.png")

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, c["x_w"] * mm, label="wheel $x_w$")
    ax.plot(t, c["x_b"] * mm, label="body $x_b$")
    ax.set(xlabel="t [s]", ylabel="displacement [mm]", title="Fig. 7: wheel and body displacement")
    ax.legend()
    ax.grid(True)
    save(fig, out, "fig07_wheel_body.png")

    if "v_b" in c:
        fig, ax = plt.subplots(figsize=(8, 4))
        ax.plot(t, c["v_b"], lw=0.6, label="measured $v_b$")
        ax.set(xlabel="t [s]", ylabel="body velocity [m/s]", title="Fig. 9: body velocity")
        ax.grid(True)
        save(fig, out, "fig09_body_velocity.png")

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, (c["x_w"] - c["x_b"]) * mm)
    ax.set(xlabel="t [s]", ylabel="$x_w - x_b$ [mm]", title="Fig. 10: suspension deflection")
    ax.grid(True)
    save(fig, out, "fig10_suspension.png")

    dt = np.median(np.diff(t))
    if "sim_f_bearing" in c:
        # Simulator truth: the body velocity from the (quantised) LVDT is too
        # noisy near zero, so use the smoothed derivative of x_b.
        kernel = np.ones(5) / 5
        v_b = np.convolve(np.gradient(c["x_b"], dt), kernel, mode="same")
        friction, source = c["sim_f_bearing"], "simulator truth"
    elif "v_w" in c and "v_b" in c:
        v_b = c["v_b"]
        accel = np.gradient(np.convolve(v_b, np.ones(9) / 9, mode="same"), dt)
        friction = args.ks * (c["x_w"] - c["x_b"]) + args.bd * (c["v_w"] - v_b) - args.mb * accel
        source = "estimated from Newton's law on the body"
    else:
        friction = None
    if friction is not None:
        fig, ax = plt.subplots(figsize=(6, 5))
        ax.plot(v_b * mm, friction, ".", ms=1.5)
        ax.set(xlabel="body velocity [mm/s]", ylabel="bearing friction [N]",
               title=f"Fig. 11: friction vs body velocity ({source})")
        ax.grid(True)
        save(fig, out, "fig11_friction.png")


if __name__ == "__main__":
    main()
