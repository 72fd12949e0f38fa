#!/usr/bin/python3
"""The paper's figures (Singh & Mazza 2018, Figs. 1-8) from a `granagg pair` results folder.

usage: /usr/bin/python3 scripts/plot_figures.py PAIR_DIR

Reads PAIR_DIR/summary.json, analysis/K<K>/*.csv (docs/analysis.md), meanfield/*.csv,
fit/K<K>/fit_curve.csv and runs/K<K>/run0/traj.h5, and writes one figure per file into
PAIR_DIR/figures/ (figN_<name>.png and .pdf):

  fig1_temperature   T_g(t) of each ensemble with Haff's law and the viscoelastic cooling law
  fig2_snapshots     projected slab (|z - L/2| < 2 d) of run 0 at three times, neutral and charged
  fig3_nstick        N_stick of the tracked particles (contacts within 1 + tolerance)
  fig4_charge        mean |q|(t), its rate against the t^(-a(1/2+kappa)) law, N_s(s) at three times
  fig5_growth        S(t) with the power-law fit where the summary reports a z (and the fitted
                     mean field where beta is determined), local slope below
  fig6_meanfield     MD against mean-field S(t) (fit-beta's fitted curve where beta is
                     determined), MSD beside
  fig7_speed         f(v~) against the Maxwellian at the first and last frames
  fig8_charge_speed  (q~, v~) scatter of the last analysed frame, charged ensembles

No curve of an undetermined quantity is drawn: no power law where S(t) is none (summary.json
"z_reported"), no fitted mean field where beta lies at a bound of its search range.
A missing input (no charged ensemble, no fit-beta output...) leaves a note in that panel; the
script does not fail for it. Exit status 1 only when a figure failed for another reason (the
figure then holds the error). Debian's python3-matplotlib, python3-numpy and python3-h5py only.
"""
import json
import os
import sys
import traceback

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import EllipseCollection  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from granagg_tables import col, paper, read  # noqa: E402

FAILED = []


def note(ax, text):
    """Marks a panel whose input is missing."""
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", fontsize=9,
            color="0.3", wrap=True)


class Study:
    def __init__(self, d):
        self.d = d
        self.summary = {}
        if os.path.exists(f"{d}/summary.json"):
            with open(f"{d}/summary.json") as f:
                self.summary = json.load(f)
        ens = self.summary.get("ensembles", [])
        if ens:
            self.ks = [(e["name"], float(e["K"])) for e in ens]
        else:  # no summary: the analysis folders
            names = sorted(os.listdir(f"{d}/analysis")) if os.path.isdir(f"{d}/analysis") else []
            self.ks = [(n, float(n[1:])) for n in names
                       if n.startswith("K") and os.path.isdir(f"{d}/analysis/{n}")]

    def table(self, name, kname):
        return read(f"{self.d}/analysis/{kname}/{name}.csv")

    def neutral(self):
        return [k for k in self.ks if k[1] == 0]

    def charged(self):
        return [k for k in self.ks if k[1] > 0]

    def label(self, k):
        return "neutral (K = 0)" if k[1] == 0 else f"charged (K = {k[1]:g})"


