#!/usr/bin/python3
"""Overlays the responses of several runs, one panel per group, to compare cases.

    tools/plots/plot_cases.py --out FIG.png --title TITLE PANEL:LABEL=RUN.csv [...]

Each argument puts the run file RUN.csv (docs/run-files.md) into
panel PANEL with legend LABEL; panels are laid out side by side. The demand
and response columns follow the rig in the file's `# rig:` line
(pneumatic_rotary: theta_d/theta; quarter_car: x_ref/x_r).
Uses Debian's python3-matplotlib (run with /usr/bin/python3).
"""
import argparse
import collections
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from plot_run import read_run  # noqa: E402

COLUMNS = {"pneumatic_rotary": ("theta_d", "theta", "angle [rad]"),
           "quarter_car": ("x_ref", "x_r", "displacement [m]")}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--title", default="")
    ap.add_argument("runs", nargs="+", help="PANEL:LABEL=RUN.csv")
    args = ap.parse_args()

    panels = collections.OrderedDict()
    for spec in args.runs:
        try:
            panel, rest = spec.split(":", 1)
            label, path = rest.split("=", 1)
        except ValueError:
            sys.exit(f"plot_cases: '{spec}' is not PANEL:LABEL=RUN.csv")
        panels.setdefault(panel, []).append((label, path))

    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4), squeeze=False)
    for ax, (panel, runs) in zip(axes[0], panels.items()):
        demand_drawn = False
        for label, path in runs:
            meta, c = read_run(path)
            demand, response, ylabel = COLUMNS.get(meta.get("rig", ""), COLUMNS["quarter_car"])
            if demand not in c or response not in c:
                sys.exit(f"{path}: needs columns {demand} and {response}")
            if not demand_drawn:
                ax.plot(c["t"], c[demand], "k--", lw=1, label=f"demand {demand}")
                demand_drawn = True
            ax.plot(c["t"], c[response], lw=1.2, label=label)
        ax.set(title=panel, xlabel="t [s]", ylabel=ylabel)
        ax.grid(True)
        ax.legend(fontsize=8)
    if args.title:
        fig.suptitle(args.title)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(args.out)


if __name__ == "__main__":
    main()
