#!/usr/bin/env python3
"""Log-log plot of granagg's time per MD step, PPPM against plain Ewald \
(scripts/bench_ewald_pppm.sh).

    /usr/bin/python3 scripts/plot_ewald_pppm.py docs/img/ewald_pppm.csv docs/img/ewald_pppm.png

Fits t = a N^b by least squares in log-log to each method (PPPM: also t = c N log N for
comparison), prints the exponents and the crossover N where the two fits meet, and draws the
measured points, the fits, and a dashed N^1.5 guide for an optimally tuned Ewald sum (alpha,
r_cut and k_max balanced; not measured, anchored at the smallest-N plain-Ewald point, where our
r_cut = L/2 reference is closest to that optimum). Plain Ewald in granagg is the O(N^2)-real-space
reference (all pairs within r_cut <= L/2), not an optimised Ewald.
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def fit_power(n, t):
    b, loga = np.polyfit(np.log(n), np.log(t), 1)
    return math.exp(loga), b


def main():
    csv_path = sys.argv[1] if len(sys.argv) > 1 else "docs/img/ewald_pppm.csv"
    png_path = sys.argv[2] if len(sys.argv) > 2 else "docs/img/ewald_pppm.png"
    rows = list(csv.DictReader(open(csv_path)))
    data = {}
    for r in rows:
        t = float(r["seconds_per_step"])
        if t <= 0:  # a difference of two noisy wall times; the step was too cheap to resolve
            print(f"skipping {r['method']} N = {r['N']}: non-positive time per step {t:.3g} s")
            continue
        data.setdefault(r["method"], []).append((int(r["N"]), t))
    for m in data:
        data[m].sort()
    fits = {}
    for m, pts in data.items():
        n = np.array([p[0] for p in pts], float)
        t = np.array([p[1] for p in pts])
        if len(n) >= 2:
            fits[m] = fit_power(n, t)
    print("| method | N range | fit t = a N^b | a | b |")
    print("|---|---|---|---|---|")
    for m, (a, b) in fits.items():
        n = [p[0] for p in data[m]]
        print(f"| {m} | {min(n)}-{max(n)} | power law | {a:.3g} | {b:.3f} |")
    if "pppm" in data:
        n = np.array([p[0] for p in data["pppm"]], float)
        t = np.array([p[1] for p in data["pppm"]])
        c = float(np.sum(t * n * np.log(n)) / np.sum((n * np.log(n)) ** 2))
        res = np.sqrt(np.mean((np.log(t) - np.log(c * n * np.log(n))) ** 2))
        print(f"| pppm | {int(n.min())}-{int(n.max())} | t = c N ln N | {c:.3g} | "
              f"(rms log residual {res:.2f}) |")
        # PPPM exponent over the upper half of the sizes only (cache / fixed costs at small N)
        big = n >= 1e4
        if big.sum() >= 2:
            a2, b2 = fit_power(n[big], t[big])
            print(f"| pppm | {int(n[big].min())}-{int(n.max())} | power law | {a2:.3g} | "
                  f"{b2:.3f} |")
    print()
    if "pppm" in fits and "ewald" in fits:
        (ap, bp), (ae, be) = fits["pppm"], fits["ewald"]
        if be != bp:
            nx = (ap / ae) ** (1.0 / (be - bp))
            print(f"Crossover of the two power-law fits: N = {nx:.3g} "
                  "(plain Ewald faster below, PPPM above); "
                  f"time per step there {ap * nx ** bp:.3g} s")
        common = sorted(set(n for n, _ in data["pppm"]) & set(n for n, _ in data["ewald"]))
        for n in common:
            tp = dict(data["pppm"])[n]
            te = dict(data["ewald"])[n]
            print(f"  N = {n}: plain Ewald / PPPM = {te / tp:.3g}")
        nmax = max(n for n, _ in data["pppm"])
        print(f"Plain Ewald extrapolated to N = {nmax}: {ae * nmax ** be:.3g} s per step "
              f"(PPPM measured {dict(data['pppm'])[nmax]:.3g} s)")
    print()

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    style = {"pppm": ("C0", "o", "PPPM (P3M, auto r_cut/mesh/order)"),
             "ewald": ("C3", "s", "plain Ewald (reference: O(N$^2$) real space, r_cut = L/2)")}
    nmin = min(p[0] for pts in data.values() for p in pts)
    nmax = max(p[0] for pts in data.values() for p in pts)
    grid = np.logspace(math.log10(nmin) - 0.1, math.log10(nmax) + 0.1, 100)
    for m, pts in data.items():
        col, mk, lab = style.get(m, ("k", "x", m))
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], mk, color=col, label=lab)
        if m in fits:
            a, b = fits[m]
            ax.loglog(grid, a * grid ** b, "-", color=col, lw=1, alpha=0.7,
                      label=f"fit $\\propto N^{{{b:.2f}}}$")
    if "ewald" in data:
        n0, t0 = data["ewald"][0]
        ax.loglog(grid, t0 * (grid / n0) ** 1.5, "--", color="C3", lw=1, alpha=0.6,
                  label="$N^{1.5}$: optimally tuned Ewald (guide, not measured)")
    if "pppm" in fits and "ewald" in fits and fits["ewald"][1] != fits["pppm"][1]:
        (ap, bp), (ae, be) = fits["pppm"], fits["ewald"]
        nx = (ap / ae) ** (1.0 / (be - bp))
        if grid[0] <= nx <= grid[-1]:
            ax.axvline(nx, color="gray", lw=0.8, ls=":")
            ax.annotate(f"crossover N ≈ {nx:.2g}", (nx, ap * nx ** bp),
                        textcoords="offset points", xytext=(6, -14), fontsize=8, color="gray")
    ax.set_xlabel("N (particles)")
    ax.set_ylabel("wall time per MD step [s]")
    ax.set_title("granagg Coulomb, K = 5, ±1 charges, φ = 0.076, accuracy 1e-4", fontsize=10)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    ax.legend(fontsize=7.5, loc="upper left")
    fig.tight_layout()
    fig.savefig(png_path, dpi=130)
    print(f"wrote {png_path}")


if __name__ == "__main__":
    main()