def readable_log(ax, axis="y"):
    """A log axis over less than about a decade gets a few plain tick labels ("1.2", not "1.2x10^0"
    or "10^0" five times); wider ranges keep matplotlib's decades."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter

    lo, hi = ax.get_ylim() if axis == "y" else ax.get_xlim()
    if not (lo > 0 and hi / lo < 15):
        return
    if hi / lo < 1.5:  # (nearly) constant data, e.g. S = 1 before any cluster: show +-25 %
        mid = np.sqrt(lo * hi)
        lo, hi = mid / 1.25, mid * 1.25
        (ax.set_ylim if axis == "y" else ax.set_xlim)(lo, hi)
    a = ax.yaxis if axis == "y" else ax.xaxis
    # round numbers inside the range, thinned to at most 6
    nice = (1, 1.1, 1.2, 1.3, 1.5, 1.7, 2, 2.5, 3, 4, 5, 6, 7, 8, 9)
    e0 = int(np.floor(np.log10(lo)))
    ticks = [m * 10.0**e for e in (e0, e0 + 1) for m in nice if lo <= m * 10.0**e <= hi]
    ticks = ticks[:: max(1, int(np.ceil(len(ticks) / 6)))]
    a.set_major_locator(FixedLocator(ticks))
    a.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    a.set_minor_formatter(NullFormatter())


def beta_determined(e):
    """Whether the summary holds a full-curve beta that is a result. A beta at a bound of fit-beta's
    search range is not one: summary.json then says beta_fit_determined = false (older folders
    still carry the bound as the value), and its curve is not drawn."""
    b = (e.get("beta_fit") or {}).get("value")
    return b is not None and bool(e.get("beta_fit_determined", False))


def beta_label(e):
    """The legend entry of a fitted mean-field curve (drawn only where beta_determined(e))."""
    return f"mean field, fitted beta = {e['beta_fit']['value']:.3g}"


def reported_z(e):
    """The growth exponent the summary reports (summary.json "z_reported"): a dict with status
    "power law", value, low, high and window, or another status and the text that says why there is
    no z. Folders written before z_reported existed: analyze's z, only in a scaling regime."""
    if "z_reported" in e:
        return e["z_reported"]
    zi = e.get("z_analyze") or {}
    if e.get("regime") == "scaling" and zi.get("value") is not None:
        return dict(status="power law", window=e.get("z_analyze_window"), **zi)
    return {"status": e.get("regime", "unknown"),
            "text": f"regime: {e.get('regime', 'unknown')}, no z"}


def colors(i):
    return ["C0", "C3", "C2", "C1", "C4", "C5"][i % 6]


def save(fig, out, name):
    os.makedirs(out, exist_ok=True)
    fig.savefig(f"{out}/{name}.png", dpi=130, bbox_inches="tight")
    fig.savefig(f"{out}/{name}.pdf", bbox_inches="tight")
    plt.close(fig)


def fig1(st, fig):
    ax = fig.add_subplot(111)
    cool = read(f"{st.d}/meanfield/cooling.csv")
    any_md = False
    for i, k in enumerate(st.ks):
        th = st.table("thermo", k[0])
        if th is None:
            continue
        m = th["t"] > 0
        ax.errorbar(th["t"][m], th["T_g_mean"][m], yerr=th["T_g_se"][m], fmt="o", ms=3,
                    color=colors(i), label=f"MD, {st.label(k)}")
        any_md = True
    if cool is not None:
        m = cool["t"] > 0
        ax.plot(cool["t"][m], cool["T"][m], "k-", label="kinetic theory, viscoelastic e(g)")
        ax.plot(cool["t"][m], cool["T_haff"][m], "k--", label="Haff's law (same initial rate)")
        tail = m & np.isfinite(cool["T_asymptote"]) & (cool["T_asymptote"] < 2)
        ax.plot(cool["t"][tail], cool["T_asymptote"][tail], "k:", label=r"$t^{-5/3}$ asymptote")
    else:
        note(ax, "meanfield/cooling.csv missing (granagg kinetic cooling)")
    if not any_md:
        note(ax, "no analysis/K*/thermo.csv: no MD ensemble analysed")
    ax.set(xscale="log", yscale="log", xlabel="t", ylabel=r"$T_g$",
           title="Fig. 1: granular temperature")
    ax.legend(fontsize=8)


def load_frames(path, wanted):
    import h5py

    with h5py.File(path, "r") as f:
        pos = f["particles/all/position"]
        times = pos["time"][:]
        edges = f["particles/all/box/edges"]
        box = edges["value"][0] if isinstance(edges, h5py.Group) else edges[()]
        L = float(np.atleast_1d(box).ravel()[0])
        charge = f["particles/all/charge/value"] if "charge" in f["particles/all"] else None
        out = []
        for t in wanted:
            i = int(np.argmin(np.abs(times - t)))
            q = (charge[i] if charge is not None and charge.ndim == 2 and i < charge.shape[0]
                 else None)
            out.append((times[i], pos["value"][i], q))
        return L, out


