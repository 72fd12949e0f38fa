#!/usr/bin/python3
"""The density length l(t) of the neutral gas in three boxes, side by side (issue 45, part 2;
docs/validation.md, "The box of L = 280").

Inputs: the validation study's ensemble tables of L = 70 (20 runs) and L = 140 (2 runs)
(docs/validation/dominance_neutral_20runs.csv, dominance_box_L140.csv: l_density_mean, _se) and
one or more L = 280 runs: an analysis folder (`granagg analyze RUN` or RUN/analysis of
`granagg md --analyze`: per_run/S_t.csv with l_density and l_perp), or, for a run still going,
its in-situ state RUN/analysis-state.h5 (the S_t rows up to its last checkpoint; the local slope
is then computed here with the same rule).

Output: OUT.csv (t, l and its standard error per box, the local slope d ln l / d ln t of each as
ln[l(t)/l(t/p)] / ln p with p = 2, and whether L = 140 and L = 280 agree within their combined
spread, 2 sigma of the difference, at each common time) and OUT.png (l(t) and the local slopes,
with the candidates 2/5 and 1/2 of the literature). It prints the times of agreement and the
largest time each box reaches. It makes no claim beyond the times the L = 280 runs reached.

    /usr/bin/python3 scripts/finite_size.py --l280 RUN1/analysis [RUN2/analysis] --out OUT
"""
import argparse
import csv
import math
import os
import sys

import numpy as np


def read_table(path):
    with open(path) as f:
        rows = [line for line in f if not line.startswith("#")]
    reader = csv.DictReader(rows)
    cols = {}
    for r in reader:
        for k, v in r.items():
            cols.setdefault(k, []).append(float(v) if v not in ("", None) else math.nan)
    return {k: np.array(v) for k, v in cols.items()}


def read_state(path):
    """The S_t rows of an in-situ analysis state (analysis/pipeline/RunAnalysis.cpp's layout)."""
    import h5py
    with h5py.File(path, "r") as f:
        rows, cols = (int(x) for x in f["integers/table.S_t.shape"][:])
        names = f["texts/table.S_t.columns"][()]
        names = (names.decode() if isinstance(names, bytes) else names).split("\n")
        flat = f["reals/table.S_t"][:].reshape(rows, cols)
    return {n: flat[:, k] for k, n in enumerate(names)}


def local_slope(t, y, p=2.0):
    """ln[y(t)/y(t/p)] / ln p with y(t/p) interpolated in (ln t, ln y); NaN before t0 p."""
    out = np.full_like(y, np.nan)
    ok = (t > 0) & (y > 0) & np.isfinite(y)
    lt, ly = np.log(t[ok]), np.log(y[ok])
    for i, (tk, yk) in enumerate(zip(t, y)):
        if not (tk > 0 and yk > 0) or len(lt) < 2 or math.log(tk / p) < lt[0]:
            continue
        out[i] = (math.log(yk) - np.interp(math.log(tk / p), lt, ly)) / math.log(p)
    return out


