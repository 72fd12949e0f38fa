#!/usr/bin/python3
"""Tables and figures of the validation study (scripts/validate.sh, docs/validation.md).

    /usr/bin/python3 scripts/validation_report.py OUT [--publish ROOT]

Reads what granagg wrote under OUT (pair studies: OUT/<part>/analysis, fit, meanfield; fit-beta
windows: OUT/<part>/windows; grid variants: OUT/sensitivity) and writes OUT/report/:
  verdict.md          the verdict table (one row per published number) with our values
  verdict.csv         the same numbers, machine-readable (granagg pair prints them beside a demo);
                      the rows of "What S measures" (quantity_id 4-6) come from the committed
                      docs/validation/dominance_*.csv (scripts/dominance_verdict.py)
  ensembles.csv       one row per ensemble: N, runs, K, Q, t_end, onset, growth, regime numbers
  windows.csv         z, beta from z and asymptotic beta over every fitted window
  fisher.csv          Fisher tau at t = 50, 100, 150: MLE and the paper's log-binned least squares
  sensitivity.csv     z and onset for each grid definition
  kscan.csv           the charged gas against K (0.25, 1, 5; neutral beside): onset, S, slopes, z
  qscan.csv           K = 5 against the charge scale Q (0.025, 0.05, 0.1) at t = 50 and 100
  fig_onset.png       S and its local slope against t / t_c (is growth one curve shifted in time?)
  S_<part>.csv        ensemble S(t) (grid and particle, standard errors, local slope of the mean)
  fig_*.png           the figures (docs/validation.md shows them)
With --publish ROOT, copies the CSV tables to ROOT/docs/validation/, the figures to
ROOT/docs/img/validation/ and verdict.csv to ROOT/data/validation/verdict.csv.

Every number here is read from granagg's outputs except two checks computed from its tables:
the least-squares slope of T_g(t) over a late window and the local slopes drawn in the figures.
Python is for plots and checks only (Debian's numpy and matplotlib).
"""
import math
import os
import shutil
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dominance_verdict  # noqa: E402
from granagg_tables import col, load_json, meta, read  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
PAPER = load_json(os.path.join(HERE, "..", "data", "reference", "paper.json"))

# part folder -> (label, colour)
PARTS = [
    ("neutral", "neutral, N = 50016", "C0"),
    ("box", "neutral, N = 400128 (L = 140)", "C9"),
    ("charged-K5", "K = 5", "C3"),
    ("charged-K1", "K = 1", "C1"),
    ("charged-K0.25", "K = 0.25", "C2"),
    ("charged-K5-Q0.025", "K = 5, Q = 0.025", "C6"),
    ("charged-K5-Q0.1", "K = 5, Q = 0.1", "C5"),
]
FISHER_TIMES = [50.0, 100.0, 150.0]


def repo_relative(text):
    """A path or a command line with the paths inside the repository written relative to its
    root: the provenance lines of the committed tables must not name the machine's folders."""
    return text.replace(ROOT + os.sep, "")


def fmt(x, p=3):
    return "n/a" if x is None or not np.isfinite(x) else f"{x:.{p}g}"


def ival(v, lo, hi, p=3):
    if v is None or not np.isfinite(v):
        return "n/a"
    return f"{v:.{p}g} [{fmt(lo, p)}, {fmt(hi, p)}]"


class Part:
    """One pair study under OUT/<name> (one K)."""

    def __init__(self, out, name, label, colour):
        self.name, self.label, self.colour = name, label, colour
        self.d = os.path.join(out, name)
        kdirs = (sorted(os.listdir(os.path.join(self.d, "analysis")))
                 if os.path.isdir(os.path.join(self.d, "analysis")) else [])
        kdirs = [k for k in kdirs
                 if k.startswith("K") and os.path.isdir(os.path.join(self.d, "analysis", k))]
        self.k = kdirs[0] if kdirs else None
        self.ok = self.k is not None and os.path.exists(self.path("analysis", "S_t.csv"))
        self.summary = load_json(os.path.join(self.d, "summary.json"))
        self.ens = (self.summary.get("ensembles") or [{}])[0]

    def path(self, sub, f):
        return os.path.join(self.d, sub, self.k, f)

    def table(self, f):
        return read(self.path("analysis", f))

    def fits(self):
        t = self.table("fits.csv")
        return None if t is None else t[0]

    def fit_beta(self):
        return load_json(self.path("fit", "fit_beta.json"))

    def K(self):
        return float(self.k[1:])


def late_slope(t, y, lo, hi):
    m = (t >= lo) & (t <= hi) & (y > 0) & np.isfinite(y)
    if m.sum() < 3:
        return float("nan")
    return float(np.polyfit(np.log(t[m]), np.log(y[m]), 1)[0])


def nearest_row(tab, t, name="t", rel=0.03):
    ts = tab[name]
    k = int(np.argmin(np.abs(ts - t)))
    return k if abs(ts[k] - t) <= rel * t else None


