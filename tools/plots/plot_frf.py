#!/usr/bin/python3
"""Bode plots of a measured FRF (rigctl identify) and of a tuned loop (rigctl tune).

    tools/plots/plot_frf.py FRF.json --out FRF.png [--tune TUNE.json]

Without --tune: for each response channel, the plant (command -> response,
estimated with the demand as instrument) and the closed loop (demand ->
response): magnitude, phase and coherence, with the plant's own
linearisation where the FRF file carries one (simulated rigs).
With --tune: the measured plant, the position loop L with the tuned gains
(magnitude and phase, the crossover and phase margin marked) and the
predicted standard step.
Uses Debian's python3-matplotlib and python3-numpy (run with /usr/bin/python3).
"""
import argparse
import json

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def complex_of(curve):
    return np.array(curve["re"]) + 1j * np.array(curve["im"])


def db(z):
    return 20.0 * np.log10(np.abs(z))


def phase(z):
    p = np.degrees(np.unwrap(np.angle(z)))
    return p - 360.0 if p[0] > 90.0 else p  # a loop lags at low frequency


def plot_measurement(frf, out):
    f = np.array(frf["frequency_hz"])
    responses = [r["name"] for r in frf["channels"]["responses"]]
    command = frf["channels"]["command"]["name"]
    demand = frf["channels"]["demand"]["name"]
    fig, axes = plt.subplots(3, len(responses), figsize=(6.5 * len(responses), 9), sharex=True, squeeze=False)
    for col, name in enumerate(responses):
        g = complex_of(frf["plant"][name])
        t = complex_of(frf["closed_loop"][name])
        ax_m, ax_p, ax_c = axes[0][col], axes[1][col], axes[2][col]
        ax_m.semilogx(f, db(g), "o-", ms=3, label=f"plant {command} -> {name} (measured)")
        ax_m.semilogx(f, db(t), "s-", ms=3, label=f"closed loop {demand} -> {name}")
        ax_p.semilogx(f, phase(g), "o-", ms=3)
        ax_p.semilogx(f, phase(t), "s-", ms=3)
        if "model" in frf and name in frf["model"]:
            m = complex_of(frf["model"][name])
            ax_m.semilogx(f, db(m), "k--", lw=1, label="plant linearisation")
            ax_p.semilogx(f, phase(m), "k--", lw=1)
        ax_c.semilogx(f, frf["plant"][name]["coherence"], "o-", ms=3, label="plant (min of demand-response, demand-command)")
        ax_c.semilogx(f, frf["closed_loop"][name]["coherence"], "s-", ms=3, label="closed loop")
        if "distortion" in frf and name in frf["distortion"]:
            ax_c.semilogx(f, np.minimum(frf["distortion"][name], 1.0), "x:", label="distortion beside the lines")
        ax_m.set_ylabel("magnitude [dB]")
        ax_p.set_ylabel("phase [deg]")
        ax_c.set_ylabel("coherence")
        ax_c.set_ylim(0, 1.05)
        ax_c.set_xlabel("frequency [Hz]")
        ax_m.set_title(f"{frf['rig']}: {name}")
        ax_m.legend(fontsize=8)
        ax_c.legend(fontsize=8)
        for ax in (ax_m, ax_p, ax_c):
            ax.grid(True, which="both", alpha=0.3)
    e = frf["excitation"]
    fig.suptitle(f"{e['kind']} {e['band_hz'][0]}-{e['band_hz'][1]} Hz, amplitude {e['amplitude']:g} "
                 f"(clamp {e['amplitude_clamp']:g}), {frf['estimation']['averages']} averages", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def plot_tuned(frf, tune, out):
    loop = tune["loop"]
    f = np.array(loop["frequency_hz"])
    l = np.array(loop["re"]) + 1j * np.array(loop["im"])
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 10))
    ax_m, ax_p, ax_s = axes
    name = frf["channels"]["responses"][0]["name"]
    ax_m.semilogx(f, db(complex_of(frf["plant"][name])), "o-", ms=3, label=f"plant (measured) -> {name}")
    ax_m.semilogx(f, db(l), "s-", ms=3, label="loop L with the tuned gains")
    ax_m.axhline(0, color="k", lw=0.8)
    ax_p.semilogx(f, phase(l), "s-", ms=3, label="loop L")
    ax_p.axhline(-180, color="k", lw=0.8)
    m = tune.get("predicted_margins", {})
    if m and m.get("crossover_hz") is not None:
        fc, pm = m["crossover_hz"], m["phase_margin_deg"]
        ax_m.axvline(fc, color="r", ls=":", label=f"crossover {fc:.3g} Hz")
        ax_p.axvline(fc, color="r", ls=":")
        ax_p.annotate(f"PM {pm:.1f} deg", (fc, -180 + pm), textcoords="offset points", xytext=(8, 8), color="r")
    gains = ", ".join(f"{k} {v:.4g}" for k, v in tune["gains"].items())
    ax_m.set_title(f"{tune['rig']} {tune['controller']} ({tune['method']}): {gains}", fontsize=9)
    ax_m.set_ylabel("magnitude [dB]")
    ax_p.set_ylabel("phase [deg]")
    ax_p.set_xlabel("frequency [Hz]")
    ax_m.legend(fontsize=8)
    for ax in (ax_m, ax_p):
        ax.grid(True, which="both", alpha=0.3)
    if "predicted_step" in tune:
        s = tune["predicted_step"]
        ax_s.plot(s["t"], s["demand"], label="demand")
        ax_s.plot(s["t"], s["response"], label="predicted response (fitted plant, rig's controller)")
        ax_s.set_xlabel("time [s]")
        ax_s.set_title(f"standard step: overshoot {100 * s['overshoot']:.1f} %, settling {s['settling_s']:.2f} s", fontsize=9)
        ax_s.legend(fontsize=8)
        ax_s.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("frf")
    ap.add_argument("--out", required=True)
    ap.add_argument("--tune")
    a = ap.parse_args()
    with open(a.frf) as fh:
        frf = json.load(fh)
    if a.tune:
        with open(a.tune) as fh:
            plot_tuned(frf, json.load(fh), a.out)
    else:
        plot_measurement(frf, a.out)


if __name__ == "__main__":
    main()