def l280(folders):
    """Mean and standard error of l_density (and l_perp) over the L = 280 runs, on the first
    run's frame times (the runs share the frame schedule)."""
    runs = [read_state(f) if f.endswith(".h5") else
            read_table(os.path.join(f, "per_run", "S_t.csv")) for f in folders]
    t = runs[0]["t"]
    n = min(len(r["t"]) for r in runs)
    t = t[:n]
    ld = np.array([r["l_density"][:n] for r in runs])
    lp = np.array([r.get("l_perp", np.full(len(r["t"]), np.nan))[:n] for r in runs])
    se = lambda a: (a.std(axis=0, ddof=1) / math.sqrt(len(a))) if len(a) > 1 else \
        np.full(a.shape[1], np.nan)
    return t, ld.mean(axis=0), se(ld), lp.mean(axis=0), len(runs)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--l70", default="docs/validation/dominance_neutral_20runs.csv")
    ap.add_argument("--l140", default="docs/validation/dominance_box_L140.csv")
    ap.add_argument("--l280", nargs="+", required=True)
    ap.add_argument("--traj", nargs="*", default=[],
                    help="traj.h5 of the first L = 280 run: tau, the mean number of collisions "
                         "per particle (2 collisions / N), for the slope against tau")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    boxes = {}
    for name, path in (("70", a.l70), ("140", a.l140)):
        tab = read_table(path)
        boxes[name] = (tab["t"], tab["l_density_mean"], tab["l_density_se"])
    t3, l3, se3, lp3, runs = l280(a.l280)
    keep = t3 > 0  # log time axes
    t3, l3, se3, lp3 = t3[keep], l3[keep], se3[keep], lp3[keep]
    boxes["280"] = (t3, l3, se3)

    # every box on the L = 280 times where the others have rows (interpolated in log t)
    def at(name, t):
        tt, ll, ss = boxes[name]
        ok = tt > 0
        inside = (t >= tt[ok].min()) & (t <= tt[ok].max())
        li = np.where(inside, np.exp(np.interp(np.log(t), np.log(tt[ok]), np.log(ll[ok]))),
                      np.nan)
        si = np.where(inside, np.interp(np.log(t), np.log(tt[ok]), ss[ok]), np.nan)
        return li, si

    # tau(t) = 2 C(t) / N from the observables of the first run (Brito & Ernst state their
    # late-time law in tau); the slope of l against tau by the same rule
    tau = np.full_like(t3, np.nan)
    if a.traj:
        import h5py
        with h5py.File(a.traj[0], "r") as f:
            g = f["granagg/observables/collisions"]
            tc, c = g["time"][:], g["value"][:]
            n = f["particles/all/position/value"].shape[1]
        tau = np.interp(t3, tc, 2.0 * c / n, left=np.nan, right=np.nan)
    z_tau = local_slope(tau, l3) if a.traj else np.full_like(t3, np.nan)
    z_perp = local_slope(t3, lp3)
    rows = []
    z = {name: local_slope(*boxes[name][:2]) for name in boxes}
    l70, s70 = at("70", t3)
    l140, s140 = at("140", t3)
    z70 = np.interp(t3, boxes["70"][0], z["70"], left=np.nan, right=np.nan)
    z140 = np.interp(t3, boxes["140"][0], z["140"], left=np.nan, right=np.nan)
    agree = []
    for i, t in enumerate(t3):
        spread = 2 * math.sqrt(np.nan_to_num(s140[i]) ** 2 + np.nan_to_num(se3[i]) ** 2)
        ok = bool(np.isfinite(l140[i]) and abs(l140[i] - l3[i]) <= spread)
        if ok:
            agree.append(t)
        rows.append([t, l70[i], s70[i], l140[i], s140[i], l3[i], se3[i], lp3[i], z70[i], z140[i],
                     z["280"][i], z_perp[i], tau[i], z_tau[i], int(ok) if np.isfinite(l140[i]) else -1])
    with open(a.out + ".csv", "w") as f:
        f.write("# l(t) of the neutral gas at L = 70 (20 runs), 140 (2 runs), 280 (%d run(s)); "
                "z_*: local slope ln[l(t)/l(t/2)]/ln 2; agree_140_280: |l_140 - l_280| <= 2 "
                "sigma of the difference (1), not (0), no L = 140 row (-1); z_perp_280: local slope of l_perp; tau_280: collisions per "
                "particle; z_tau_280: d ln l / d ln tau; "
                "scripts/finite_size.py\n" % runs)
        f.write("t,l_70,l_70_se,l_140,l_140_se,l_280,l_280_se,l_perp_280,z_70,z_140,z_280,"
                "z_perp_280,tau_280,z_tau_280,agree_140_280\n")
        for r in rows:
            f.write(",".join("%.6g" % x for x in r) + "\n")
    print("L = 280: %d run(s), frames to t = %.4g" % (runs, t3.max()))
    common = [r for r in rows if r[-1] >= 0]
    if common:
        print("L = 140 and L = 280 agree within 2 sigma at %d of %d common times (t = %.4g .. %.4g)"
              % (len(agree), len(common), common[0][0], common[-1][0]))
    else:
        print("no common times with L = 140 yet (its table starts at t = %.4g)"
              % boxes["140"][0].min())

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for name, col in (("70", "C0"), ("140", "C1"), ("280", "C3")):
        t, l, s = boxes[name]
        ax[0].errorbar(t, l, s, color=col, label="L = %s" % name, fmt="-", lw=1)
        ax[1].plot(t, z[name], color=col, label="L = %s" % name)
    ax[0].plot(t3, lp3, "C3--", lw=1, label="l_perp, L = 280")
    for v, lab in ((0.4, "2/5"), (0.5, "1/2")):
        ax[1].axhline(v, color="gray", ls=":", lw=1)
        ax[1].annotate(lab, (1.0, v), xycoords=("axes fraction", "data"), color="gray",
                       ha="right", va="bottom")
    ax[0].set(xscale="log", yscale="log", xlabel="t", ylabel="l (density length, d)")
    ax[1].set(xscale="log", xlabel="t", ylabel="d ln l / d ln t (p = 2)")
    ax[0].legend(fontsize=8)
    ax[1].legend(fontsize=8)
    fig.suptitle("neutral gas: the density length in three boxes (L = 280: t <= %.3g)" % t3.max())
    fig.tight_layout()
    fig.savefig(a.out + ".png", dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