def growth_regime(S):
    """Local slope of the mean over the last half decade (the rule of granagg pair's regime)."""
    t, z = S["t"], col(S, "z_local_grid_of_mean")
    if z is None:
        return float("nan"), float("nan")
    m = (t >= t[-1] / math.sqrt(10)) & np.isfinite(z)
    if m.sum() == 0:
        return float("nan"), float("nan")
    return float(np.min(z[m])), float(np.max(z[m]))


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    out = sys.argv[1]
    publish = sys.argv[sys.argv.index("--publish") + 1] if "--publish" in sys.argv else None
    rep = os.path.join(out, "report")
    os.makedirs(rep, exist_ok=True)
    parts = [Part(out, *p) for p in PARTS]
    have = [p for p in parts if p.ok]
    missing = [p.name for p in parts if not p.ok]
    print(f"validation_report: parts present: {[p.name for p in have]}; missing: {missing}")

    # ---- ensembles.csv and S_<part>.csv
    ens_rows = []
    for p in have:
        S, f, fb = p.table("S_t.csv"), p.fits(), p.fit_beta()
        md = meta(p.path("analysis", "S_t.csv"))
        runs = int(f["runs"])
        e = p.ens
        zmin, zmax = growth_regime(S)
        base = f["onset_S_base_grid"] if "onset_S_base_grid" in f.dtype.names else float("nan")
        Sg = S["S_grid_mean"]
        last = np.where(np.isfinite(Sg))[0][-1]
        ens_rows.append(dict(part=p.name, K=p.K(),
                             Q=e.get("charging_Q", float("nan")) if p.K() > 0 else float("nan"),
                             N=e.get("N", float("nan")), runs=runs, t_end=float(S["t"][last]),
                             S_grid_end=float(Sg[last]), S_grid_end_se=float(S["S_grid_se"][last]),
                             S_particle_end=(float(S["S_particle_mean"][last])
                                             if col(S, "S_particle_mean") is not None
                                             else float("nan")),
                             S_base=float(base),
                             growth=float(Sg[last] / base) if base > 0 else float("nan"),
                             onset=(float(f["onset_time_grid"])
                                    if "onset_time_grid" in f.dtype.names else float("nan")),
                             onset_se=(float(f["onset_time_grid_err"])
                                       if "onset_time_grid_err" in f.dtype.names
                                       else float("nan")),
                             zloc_min=zmin, zloc_max=zmax,
                             charging=float(f["charging_rate_exponent"]),
                             charging_low=float(f["charging_rate_low"]),
                             charging_high=float(f["charging_rate_high"]),
                             charging_expected=float(f["charging_rate_expected"]),
                             beta_asym=fb.get("beta_asymptotic"), fb_z=fb.get("z")))
        keep = [c for c in ("t", "S_grid_mean", "S_grid_se", "S_particle_mean", "S_particle_se",
                            "z_local_grid_of_mean", "z_local_particle_of_mean",
                            "largest_grid_mean", "mean_contacts_mean")
                if col(S, c) is not None]
        with open(os.path.join(rep, f"S_{p.name}.csv"), "w") as fo:
            src = repo_relative(os.path.abspath(p.path("analysis", "S_t.csv")))
            fo.write(f"# ensemble S(t) of {p.label} ({runs} runs), from {src}\n")
            fo.write(f"# command = {repo_relative(md.get('command', '?'))}\n")
            fo.write(",".join(keep) + "\n")
            for k in range(len(S)):
                fo.write(",".join(f"{S[c][k]:.6g}" for c in keep) + "\n")
    write_csv(os.path.join(rep, "ensembles.csv"), ens_rows,
              "# one row per ensemble; onset: S_grid reaches 2 x its median over t <= 10; "
              "growth = S_grid(t_end) / that median; zloc_min/max: local slope of the mean S_grid "
              "over the last half decade; charging: exponent of d<|q|>/dt over t = 1..100 "
              "(bootstrap over runs) and its expectation -5/6 - 5 kappa/3")

    # ---- windows.csv
    win_rows = []
    for p in have:
        wd = os.path.join(p.d, "windows")
        for w in sorted(os.listdir(wd)) if os.path.isdir(wd) else []:
            j = load_json(os.path.join(wd, w, "fit_beta.json"))
            if not j:
                continue
            win_rows.append(dict(part=p.name, column=j.get("column"), t0=j.get("t0"),
                                 t1=j.get("t1"), n=j.get("n_points"),
                                 z=j.get("z"), z_low=j.get("z_low"), z_high=j.get("z_high"),
                                 S0=j.get("S0"), S1=j.get("S1"),
                                 beta_from_z=j.get("beta_from_z"),
                                 beta_from_z_low=j.get("beta_from_z_low"),
                                 beta_from_z_high=j.get("beta_from_z_high"),
                                 beta_asym=j.get("beta_asymptotic"),
                                 beta_asym_low=j.get("beta_asymptotic_low"),
                                 beta_asym_high=j.get("beta_asymptotic_high")))
    write_csv(os.path.join(rep, "windows.csv"), win_rows,
              "# granagg fit-beta over each window (95 % intervals, bootstrap over runs); "
              "beta_from_z: the full Smoluchowski z(beta) at the window's S; "
              "beta_asym: 3z/(3-z); null = not available")

    # ---- fisher.csv
    fi_rows = []
    for p in have:
        fp = p.table("fisher_pooled.csv")
        if fp is None:
            continue
        for t in FISHER_TIMES:
            k = nearest_row(fp, t)
            if k is None:
                continue
            r = dict(part=p.name, t=float(fp["t"][k]))
            for c in ("tau_grid", "tau_grid_err", "tail_grid", "tau_ls_grid", "tau_ls_grid_err",
                      "bins_ls_grid", "tau_particle", "tau_particle_err", "tau_ls_particle",
                      "tau_ls_particle_err"):
                r[c] = float(fp[c][k]) if c in fp.dtype.names else float("nan")
            fi_rows.append(r)
    write_csv(os.path.join(rep, "fisher.csv"), fi_rows,
              "# Fisher exponent tau of N_s summed over runs (fisher_pooled.csv): MLE (Clauset "
              "et al.) and the paper's least squares on log-binned N_s (tau_ls); the paper prints "
              "-tau")

    # ---- sensitivity.csv
    se_rows = []
    sd = os.path.join(out, "sensitivity")
    for name in sorted(os.listdir(sd)) if os.path.isdir(sd) else []:
        for v in sorted(os.listdir(os.path.join(sd, name))):
            f = read(os.path.join(sd, name, v, "fits.csv"))
            S = read(os.path.join(sd, name, v, "S_t.csv"))
            j = load_json(os.path.join(sd, name, v, "fit", "fit_beta.json"))
            if f is None or S is None:
                continue
            zmin, zmax = growth_regime(S)
            last = np.where(np.isfinite(S["S_grid_mean"]))[0][-1]
            fp = read(os.path.join(sd, name, v, "fisher_pooled.csv"))
            ls = {}
            for t in (50.0, 150.0, float(S["t"][last])):
                k = nearest_row(fp, t) if fp is not None else None
                ls[t] = -float(fp["tau_ls_grid"][k]) if k is not None else float("nan")
            lst = list(ls.values())
            se_rows.append(dict(part=name, variant=v, t0=float(f["fit_t_min"][0]),
                                t1=float(f["fit_t_max"][0]),
                                fb_z=j.get("z"), fb_z_low=j.get("z_low"), fb_z_high=j.get("z_high"),
                                onset=float(f["onset_time_grid"][0]),
                                S_base=float(f["onset_S_base_grid"][0]),
                                S_end=float(S["S_grid_mean"][last]), zloc_min=zmin, zloc_max=zmax,
                                fisher_ls_t50=lst[0], fisher_ls_t150=lst[1], fisher_ls_end=lst[2],
                                occupied=(float(S["occupied_fraction_mean"][1])
                                          if col(S, "occupied_fraction_mean") is not None
                                          else float("nan"))))
    write_csv(os.path.join(rep, "sensitivity.csv"), se_rows,
              "# grid-cluster definitions: grid<spacing>_fill<filling fraction> or "
              "_count<centres per cell>; fb_z: fit-beta z over [t0, t1] (bootstrap over runs); "
              "onset and local slope as in ensembles.csv; fisher_ls_*: the paper's Fisher slope "
              "(-tau, log-binned least squares) at t = 50, 150 and the last frame; "
              "occupied: fraction of occupied sites in the first frame after t = 0")

    k_rows, q_rows = scan_tables(have, ens_rows, win_rows, rep)
    figures(have, rep, out)
    verdict(have, ens_rows, win_rows, fi_rows, se_rows, rep, missing, k_rows, q_rows)

    if publish:
        dd = os.path.join(publish, "docs", "validation")
        di = os.path.join(publish, "docs", "img", "validation")
        dv = os.path.join(publish, "data", "validation")
        for d in (dd, di, dv):
            os.makedirs(d, exist_ok=True)
        for f in os.listdir(rep):
            src = os.path.join(rep, f)
            if f.endswith(".csv") or f.endswith(".md"):
                shutil.copy(src, dd)
            elif f.endswith(".png"):
                shutil.copy(src, di)
        shutil.copy(os.path.join(rep, "verdict.csv"), dv)
        print(f"validation_report: published to {dd}, {di}, {dv}")
    print(f"validation_report: wrote {rep}")
    return 0