def fig2(st, fig):
    rows = [k for k in (st.neutral()[:1] + st.charged()[-1:])]
    if not rows:
        note(fig.add_subplot(111), "no ensembles")
        return
    for r, k in enumerate(rows):
        path = f"{st.d}/runs/{k[0]}/run0/traj.h5"
        if not os.path.exists(path):
            note(fig.add_subplot(len(rows), 1, r + 1), f"{path} missing")
            continue
        import h5py

        with h5py.File(path, "r") as f:
            times = f["particles/all/position/time"][:]
        if len(times) == 0:  # analysed during the run, frames not kept
            note(fig.add_subplot(len(rows), 1, r + 1),
                 f"{path}: no particle frames stored (granagg pair --keep-trajectories keeps them)")
            continue
        tt = times[times > 0]
        wanted = [tt[0], np.sqrt(tt[0] * tt[-1]), tt[-1]] if len(tt) else [times[0]]
        L, frames = load_frames(path, wanted)
        coloured = k[1] > 0 and all(q is not None for _, _, q in frames)
        # one colour scale for the row, so that the three times compare
        qs = max(float(np.max(np.abs(q))) for _, _, q in frames) if coloured else 1.0
        axes = []
        for c, (t, x, q) in enumerate(frames):
            ax = fig.add_subplot(len(rows), 3, 3 * r + c + 1)
            axes.append(ax)
            slab = np.abs(x[:, 2] - L / 2) < 2.0
            # particles drawn at their true size (diameter 1 in data units)
            ec = EllipseCollection(np.ones(slab.sum()), np.ones(slab.sum()), np.zeros(slab.sum()),
                                   units="xy", offsets=x[slab, :2], offset_transform=ax.transData,
                                   edgecolors="k", linewidths=0.3)
            if coloured:
                ec.set_array(q[slab])
                ec.set_cmap("coolwarm")
                ec.set_clim(-(qs or 1.0), qs or 1.0)
            else:
                ec.set_facecolor("0.6")
            ax.add_collection(ec)
            ax.set(xlim=(0, L), ylim=(0, L), aspect="equal", title=f"{st.label(k)}, t = {t:.3g}",
                   xlabel="x / d")
            if c == 0:
                ax.set_ylabel("y / d")
            ax.tick_params(labelsize=7)
        if coloured:
            cb = fig.colorbar(ec, ax=axes, shrink=0.8, pad=0.02)
            cb.set_label("charge q (same scale for the three times)")
    fig.suptitle("Fig. 2: slab |z - L/2| < 2 d of run 0 projected on (x, y); "
                 "particles at their true size")


def fig3(st, fig):
    ax = fig.add_subplot(111)
    drawn = False
    for i, k in enumerate(st.ks):
        ns = st.table("nstick", k[0])
        if ns is None:
            continue
        ids = [n for n in ns.dtype.names if n.startswith("n_stick_id") and n.endswith("_mean")]
        for j, n in enumerate(ids):
            ax.plot(ns["t"], ns[n], "-", color=colors(i), alpha=0.25, lw=0.8,
                    label=f"tracked particles, {st.label(k)}" if j == 0 else None)
        if "n_stick_mean_mean" in ns.dtype.names:
            ax.plot(ns["t"], ns["n_stick_mean_mean"], "o-", ms=3, color=colors(i),
                    label=f"mean over tracked, {st.label(k)}")
        drawn = True
    if not drawn:
        note(ax, "no analysis/K*/nstick.csv")
    ax.set(xscale="log", xlabel="t", ylabel=r"$N_{stick}$",
           title="Fig. 3: contacts of tracked particles")
    ax.legend(fontsize=8)


