#!/usr/bin/python3
"""Figures for the mean-field demo (scripts/demo.sh): S(t) and its local slope for beta = 2, 3
with the three solvers, the z(beta) table, and the kinetic-theory tables.

usage: /usr/bin/python3 scripts/plot_meanfield.py RESULTS_DIR
Reads the CSV tables written by `granagg smol` / `granagg kinetic` (provenance lines start
with '#') and writes PNG files next to them. Debian's python3-matplotlib and python3-numpy only.
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from granagg_tables import paper, read  # noqa: E402


def plot_S(out):
    fig, (ax, az) = plt.subplots(1, 2, figsize=(11, 4.2))
    styles = {"sectional": "-", "discrete": "--", "mono": ":"}
    colors = {2: "tab:blue", 3: "tab:red"}
    for beta in (2, 3):
        for method, ls in styles.items():
            d = read(os.path.join(out, f"S_beta{beta}_{method}.csv"))
            if d is None:
                continue
            ok = d["valid"] > 0
            ax.loglog(d["t"][ok], d["S"][ok], ls, color=colors[beta], label=f"beta={beta} {method}")
            z = d["z_local"]
            good = ok & np.isfinite(z)
            az.semilogx(d["S"][good], z[good], ls, color=colors[beta],
                        label=f"beta={beta} {method}")
        zinf = 3 * beta / (beta + 3)
        az.axhline(zinf, color=colors[beta], lw=0.6)
    # the paper's mean-field values (Singh & Mazza 2018): local slopes near S ~ 250 and ~ 1650
    p2, p3 = paper()["z_meanfield_beta2"], paper()["z_meanfield_beta3"]
    az.plot([p2["S"], p3["S"]], [p2["value"], p3["value"]], "ko", ms=5,
            label=f"paper: {p2['value']}, {p3['value']}")
    ax.set_xlabel("t  [1/(K0 n1(0))]")
    ax.set_ylabel("S = M2/M1")
    ax.legend(fontsize=7)
    az.set_xlabel("S")
    az.set_ylabel("local slope z = log[S(t)/S(t/2)]/log 2")
    az.set_ylim(0.9, 1.6)
    az.legend(fontsize=7)
    fig.suptitle("Smoluchowski equation, kernel (i^1/3+j^1/3)^2 (1/i+1/j)^(1/beta)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "meanfield_S.png"), dpi=120)
    plt.close(fig)


def plot_zbeta(out):
    d = read(os.path.join(out, "zbeta.csv"))
    if d is None:
        return
    fig, ax = plt.subplots(figsize=(5, 4))
    b = np.linspace(d["beta"].min(), d["beta"].max(), 200)
    ax.plot(b, 3 * b / (b + 3), "k-", lw=1, label="3 beta/(beta+3)")
    ax.plot(d["beta"], d["z_asymptotic"], "o", label="full equation, asymptotic")
    if "z_local_S250" in d.dtype.names:
        ax.plot(d["beta"], d["z_local_S250"], "s", mfc="none", label="local slope at S = 250")
    ax.set_xlabel("beta")
    ax.set_ylabel("z")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "zbeta.png"), dpi=120)
    plt.close(fig)


def plot_kinetic(out):
    r = read(os.path.join(out, "restitution.csv"))
    c = read(os.path.join(out, "cooling.csv"))
    if r is None and c is None:
        return
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    if r is not None:
        names = r.dtype.names
        axes[0].semilogx(r[names[0]], r[names[1]], "o-", label=names[1])
        axes[0].set_xlabel(names[0] + "  (impact speed)")
        axes[0].set_ylabel("restitution coefficient")
        axes[0].legend()
    if c is not None:
        names = c.dtype.names
        t = c[names[0]]
        for n in [m for m in names[1:] if m.startswith("T")]:
            y = c[n]
            if np.all(np.isfinite(y)) and np.all(y > 0):
                axes[1].loglog(t, y, label=n)
        axes[1].set_xlabel(names[0])
        axes[1].set_ylabel("T_g")
        axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "kinetic.png"), dpi=120)
    plt.close(fig)


def plot_md(out):
    """T_g(t) of the MD run in OUT/md-quick beside the kinetic-theory cooling (cooling.csv)."""
    traj = os.path.join(out, "md-quick", "traj.h5")
    if not os.path.exists(traj):
        return
    import h5py

    with h5py.File(traj, "r") as f:
        g = f["granagg/observables/temperature"]
        t, T = g["time"][:], g["value"][:]
        c = f["granagg/observables/contacts_per_particle/value"][:]
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    ok = t > 0
    ax.loglog(t[ok], T[ok], "-", label="MD, quick preset (N = 2000)")
    theory = read(os.path.join(out, "cooling.csv"))
    if theory is not None:
        names = theory.dtype.names
        ax.loglog(theory[names[0]], theory["T"], "--",
                  label="kinetic theory, exact e(v), Enskog rate")
    ax.set_xlabel("t  [sqrt(m d^2/T0)]")
    ax.set_ylabel("T_g / T0")
    ax.set_xlim(left=0.05)
    ax.legend(fontsize=8)
    ax.set_title(f"viscoelastic gas (mean contacts per particle {c.mean():.2f})", fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "md_cooling.png"), dpi=120)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    plot_S(out)
    plot_zbeta(out)
    plot_kinetic(out)
    plot_md(out)
    print("figures:", ", ".join(f for f in sorted(os.listdir(out)) if f.endswith(".png")))


if __name__ == "__main__":
    main()