def at(tab, name, t):
    """Column `name` of `tab` at the frame nearest t (within 3 %), or nan."""
    c = col(tab, name)
    k = nearest_row(tab, t) if c is not None else None
    return float(c[k]) if k is not None else float("nan")


def at_log(tab, name, t):
    """Column `name` of `tab` interpolated linearly in ln t at t (nan outside the frames)."""
    c = col(tab, name)
    if c is None or not np.isfinite(t) or t <= 0:
        return float("nan")
    m = (tab["t"] > 0) & np.isfinite(c)
    ts, ys = tab["t"][m], c[m]
    if len(ts) < 2 or t < ts[0] or t > ts[-1] * (1 + 1e-4):
        return float("nan")
    return float(np.interp(np.log(t), np.log(ts), ys))


def window_z(win_rows, part, t0, t1, column="S_grid_mean"):
    """The fit-beta row of `part` over [t0, t1] (within 5 %), or None."""
    for r in win_rows:
        if (r["part"] == part and r["column"] == column and r["t0"] is not None
                and abs(r["t0"] - t0) < 0.05 * t0 and abs(r["t1"] - t1) < 0.05 * t1):
            return r
    return None


def collapsed_runs(d):
    """[(t, reason)] of the MD runs that stopped in the pair study at `d` (its pair.log), or []."""
    log = os.path.join(d, "pair.log")
    if not os.path.exists(log):
        return []
    out = []
    with open(log) as f:
        for line in f:
            if "FAILED" not in line or "(t = " not in line:
                continue
            t = line.split("(t = ", 1)[1].split(")", 1)[0]
            reason = ("overlap beyond run.max_overlap: Coulomb collapse"
                      if "attractive Coulomb pair" in line else "run stopped")
            out.append((t, reason))
    return out