def fig4(st, fig):
    ax1, ax2, ax3 = fig.add_subplot(131), fig.add_subplot(132), fig.add_subplot(133)
    ch = read(f"{st.d}/meanfield/charging.csv")
    expo = float(ch["charging_rate_exponent"][0]) if ch is not None else None
    drawn = False
    for i, k in enumerate(st.charged()):
        th = st.table("thermo", k[0])
        if th is None:
            continue
        m = th["t"] > 0
        t, q = th["t"][m], th["mean_abs_q_mean"][m]
        ax1.errorbar(t, q, yerr=th["mean_abs_q_se"][m], fmt="o-", ms=3, color=colors(i + 1),
                     label=st.label(k))
        rate = np.diff(q) / np.diff(t)
        tm = np.sqrt(t[1:] * t[:-1])
        good = rate > 0
        ax2.loglog(tm[good], rate[good], "o", ms=3, color=colors(i + 1), label=f"MD, {st.label(k)}")
        if expo is not None and good.sum() > 1:
            ref = tm[good][len(tm[good]) // 2]
            c = np.interp(ref, tm[good], rate[good]) / ref**expo
            tl = np.geomspace(tm[good].min(), tm[good].max(), 50)
            ax2.loglog(tl, c * tl**expo, "k--",
                       label=rf"kinetic theory $t^{{{expo:.3g}}}$, matched to MD at t = {ref:.3g}")
            ax2.plot([ref], [c * ref**expo], "kx", ms=7)
        drawn = True
    if not drawn:
        note(ax1, "no charged ensemble (K > 0)")
        note(ax2, "no charged ensemble (K > 0)")
    ax1.set(xscale="log", xlabel="t", ylabel=r"$\langle|q|\rangle$", title="mean |q|")
    ax2.set(xlabel="t", ylabel=r"d$\langle|q|\rangle$/dt", title="charging rate")
    ax1.legend(fontsize=8)
    ax2.legend(fontsize=8)
    drawn = False
    for i, k in enumerate(st.ks):
        ng = st.table("N_s_grid", k[0])
        if ng is None:
            continue
        ts = np.unique(ng["t"][ng["t"] > 0])
        if len(ts) == 0:
            continue
        pick = sorted(set([ts[0], ts[len(ts) // 2], ts[-1]]))
        for j, t in enumerate(pick):
            m = (ng["t"] == t) & (ng["N_s_mean"] > 0)
            # each time its own marker and line style: the legend tells them apart
            ax3.loglog(ng["s"][m], ng["N_s_mean"][m], marker="os^"[j % 3],
                       ls=["-", "--", ":"][j % 3], ms=4,
                       mfc="none" if j == 1 else colors(i), lw=1.2, color=colors(i),
                       label=f"{st.label(k)}, t = {t:.3g}")
        drawn = True
    if not drawn:
        note(ax3, "no analysis/K*/N_s_grid.csv")
    ax3.set(xlabel="s (grid sites)", ylabel=r"$N_s$ (clusters per frame)",
            title="cluster-size distribution")
    ax3.legend(fontsize=7, loc="upper right", handlelength=3)
    for a in (ax1, ax2, ax3):
        a.tick_params(labelsize=8)
    fig.suptitle("Fig. 4: charge build-up and N_s(s) at three times")


def powerfit(t, S, lo, hi):
    m = (t >= lo) & (t <= hi) & (S > 0) & np.isfinite(S)
    if m.sum() < 2:
        return None
    z, c = np.polyfit(np.log(t[m]), np.log(S[m]), 1)
    return z, c, t[m]


def fig5(st, fig):
    # the local slope in a panel of its own below (an inset covered the late-time data)
    ax, ins = fig.subplots(2, 1, sharex=True,
                           gridspec_kw={"height_ratios": [2.2, 1], "hspace": 0.06})
    drawn = False
    ens = {e["name"]: e for e in st.summary.get("ensembles", [])}
    for i, k in enumerate(st.ks):
        S = st.table("S_t", k[0])
        if S is None:
            continue
        m = (S["t"] > 0) & np.isfinite(S["S_grid_mean"])
        t, s = S["t"][m], S["S_grid_mean"][m]
        e = ens.get(k[0], {})
        zr = reported_z(e) if e else {"status": "unknown"}
        # A power-law line only where the summary reports a z (a flat local slope, an interval
        # above 0); otherwise the legend says why there is none.
        why = "" if zr.get("status") == "power law" or not zr.get("text") else f"; z: {zr['text']}"
        ax.errorbar(t, s, yerr=S["S_grid_se"][m], fmt="o", ms=3, color=colors(i),
                    label=f"MD, {st.label(k)}{why}")
        win = zr.get("window") or [None, None]
        if zr.get("status") == "power law" and None not in win:
            f = powerfit(t, s, win[0], win[1])
            if f:
                _, c, tw = f
                z = zr["value"]
                c = np.mean(np.log(s[(t >= tw[0]) & (t <= tw[-1])])
                            - z * np.log(tw))  # the reported z
                lab = (f"power law over t = {win[0]:.3g}..{win[1]:.3g}: "
                       f"z = {z:.3g} [{zr['low']:.3g}, {zr['high']:.3g}]")
                ax.plot(tw, np.exp(c) * tw**z, "-", color=colors(i), lw=2, label=lab)
        fc = read(f"{st.d}/fit/{k[0]}/fit_curve.csv")
        if beta_determined(e) and fc is not None and col(fc, "S_mf_fitted") is not None:
            ax.plot(fc["t"], fc["S_mf_fitted"], "--", color=colors(i), label=beta_label(e))
        zl = col(S, "z_local_grid_of_mean")
        if zl is not None:
            ins.plot(S["t"], zl, ".-", color=colors(i), ms=3, label=st.label(k))
        drawn = True
    if not drawn:
        note(ax, "no analysis/K*/S_t.csv")
    zn, zc = paper()["z_neutral"]["value"], paper()["z_charged"]["value"]
    ins.axhline(zn, color="C0", ls=":", lw=0.8, label=f"paper: z = {zn} (neutral)")
    ins.axhline(zc, color="C3", ls=":", lw=0.8, label=f"paper: z = {zc} (charged)")
    ins.set(xscale="log", xlabel="t", ylabel="local slope z(t)")
    ins.legend(fontsize=7, loc="upper left", ncol=2)
    ax.set(xscale="log", yscale="log", ylabel="S (grid sites)",
           title="Fig. 5: mean cluster size S(t); below: its local slope d ln S / d ln t")
    readable_log(ax)
    ax.legend(fontsize=8, loc="upper left")


def fig6(st, fig):
    # the MSD in a panel of its own at the right (an inset covered the late-time data)
    ax, ins = fig.subplots(1, 2, gridspec_kw={"width_ratios": [2, 1], "wspace": 0.3})
    ens = {e["name"]: e for e in st.summary.get("ensembles", [])}
    drawn = False
    undetermined = []
    for i, k in enumerate(st.ks):
        fc = read(f"{st.d}/fit/{k[0]}/fit_curve.csv")
        S = st.table("S_t", k[0])
        e = ens.get(k[0], {})
        if fc is not None and col(fc, "S_md") is not None and beta_determined(e):
            ax.plot(fc["t"], fc["S_md"], "o", ms=3, color=colors(i), label=f"MD, {st.label(k)}")
            ax.plot(fc["t"], fc["S_mf_fitted"], "-", color=colors(i),
                    label=beta_label(e) + " (S_c, tau_c fitted)")
            drawn = True
        elif S is not None:
            # no fitted beta (fit-beta not run, or beta at a bound of its range): the MD data alone
            why = "no fit-beta output" if fc is None else "beta not determined, no fitted curve"
            if fc is not None:
                undetermined.append(f"K = {k[1]:g}")
            m = S["t"] > 0
            ax.plot(S["t"][m], S["S_grid_mean"][m], "o", ms=3, color=colors(i),
                    label=f"MD, {st.label(k)} ({why})")
        msd = st.table("msd", k[0])
        if msd is not None:
            m = msd["t"] > 0
            ins.loglog(msd["t"][m], msd["msd_mean"][m], "-", color=colors(i), label=st.label(k))
    ax2 = None
    for b, ls in ((2, ":"), (3, "-.")):
        mf = read(f"{st.d}/meanfield/S_beta{b}.csv")
        if mf is not None and not drawn:
            ax2 = ax2 or ax.twiny()
            m = (mf["t"] > 0) & (mf["S"] < 1e4)
            ax2.loglog(mf["t"][m], mf["S"][m], "k" + ls,
                       label=f"mean field beta = {b} (top axis: t in 1/(K0 n1(0)))")
            ax2.legend(fontsize=7, loc="lower right")
    if not drawn:
        note(ax, (f"beta not determined ({', '.join(undetermined)}): no fitted mean-field curve"
                  if undetermined else "fit/K*/fit_curve.csv missing (granagg fit-beta not run)")
             + ":\nMD and mean field shown on their own time axes")
    ins.set(xlabel="t", ylabel=r"MSD / $d^2$", title="mean squared displacement")
    if ins.lines:
        ins.legend(fontsize=7)
    ax.set(xscale="log", yscale="log", xlabel="t", ylabel="S (grid sites)",
           title="Fig. 6: MD against mean-field S(t)")
    readable_log(ax)
    ax.legend(fontsize=8, loc="upper left")


def fig7(st, fig):
    ax = fig.add_subplot(111)
    drawn = False
    for i, k in enumerate(st.ks):
        sp = st.table("speed_dist", k[0])
        if sp is None:
            continue
        ts = np.unique(sp["t"])
        for j, t in enumerate([ts[0], ts[-1]] if len(ts) > 1 else ts):
            m = sp["t"] == t
            v = 0.5 * (sp["v_low"][m] + sp["v_high"][m])
            ax.plot(v, sp["f_mean"][m], "o" if j else "s", ms=3,
                    mfc="none" if j == 0 else colors(i), color=colors(i),
                    label=f"{st.label(k)}, t = {t:.3g}")
            if not drawn:
                ax.plot(v, sp["f_maxwell_mean"][m], "k-", label="Maxwellian")
            drawn = True
    if not drawn:
        note(ax, "no analysis/K*/speed_dist.csv")
    ax.set(yscale="log", ylim=(1e-4, 2), xlabel=r"$\tilde v = v/\langle v^2\rangle^{1/2}$",
           ylabel=r"$f(\tilde v)$", title="Fig. 7: speed distribution against the Maxwellian")
    ax.legend(fontsize=8)


def fig8(st, fig):
    ax = fig.add_subplot(111)
    drawn = False
    for i, k in enumerate(st.charged()):
        cs = read(f"{st.d}/analysis/{k[0]}/per_run/charge_speed.csv")
        if cs is None:
            continue
        ax.scatter(cs["q_tilde"], cs["v_tilde"], s=4, alpha=0.5, color=colors(i + 1), linewidths=0,
                   label=f"{st.label(k)}, t = {np.max(cs['t']):.3g}, all runs")
        drawn = True
    if not drawn:
        note(ax, "no charged ensemble (K > 0): no charge-speed data")
    ax.set(xlabel=r"$\tilde q = q/\langle q^2\rangle^{1/2}$", ylabel=r"$\tilde v$",
           title="Fig. 8: charge-speed scatter")
    if drawn:
        ax.legend(fontsize=8)


FIGURES = [("fig1_temperature", fig1, (7, 5)), ("fig2_snapshots", fig2, (12, 8)),
           ("fig3_nstick", fig3, (7, 5)), ("fig4_charge", fig4, (16, 4.8)),
           ("fig5_growth", fig5, (7.5, 7)), ("fig6_meanfield", fig6, (12, 5)),
           ("fig7_speed", fig7, (7, 5)), ("fig8_charge_speed", fig8, (6, 5))]


def main():
    if len(sys.argv) != 2 or not os.path.isdir(sys.argv[1]):
        sys.exit("usage: plot_figures.py PAIR_DIR (a `granagg pair` results folder)")
    st = Study(sys.argv[1])
    out = f"{st.d}/figures"
    for name, fn, size in FIGURES:
        fig = plt.figure(figsize=size)
        try:
            fn(st, fig)
        except Exception as e:  # draw what failed into the figure, go on with the others
            FAILED.append(name)
            traceback.print_exc()
            fig.clf()
            note(fig.add_subplot(111), f"{name} failed: {type(e).__name__}: {e}")
        save(fig, out, name)
        print(f"plot_figures: wrote {out}/{name}.png")
    if FAILED:
        sys.exit(f"plot_figures: {len(FAILED)} figure(s) failed: {', '.join(FAILED)}")


if __name__ == "__main__":
    main()
