#!/usr/bin/python3
"""Figures of a `granagg analyze` output folder: S(t) with its local slope, N_s(s) at the last
time, f(v~) beside the Maxwellian at the first and last times, T_g and a2, MSD, mean |q|.

usage: /usr/bin/python3 scripts/plot_analysis.py ANALYSIS_DIR
Reads the ensemble CSV tables (docs/analysis.md, "Outputs") and writes analysis.png next to them.
Debian's python3-matplotlib and python3-numpy only.
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from granagg_tables import read  # noqa: E402


def main():
    d = sys.argv[1]
    S, thermo, msd = read(f"{d}/S_t.csv"), read(f"{d}/thermo.csv"), read(f"{d}/msd.csv")
    speed, ng, npart = (read(f"{d}/speed_dist.csv"), read(f"{d}/N_s_grid.csv"),
                        read(f"{d}/N_s_particle.csv"))
    fig, ax = plt.subplots(2, 3, figsize=(15, 8.5))
    a = ax[0, 0]
    for name, label in (("S_grid_mean", "grid"), ("S_particle_mean", "particle")):
        m = S["t"] > 0
        a.errorbar(S["t"][m], S[name][m], yerr=S[name.replace("_mean", "_se")][m],
                   label=f"S(t), {label}", fmt=".-")
    a.set(xscale="log", yscale="log", xlabel="t", ylabel="S", title="mean cluster size")
    a.legend()
    a = ax[0, 1]
    for name, label in (("z_local_grid_of_mean", "grid"), ("z_local_particle_of_mean", "particle")):
        a.plot(S["t"], S[name], ".-", label=label)
    a.set(xscale="log", xlabel="t", ylabel="z(t) = ln[S(t)/S(t/p)]/ln p", title="local slope")
    a.legend()
    a = ax[0, 2]
    for tab, label in ((ng, "grid"), (npart, "particle")):
        if tab is None:
            continue
        t_last = tab["t"].max()
        m = tab["t"] == t_last
        a.loglog(tab["s"][m], tab["N_s_mean"][m], "o", label=f"{label}, t = {t_last:.3g}")
    a.set(xlabel="s", ylabel="N_s", title="cluster-size distribution")
    a.legend()
    a = ax[1, 0]
    if speed is not None:
        times = np.unique(speed["t"])
        for t in (times[0], times[-1]):
            m = speed["t"] == t
            v = 0.5 * (speed["v_low"][m] + speed["v_high"][m])
            a.plot(v, speed["f_mean"][m], ".", label=f"t = {t:.3g}")
        m = speed["t"] == times[0]
        a.plot(0.5 * (speed["v_low"][m] + speed["v_high"][m]), speed["f_maxwell_mean"][m], "k-",
               label="Maxwellian")
        a.set(xlabel="v~ = v / <v^2>^(1/2)", ylabel="f(v~)", title="speed distribution")
        a.legend()
    a = ax[1, 1]
    m = thermo["t"] > 0
    a.loglog(thermo["t"][m], thermo["T_g_mean"][m], ".-", label="T_g")
    if np.isfinite(thermo["mean_abs_q_mean"]).any():
        a.loglog(thermo["t"][m], thermo["mean_abs_q_mean"][m], ".-", label="<|q|>")
    a.set(xlabel="t", title="temperature and charge")
    a.legend()
    a2 = a.twinx()
    a2.errorbar(thermo["t"][m], thermo["a2_mean"][m], yerr=thermo["a2_err_mean"][m], fmt="r.",
                label="a2")
    a2.set_ylabel("a2", color="r")
    a = ax[1, 2]
    if msd is not None:
        m = msd["t"] > 0
        a.loglog(msd["t"][m], msd["msd_mean"][m], ".-", label="MSD from t0")
    a.set(xlabel="t", ylabel="MSD", title="mean-squared displacement")
    a.legend()
    fig.tight_layout()
    out = f"{d}/analysis.png"
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