def scan_tables(have, ens_rows, win_rows, rep):
    """kscan.csv (the paper's claim: z does not depend on K; t_c falls as K grows) and qscan.csv
    (how K = 5 depends on the charge scale Q, which the paper does not give)."""
    by = {p.name: p for p in have}
    ens = {r["part"]: r for r in ens_rows}

    def common(p, t_list):
        S, th = p.table("S_t.csv"), p.table("thermo.csv")
        e = ens[p.name]
        r = dict(part=p.name, K=p.K(), Q=e["Q"], N=e["N"], runs=e["runs"], t_end=e["t_end"],
                 onset=e["onset"], onset_se=e["onset_se"])
        for t in t_list:
            r[f"S_grid_{t}"] = at(S, "S_grid_mean", t)
            r[f"S_grid_{t}_se"] = at(S, "S_grid_se", t)
            r[f"S_particle_{t}"] = at(S, "S_particle_mean", t)
            r[f"zloc_{t}"] = at(S, "z_local_grid_of_mean", t)
            # the largest particle cluster as a fraction of all particles: finite size
            r[f"largest_particle_frac_{t}"] = at(S, "largest_particle_mean", t) / e["N"]
            r[f"mean_abs_q_{t}"] = at(th, "mean_abs_q_mean", t) if th is not None else float("nan")
            r[f"T_g_{t}"] = at(th, "T_g_mean", t) if th is not None else float("nan")
        # the local slope at a fixed multiple of the onset time: equal along the ensembles if
        # their growth is one curve shifted in time (S(t) = F(t / t_c))
        for f in (1.25, 1.5, 2.0):
            key = f"zloc_at_{f:g}tc".replace(".", "p")  # zloc_at_1p25tc
            r[key] = at_log(S, "z_local_grid_of_mean", f * e["onset"])
        r.update(charging=e["charging"], charging_low=e["charging_low"],
                 charging_high=e["charging_high"])
        return r

    def add_windows(r, name, windows):
        """z_T0_T1 (and _low, _high) of each fitted window into row r (None if not fitted)."""
        for t0, t1 in windows:
            w = window_z(win_rows, name, t0, t1)
            r[f"z_{t0}_{t1}"], r[f"z_{t0}_{t1}_low"], r[f"z_{t0}_{t1}_high"] = (
                (w["z"], w["z_low"], w["z_high"]) if w else (None, None, None))

    k_rows = []
    for name in ("neutral", "charged-K0.25", "charged-K1", "charged-K5"):
        if name not in by:
            continue
        r = common(by[name], (50, 100, 150))
        add_windows(r, name, ((10, 150), (50, 150), (100, 1000)))
        k_rows.append(r)
    write_csv(os.path.join(rep, "kscan.csv"), k_rows,
              "# the gas against K (neutral K = 0 at N = 50016 beside the charged N = 1e4): onset "
              "t_c (+- s.e. over runs), S_grid (+- s.e.), S_particle, local slope of the mean "
              "(zloc), largest particle cluster / N, <|q|>, T_g at t = 50, 100, 150; z over "
              "windows (fit-beta, 95 % bootstrap over runs); charging exponent of d<|q|>/dt")
    q_rows = []
    for name in ("charged-K5-Q0.025", "charged-K5", "charged-K5-Q0.1"):
        if name not in by:
            stopped = collapsed_runs(os.path.join(os.path.dirname(rep), name))
            if stopped:  # every run stopped: a result (a Coulomb collapse), not a missing part
                q_rows.append(dict(part=name, K=5.0, Q=float(name.split("-Q")[1]),
                                   status="all %d runs stopped at t = %s: %s" % (
                                       len(stopped), " / ".join(t for t, _ in stopped),
                                       stopped[0][1])))
            continue
        r = common(by[name], (50, 100))
        r["status"] = "ok"
        add_windows(r, name, ((10, 100), (50, 100)))
        q_rows.append(r)
    q_rows.sort(key=lambda r: r["Q"])
    write_csv(os.path.join(rep, "qscan.csv"), q_rows,
              "# K = 5, N = 1e4 against the charge scale Q of collisional charging (charging.Q); "
              "Q = 0.05 is the 5-run ensemble to t = 150, the others 2 runs (seeds 1-2) to "
              "t = 100; columns as in kscan.csv")
    return k_rows, q_rows


def write_csv(path, rows, header):
    with open(path, "w") as f:
        f.write(header + "\n")
        if not rows:
            return
        keys = []
        for r in rows:  # rows may differ (a collapsed Q has no numbers): the union, in order
            keys += [k for k in r if k not in keys]
        f.write(",".join(keys) + "\n")
        for r in rows:
            f.write(",".join(cell(r.get(k)) for k in keys) + "\n")


def cell(v):
    if v is None:
        return "nan"
    if isinstance(v, str):
        return v
    return f"{v:.6g}"


# ---------------------------------------------------------------- figures

