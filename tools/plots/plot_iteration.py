#!/usr/bin/python3
"""Plots of a drive iteration (rigctl iterate --plot, or by hand).

    tools/plots/plot_iteration.py DIR [--out PNG]

Reads DIR/summary.json and each iteration's DIR/iter_NN_response.csv (the
recorded response beside its target) and DIR/iter_NN_drive.csv, and draws:
the target against the first and the last response (a 4 s window where the
target moves most), the error of every iteration over the whole record, and
the relative RMS error and TRAC per iteration with the tolerance.
Default output: DIR/iterations.png.
Uses Debian's python3-matplotlib and python3-numpy (run with /usr/bin/python3).
"""
import argparse
import json
import os

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_run_file(path):
    """Columns of a run file by name (metadata lines skipped)."""
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    header = lines[0].strip().split(",")
    data = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    return {name: data[:, i] for i, name in enumerate(header)}


def busiest_window(t, x, seconds=4.0):
    """Start and end of the window where x moves most (largest variance)."""
    dt = t[1] - t[0]
    n = max(2, int(seconds / dt))
    if len(x) <= n:
        return t[0], t[-1]
    var = [np.var(x[i:i + n]) for i in range(0, len(x) - n, max(1, n // 8))]
    i = int(np.argmax(var)) * max(1, n // 8)
    return t[i], t[i + n - 1]


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dir")
    p.add_argument("--out")
    a = p.parse_args()
    summary = json.load(open(os.path.join(a.dir, "summary.json")))
    its = summary["iterations"]
    if not its:
        raise SystemExit("no iteration was played: " + summary.get("end_detail", ""))
    ch = summary["channel"]
    runs = [read_run_file(os.path.join(a.dir, i["response_file"])) for i in its]
    t = runs[0]["t"]
    target = runs[0]["target"]

    fig, ax = plt.subplots(3, 1, figsize=(9, 10))
    lo, hi = busiest_window(t, target)
    sel = (t >= lo) & (t <= hi)
    ax[0].plot(t[sel], 1e3 * target[sel], "k", lw=2, label="target")
    ax[0].plot(t[sel], 1e3 * runs[0][ch][sel], lw=1, label="iteration 1")
    if len(runs) > 1:
        ax[0].plot(t[sel], 1e3 * runs[-1][ch][sel], "--", lw=1, label=f"iteration {its[-1]['iteration']}")
    ax[0].set_ylabel(f"{ch} [mm]")
    source = " ".join(os.path.basename(w) if "/" in w else w for w in summary["frf_source"].split(" "))
    ax[0].set_title(f"{ch}: target and response (inverse from {source})")
    ax[0].legend(loc="upper right")
    for i, r in zip(its, runs):
        ax[1].plot(t, 1e3 * (r[ch] - r["target"]), lw=0.8,
                   label=f"{i['iteration']}: {i['rel_rms_percent']:.1f} %")
    ax[1].set_ylabel("error [mm]")
    ax[1].set_xlabel("t [s]")
    ax[1].set_title("error per iteration (response - target, unfiltered)")
    ax[1].legend(loc="upper right", fontsize=8)
    k = [i["iteration"] for i in its]
    ax[2].plot(k, [i["rel_rms_percent"] for i in its], "o-", label="relative RMS error [%]")
    ax[2].axhline(summary["tolerance_percent"], color="gray", ls=":", label="tolerance")
    ax[2].set_xlabel("iteration")
    ax[2].set_ylabel(f"error over {summary['band_hz'][0]}-{summary['band_hz'][1]} Hz [%]")
    ax[2].set_xticks(k)
    tr = ax[2].twinx()
    tr.plot(k, [i["trac"] for i in its], "s--", color="tab:green", label="TRAC")
    tr.set_ylabel("TRAC")
    tr.set_ylim(min(0.9, min(i["trac"] for i in its)), 1.0)
    ax[2].legend(loc="upper center")
    ax[2].set_title(f"end: {summary['end']}")
    fig.tight_layout()
    fig.savefig(a.out or os.path.join(a.dir, "iterations.png"), dpi=90)


if __name__ == "__main__":
    main()