def figures(have, rep, out):
    by = {p.name: p for p in have}
    # Fig. 5 analogue: S_grid(t) per ensemble with standard errors; beside it (the paper's inset),
    # the local slope of the mean against 1/t.
    fig, (ax, ins) = plt.subplots(1, 2, figsize=(12, 4.8), gridspec_kw={"width_ratios": [1.4, 1]})
    for p in have:
        S = p.table("S_t.csv")
        m = (S["t"] > 0) & np.isfinite(S["S_grid_mean"])
        ax.errorbar(S["t"][m], S["S_grid_mean"][m], yerr=S["S_grid_se"][m], fmt="o-", ms=2.5,
                    lw=0.8, color=p.colour, label=f"{p.label} ({int(p.fits()['runs'])} runs)")
        z = col(S, "z_local_grid_of_mean")
        mz = m & np.isfinite(z) & (S["t"] >= 5)
        ins.plot(1.0 / S["t"][mz], z[mz], ".-", ms=3, lw=0.8, color=p.colour, label=p.label)
    ins.axhline(PAPER["z_neutral"]["value"], color="k", ls="--", lw=0.8,
                label="paper: 1.21 (neutral)")
    ins.axhline(PAPER["z_charged"]["value"], color="k", ls=":", lw=0.8,
                label="paper: 1.49 (charged)")
    ins.set(xscale="log", xlabel="1/t", ylabel="local slope z(t) = ln[S(t)/S(t/2)]/ln 2",
            title="local slope of the mean S (the paper's Fig. 5 inset)")
    ins.legend(fontsize=7)
    ax.set(xscale="log", yscale="log", xlabel="t", ylabel=r"$S_{grid}(t)$ (grid sites)",
           title="mean cluster size, grid clusters (mean $\\pm$ s.e. over runs)")
    ax.legend(fontsize=8, loc="upper left")
    save(fig, rep, "fig_growth")

    # Local slope against t, grid and particle clusters.
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for p in have:
        S = p.table("S_t.csv")
        for ax, c in zip(axs, ("z_local_grid_of_mean", "z_local_particle_of_mean")):
            z = col(S, c)
            if z is None:
                continue
            m = np.isfinite(z) & (S["t"] >= 1)
            ax.plot(S["t"][m], z[m], ".-", ms=3, color=p.colour, label=p.label)
    for ax, what in zip(axs, ("grid clusters", "particle clusters")):
        ax.axhline(1.21, color="k", ls="--", lw=0.7)
        ax.axhline(1.49, color="k", ls=":", lw=0.7)
        ax.set(xscale="log", xlabel="t", title=f"local slope ln[S(t)/S(t/2)]/ln 2, {what}")
    axs[0].set_ylabel("z(t)")
    axs[0].legend(fontsize=7)
    save(fig, rep, "fig_local_slope")

    # N_s(s) at t = 50, 100, 150 (the paper's Fig. 3(b-d)) with the least-squares lines.
    show = [n for n in ("neutral", "charged-K5") if n in by]
    if show:
        fig, axs = plt.subplots(1, 3, figsize=(13, 4), sharey=True)
        for ax, t in zip(axs, FISHER_TIMES):
            for n in show:
                p = by[n]
                ns = p.table("N_s_grid.csv")
                fp = p.table("fisher_pooled.csv")
                if ns is None or fp is None:
                    continue
                k = nearest_row(fp, t)
                if k is None:
                    continue
                tt = fp["t"][k]
                m = np.abs(ns["t"] - tt) < 1e-6 * tt
                s, n_s = ns["s"][m], ns["N_s_mean"][m] * int(p.fits()["runs"])  # summed over runs
                ok = n_s > 0
                ax.loglog(s[ok], n_s[ok], "o", ms=3, color=p.colour, alpha=0.6, label=p.label)
                tau = fp["tau_ls_grid"][k] if "tau_ls_grid" in fp.dtype.names else float("nan")
                if np.isfinite(tau):
                    # line through the log-binned densities' centre of mass
                    sl = np.geomspace(1, s[ok].max(), 20)
                    c = np.exp(np.mean(np.log(n_s[ok]) + tau * np.log(s[ok])))
                    ax.loglog(sl, c * sl**(-tau), "-", color=p.colour, lw=1,
                              label=f"slope {-tau:.2f} (LS), MLE tau {fp['tau_grid'][k]:.2f}")
            ax.set(xlabel="s (grid sites)", title=f"t = {t:g}")
            ax.legend(fontsize=7)
        axs[0].set_ylabel(r"$N_s$ (summed over runs)")
        fig.suptitle("Cluster-size distributions (paper: slopes -2.51 -> -2.45 neutral, "
                     "-1.62 -> -1.34 charged)")
        save(fig, rep, "fig_fisher")

    # Temperature and charge.
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for p in have:
        th = p.table("thermo.csv")
        if th is None:
            continue
        m = th["t"] > 0
        a1.loglog(th["t"][m], th["T_g_mean"][m], "-", color=p.colour, label=p.label)
        if p.K() > 0 and col(th, "mean_abs_q_mean") is not None:
            a2.loglog(th["t"][m], th["mean_abs_q_mean"][m], "-", color=p.colour, label=p.label)
    cool = None
    for p in have:
        cool = read(os.path.join(p.d, "meanfield", "cooling.csv"))
        if cool is not None:
            break
    if cool is not None:
        m = cool["t"] > 0
        a1.loglog(cool["t"][m], cool["T"][m], "k-", lw=0.8, label="kinetic theory, viscoelastic")
        a1.loglog(cool["t"][m], cool["T_haff"][m], "k--", lw=0.8,
                  label="Haff's law, same initial rate")
        tl = np.geomspace(30, 1000, 10)
        a1.loglog(tl, 3 * tl**(-5 / 3), "k:", lw=0.8, label=r"$\propto t^{-5/3}$")
    a1.set(xlabel="t", ylabel=r"$T_g$", title="granular temperature")
    a2.set(xlabel="t", ylabel=r"$\langle|q|\rangle$",
           title="mean absolute charge (collisional charging)")
    a1.legend(fontsize=7)
    a2.legend(fontsize=7)
    save(fig, rep, "fig_temperature_charge")

    # Cluster definition.
    sd = os.path.join(out, "sensitivity")
    if os.path.isdir(sd):
        names = sorted(os.listdir(sd))
        fig, axs = plt.subplots(1, max(1, len(names)), figsize=(6 * max(1, len(names)), 4.2),
                                squeeze=False)
        for ax, name in zip(axs[0], names):
            for i, v in enumerate(sorted(os.listdir(os.path.join(sd, name)))):
                S = read(os.path.join(sd, name, v, "S_t.csv"))
                if S is None:
                    continue
                m = (S["t"] > 0) & np.isfinite(S["S_grid_mean"])
                ax.loglog(S["t"][m], S["S_grid_mean"][m], "-", color=f"C{i}",
                          label=v.replace("_", ", "))
            ax.set(xlabel="t", ylabel="S_grid",
                   title=f"{name}: grid spacing and occupation threshold")
            ax.legend(fontsize=7)
        save(fig, rep, "fig_sensitivity")


    # The charged gas against K and against Q: grid and particle S(t) and the mean charge.
    for fname, names, what in (
            ("fig_kscan", ("charged-K0.25", "charged-K1", "charged-K5"), "K (Q = 0.05)"),
            ("fig_qscan", ("charged-K5-Q0.025", "charged-K5", "charged-K5-Q0.1"), "Q (K = 5)")):
        show = [by[n] for n in names if n in by]
        if len(show) < 2:
            continue
        fig, axs = plt.subplots(1, 3, figsize=(14, 4.2))
        for p in show:
            S, th = p.table("S_t.csv"), p.table("thermo.csv")
            runs = int(p.fits()["runs"])
            m = (S["t"] > 0) & np.isfinite(S["S_grid_mean"])
            lab = f"{p.label} ({runs} runs)"
            axs[0].errorbar(S["t"][m], S["S_grid_mean"][m], yerr=S["S_grid_se"][m], fmt="o-",
                            ms=2.5, lw=0.8, color=p.colour, label=lab)
            if col(S, "S_particle_mean") is not None:
                axs[1].errorbar(S["t"][m], S["S_particle_mean"][m], yerr=S["S_particle_se"][m],
                                fmt="o-", ms=2.5, lw=0.8, color=p.colour, label=lab)
            if th is not None and col(th, "mean_abs_q_mean") is not None:
                mt = th["t"] > 0
                axs[2].loglog(th["t"][mt], th["mean_abs_q_mean"][mt], "-", color=p.colour,
                              label=lab)
        axs[0].set(xscale="log", yscale="log", xlabel="t", ylabel="S_grid (grid sites)",
                   title=f"grid clusters against {what}")
        axs[1].set(xscale="log", yscale="log", xlabel="t", ylabel="S_particle (particles)",
                   title="particle clusters (contact within 1.05 d)")
        axs[2].set(xlabel="t", ylabel=r"$\langle|q|\rangle$", title="mean absolute charge")
        for ax in axs:
            ax.legend(fontsize=7)
        save(fig, rep, fname)


    # Time measured from the onset: S_grid / S_base and the local slope against t / t_c
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.4))
    for p in have:
        S, f = p.table("S_t.csv"), p.fits()
        tc = float(f["onset_time_grid"]) if "onset_time_grid" in f.dtype.names else float("nan")
        base = (float(f["onset_S_base_grid"]) if "onset_S_base_grid" in f.dtype.names
                else float("nan"))
        if not (np.isfinite(tc) and base > 0):
            continue
        m = (S["t"] > 0) & np.isfinite(S["S_grid_mean"])
        lab = f"{p.label} (t_c = {tc:.3g})"
        a1.loglog(S["t"][m] / tc, S["S_grid_mean"][m] / base, "o-", ms=2.5, lw=0.8,
                  color=p.colour, label=lab)
        z = col(S, "z_local_grid_of_mean")
        mz = m & np.isfinite(z) & (S["t"] >= 5)
        a2.plot(S["t"][mz] / tc, z[mz], ".-", ms=3, lw=0.8, color=p.colour, label=lab)
    a1.set(xlabel="t / t_c", ylabel="S_grid / (its median over t <= 10)",
           title="growth against time from the onset")
    a2.set(xscale="log", xlabel="t / t_c", ylabel="local slope of the mean S_grid",
           title="local slope against t / t_c")
    a2.axhline(1.21, color="k", ls="--", lw=0.7)
    a2.axhline(1.49, color="k", ls=":", lw=0.7)
    a1.legend(fontsize=7)
    save(fig, rep, "fig_onset")


def save(fig, rep, name):
    fig.tight_layout()
    fig.savefig(os.path.join(rep, name + ".png"), dpi=110)
    plt.close(fig)


# ---------------------------------------------------------------- verdict

def verdict(have, ens_rows, win_rows, fi_rows, se_rows, rep, missing, k_rows, q_rows):
    by = {r["part"]: r for r in ens_rows}
    csv_rows = []
    lines = ["| quantity | paper | granagg (95 % interval) | agree? | why not / remark |",
             "|---|---|---|---|---|"]

    def zwin(part, t0, t1):
        return window_z(win_rows, part, t0, t1)

    zp = PAPER["z_neutral"]
    for part, t0, t1 in (("neutral", 100, 1000), ("neutral", 631, 1000), ("box", 100, 1000),
                         ("box", 631, 1000)):
        r, e = zwin(part, t0, t1), by.get(part)
        if r is None or e is None:
            continue
        inside = r["z_low"] <= zp["value"] + zp["pm"] and r["z_high"] >= zp["value"] - zp["pm"]
        flat = (np.isfinite(e["zloc_min"])
                and e["zloc_max"] - e["zloc_min"] <= 0.25 * 0.5 * (e["zloc_max"] + e["zloc_min"]))
        lines.append(f"| z, neutral ({part}, t = {t0}..{t1}) | {zp['value']} ± {zp['pm']} | "
                     f"{ival(r['z'], r['z_low'], r['z_high'])} | "
                     f"{'number: yes' if inside else 'no'}"
                     f"{'' if flat else '; curve: no'} | "
                     f"local slope {fmt(e['zloc_min'])}..{fmt(e['zloc_max'])} over "
                     f"the last half decade: {'flat' if flat else 'not a power law (onset)'}; "
                     f"onset t_c = "
                     f"{fmt(e['onset'])} ± {fmt(e['onset_se'], 2)} |")
        csv_rows.append(dict(quantity_id=1 if (part, t0) == ("neutral", 100) else 2,
                             K=0.0, N=e["N"],
                             runs=e["runs"], t_end=e["t_end"], t0=t0, t1=t1,
                             value=r["z"], low=r["z_low"], high=r["z_high"],
                             onset=e["onset"], growth_factor=e["growth"], paper=zp["value"],
                             zloc_min=e["zloc_min"], zloc_max=e["zloc_max"]))
    zc = PAPER["z_charged"]
    for part in ("charged-K5", "charged-K1", "charged-K0.25", "charged-K5-Q0.025",
                 "charged-K5-Q0.1"):
        e = by.get(part)
        if e is None:
            continue
        # the Q scan ends at t = 100; K = 5 at Q = 0.05 is shown over its window too
        windows = (((50, 100), (10, 100)) if "Q" in part
                   else ((50, 150), (10, 150), (50, 100)) if part == "charged-K5"
                   else ((50, 150), (10, 150)))
        for t0, t1 in windows:
            r = zwin(part, t0, t1)
            if r is None:
                continue
            inside = r["z_low"] <= zc["value"] + zc["pm"] and r["z_high"] >= zc["value"] - zc["pm"]
            flat = (np.isfinite(e["zloc_min"])
                    and e["zloc_max"] - e["zloc_min"]
                    <= 0.25 * 0.5 * (e["zloc_max"] + e["zloc_min"]))
            q = e["Q"]
            lines.append(f"| z, charged K = {e['K']:g}, Q = {q:g} (t = {t0}..{t1}) | "
                         f"{zc['value']} ± {zc['pm']} | "
                         f"{ival(r['z'], r['z_low'], r['z_high'])} | {'yes' if inside else 'no'} | "
                         f"local slope "
                         f"{fmt(e['zloc_min'])}..{fmt(e['zloc_max'])} over "
                         f"t = {fmt(e['t_end'] / math.sqrt(10))}.."
                         f"{fmt(e['t_end'])} ({'flat' if flat else 'not flat'}); "
                         f"N = {e['N']:g}, {e['runs']} runs; "
                         f"onset t_c = {fmt(e['onset'])} ± {fmt(e['onset_se'], 2)} |")
            csv_rows.append(dict(quantity_id=1 if (t0, t1) == (50, 150) else 2,
                                 K=e["K"], N=e["N"],
                                 runs=e["runs"], t_end=e["t_end"], t0=t0, t1=t1, value=r["z"],
                                 low=r["z_low"], high=r["z_high"], onset=e["onset"],
                                 growth_factor=e["growth"], paper=zc["value"],
                                 zloc_min=e["zloc_min"], zloc_max=e["zloc_max"]))
    # z against K: the paper finds the same z for K = 0.25, 1 and 5
    kz = [r for r in k_rows if r["K"] > 0 and r.get("z_50_150") is not None]
    if len(kz) >= 2:
        lows, highs = [r["z_50_150_low"] for r in kz], [r["z_50_150_high"] for r in kz]
        overlap = max(lows) <= min(highs)
        lines.append("| z independent of K (t = 50..150) | yes (1.49 for K = 0.25, 1, 5) | " +
                     "; ".join(f"K = {r['K']:g}: "
                               + ival(r["z_50_150"], r["z_50_150_low"], r["z_50_150_high"])
                               for r in kz) +
                     f" | {'intervals overlap' if overlap else 'no: intervals disjoint'} | "
                     "local slope at t = 150: " +
                     ", ".join(f"{fmt(r['zloc_150'])} (K = {r['K']:g})" for r in kz) +
                     "; onset: " + ", ".join(f"{fmt(r['onset'])} ± {fmt(r['onset_se'], 2)}"
                                             for r in kz) + " |")
    # Q: not in the paper; how much the charged results depend on it
    if len(q_rows) >= 2:
        lines.append("| dependence on the charge scale Q (K = 5, t = 100) | Q not given | " +
                     "; ".join((f"Q = {r['Q']:g}: t_c {fmt(r['onset'])} ± "
                                f"{fmt(r['onset_se'], 2)}, S_grid {fmt(r['S_grid_100'])}, "
                                f"<abs q> {fmt(r['mean_abs_q_100'])}") if r["status"] == "ok"
                               else f"Q = {r['Q']:g}: {r['status']}" for r in q_rows) +
                     " | - | qscan.csv; Q = 0.05 is 5 runs, the others 2 |")
    # onset against K
    # an onset not reached by t_end is later than t_end (a lower bound, for the order)
    ks = [(by[p]["K"], by[p]["onset"], by[p]["onset_se"], by[p]["t_end"])
          for p in ("neutral", "charged-K0.25", "charged-K1", "charged-K5") if p in by]
    if len(ks) >= 2:
        ks.sort()
        lower = [t if np.isfinite(t) else te for _, t, _, te in ks]
        mono = all(lower[i] >= lower[i + 1] for i in range(len(ks) - 1))
        lines.append("| onset time t_c against K | falls as K grows | " +
                     ", ".join(f"K = {k:g}: {fmt(t)} ± {fmt(s, 2)}" if np.isfinite(t)
                               else f"K = {k:g}: > {fmt(te)} (not reached)"
                               for k, t, s, te in ks) +
                     f" | {'yes' if mono else 'no'} | t_c: S_grid reaches twice its early median |")
    # Fisher
    fp = {(r["part"], round(r["t"] / 50) * 50): r for r in fi_rows}
    for part, key in (("neutral", "fisher_slope_neutral"), ("charged-K5", "fisher_slope_charged")):
        vals = [fp.get((part, t)) for t in (50, 100, 150)]
        if not any(vals):
            continue
        pv = PAPER[key]
        ls = ", ".join(f"{-v['tau_ls_grid']:.2f}" if v and np.isfinite(v["tau_ls_grid"]) else "n/a"
                       for v in vals)
        ml = ", ".join(f"{-v['tau_grid']:.2f}" if v and np.isfinite(v["tau_grid"]) else "n/a"
                       for v in vals)
        lines.append(f"| Fisher slope, {part} (t = 50, 100, 150) | {pv['t50']} -> {pv['t150']} | "
                     f"LS: {ls}; MLE: {ml} | "
                     f"see text | printed as -tau; LS = least squares on log-binned N_s "
                     f"(the paper's method) |")
        e = by.get(part, {})
        for t, v in zip((50, 100, 150), vals):
            if not v:
                continue
            # t_end: the ensemble's last frame, as in the z rows; the frame is t0 = t1. paper: its
            # slope at this t (paper.json has t = 50 and 150; nan at t = 100)
            csv_rows.append(dict(quantity_id=3, K=e.get("K", float("nan")),
                                 N=e.get("N", float("nan")), runs=e.get("runs", 0),
                                 t_end=e.get("t_end", float("nan")), t0=v["t"], t1=v["t"],
                                 value=-v["tau_ls_grid"],
                                 low=-v["tau_ls_grid"] - 1.96 * v["tau_ls_grid_err"],
                                 high=-v["tau_ls_grid"] + 1.96 * v["tau_ls_grid_err"],
                                 onset=float("nan"), growth_factor=float("nan"),
                                 paper=pv.get(f"t{t}", float("nan")),
                                 zloc_min=float("nan"), zloc_max=float("nan")))
    # charging exponent
    ce = PAPER["charging_rate_exponent"]
    for part in ("charged-K5", "charged-K1", "charged-K0.25", "neutral"):
        e = by.get(part)
        if e is None or not np.isfinite(e["charging"]):
            continue
        lines.append(f"| charging rate exponent, {part} (t = 1..100) | "
                     f"-13/6 = {ce['value']:.3f} (kappa = 0.8); "
                     f"{e['charging_expected']:.3f} at kappa = 0.83 | "
                     f"{ival(e['charging'], e['charging_low'], e['charging_high'])} | "
                     f"""{'yes' if e['charging_low'] <= e['charging_expected']
                             <= e['charging_high'] else 'no'} | """
                     f"""{'Coulomb off (K = 0): charges exchanged but no force'
                          if e['K'] == 0 else ''} |""")
    # cooling
    for p in have:
        th = p.table("thermo.csv")
        if th is None:
            continue
        for lo, hi in ((20, 200), (300, 1000)) if p.K() == 0 else ((10, 50), (50, 150)):
            s = late_slope(th["t"], th["T_g_mean"], lo, hi)
            if not np.isfinite(s):
                continue
            lines.append(f"| T_g exponent, {p.name} (t = {lo}..{hi}) | -5/3 = -1.667 "
                         f"(viscoelastic, neutral, homogeneous) | {fmt(s)} | "
                         f"{'yes' if abs(s + 5 / 3) < 0.1 else 'no'} | "
                         f"least squares of ln T_g on ln t (a check, in Python) |")
    # beta
    for p in have:
        fb = p.fit_beta()
        if not fb:
            continue
        lines.append(f"| beta ({p.name}; fit-beta, window "
                     f"{fmt(fb.get('t0'))}..{fmt(fb.get('t1'))}) | "
                     f"{'2 (z = 6/5)' if p.K() == 0 else '3 (z = 3/2)'} | asymptotic: "
                     f"""{ival(fb.get('beta_asymptotic'), fb.get('beta_asymptotic_low'),
                               fb.get('beta_asymptotic_high'))}; """
                     f"""at the data's S: {ival(fb.get('beta_from_z'), fb.get('beta_from_z_low'),
                                                fb.get('beta_from_z_high'))}; """
                     f"""curve fit: {'not determined' if not fb.get('beta_fit_determined', True)
                                     else fmt(fb.get('beta_fit'))} | """
                     f"see text | z = {ival(fb.get('z'), fb.get('z_low'), fb.get('z_high'))}; "
                     f"regime at the end: "
                     f"{p.ens.get('regime', '?')} (the asymptotic map needs a scaling regime) |")
    # sensitivity summary
    for r in se_rows:
        lines.append(f"| z, {r['part']}, grid {r['variant']} "
                     f"(t = {fmt(r['t0'])}..{fmt(r['t1'])}) | - | "
                     f"{ival(r['fb_z'], r['fb_z_low'], r['fb_z_high'])} | - | "
                     f"onset {fmt(r['onset'])}, S_end "
                     f"{fmt(r['S_end'])}, local slope {fmt(r['zloc_min'])}..{fmt(r['zloc_max'])}; "
                     f"Fisher slope (LS) "
                     f"{fmt(r['fisher_ls_t50'])} (t = 50), {fmt(r['fisher_ls_t150'])} (150), "
                     f"{fmt(r['fisher_ls_end'])} "
                     f"(end); occupied {fmt(r['occupied'], 2)} |")
    if missing:
        lines.append(f"\nParts not (yet) run: {', '.join(missing)} "
                     f"(rerun scripts/validate.sh to resume).")
    with open(os.path.join(rep, "verdict.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    write_csv(os.path.join(rep, "verdict.csv"), csv_rows,
              "# validation study verdict numbers (scripts/validation_report.py; "
              "docs/validation.md); quantity_id 1 = the headline z of an ensemble "
              "(granagg pair prints it beside a demo), 2 = other windows of z, 3 = Fisher slopes "
              "(-tau, log-binned least squares, at the frame t0 = t1; paper: the paper's slope "
              "at that t, nan where it prints none); numeric columns only "
              "(granagg's common::readCsv reads it)")
    # quantity_id 4-6, "What S measures": from the committed tables of s_dominance.py
    d_rows, d_lines = dominance_verdict.rows(os.path.join(ROOT, "docs", "validation"))
    dominance_verdict.rewrite_csv(os.path.join(rep, "verdict.csv"), d_rows)
    dominance_verdict.rewrite_md(os.path.join(rep, "verdict.md"), d_lines)


if __name__ == "__main__":
    sys.exit(main())
