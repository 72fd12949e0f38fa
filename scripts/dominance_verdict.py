#!/usr/bin/python3
"""The verdict rows of "What S measures" (docs/validation.md): from the committed tables of
scripts/s_dominance.py (docs/validation/dominance_*.csv, one row per frame time with the mean and
standard error over the runs), per ensemble

  quantity_id 4  local slope of S_grid without the largest cluster
  quantity_id 5  the largest cluster's share of the occupied grid sites at the last frame
  quantity_id 6  local slope of the density length l(t)

For 4 and 6, `value` is the mean local slope over the flattest window of at least half a decade
(t1 / t0 >= sqrt(10), frames with t >= T_MIN), `low` and `high` the smallest and largest mean
local slope in that window, and zloc_min, zloc_max the range over all frames with t >= T_MIN.
Flattest: the smallest range relative to the midrange (max + min) / 2; flat: a range of at most
25 % of the midrange (the rule of the z rows, validation_report.py). For 5, `value` is the mean
share at the last frame and low, high its 95 % interval (1.96 standard errors over the runs).
`paper` is the paper's z (1.21 neutral, 1.49 charged) for 4 and nan otherwise: the paper reports
no such quantity.

    /usr/bin/python3 scripts/dominance_verdict.py ROOT

rewrites the rows with quantity_id 4-6 of ROOT/docs/validation/verdict.csv and
ROOT/data/validation/verdict.csv, and the section between the markers in
ROOT/docs/validation/verdict.md; the other rows are kept as scripts/validation_report.py wrote them
(its study folder need not exist). validation_report.py calls rows() as well, so that a rerun of
the whole study keeps these rows.
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from granagg_tables import load_json, read  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
PAPER = load_json(os.path.join(HERE, "..", "data", "reference", "paper.json"))
T_MIN = 50.0
HALF_DECADE = math.sqrt(10.0)
FLAT = 0.25
HEAD_4_6 = ("# quantity_id 4-6 (scripts/dominance_verdict.py, from "
            "docs/validation/dominance_*.csv): "
            "4 = local slope of S_grid without the largest cluster, 6 = local slope of the density "
            "length l (value: mean over the flattest half decade t0..t1, low/high: its range; "
            "zloc_min/max: range over t >= 50), 5 = the largest cluster's share of the occupied "
            "sites at t_end (low/high: 95 % interval over the runs)")
BEGIN = "<!-- dominance rows (scripts/dominance_verdict.py) -->"
END = "<!-- end of dominance rows -->"

# table in docs/validation (one ensemble; its n_runs column gives the runs), label, K, N
ENSEMBLES = [
    ("dominance_neutral_20runs.csv", "neutral, L = 70 (paper's N)", 0.0, 50016),
    ("dominance_box_L140.csv", "neutral, L = 140", 0.0, 400128),
    ("dominance_charged-K5-N50016-t1000.csv", "charged K = 5, L = 70 (paper's N)", 5.0, 50016),
]


def flattest(t, z):
    """(t0, t1, mean, lo, hi, flat) of the window of at least half a decade (every window of
    consecutive frames with finite slopes is tried) whose local slope has the smallest range
    relative to its midrange; None without such a window."""
    best = None
    for i in range(len(t)):
        for j in range(i + 1, len(t)):
            w = z[i:j + 1]
            if not np.all(np.isfinite(w)):
                break
            if t[j] / t[i] < HALF_DECADE:
                continue
            lo, hi = float(np.min(w)), float(np.max(w))
            mid = 0.5 * (lo + hi)
            score = (hi - lo) / abs(mid) if mid != 0 else math.inf
            if best is None or score < best[0]:
                best = (score, t[i], t[j], float(np.mean(w)), lo, hi)
    if best is None:
        return None
    score, t0, t1, m, lo, hi = best
    return t0, t1, m, lo, hi, score <= FLAT


def rows(docs_validation):
    """verdict.csv rows (dicts) and verdict.md lines of every ensemble whose table exists."""
    csv_rows, lines = [], []
    for name, label, K, N in ENSEMBLES:
        tab = read(os.path.join(docs_validation, name))
        if tab is None:
            continue
        runs = int(tab["n_runs"][-1])
        t = np.asarray(tab["t"], float)
        keep = t >= T_MIN
        t_end = float(t[-1])
        z_paper = PAPER["z_neutral" if K == 0 else "z_charged"]["value"]
        for qid, col, what in ((4, "z_S_grid_without_largest_mean",
                                "local slope of S_grid without the largest cluster"),
                               (6, "z_l_density_mean", "local slope of the density length l")):
            z = np.asarray(tab[col], float)[keep]
            tk = t[keep]
            w = flattest(tk, z)
            zmin, zmax = float(np.nanmin(z)), float(np.nanmax(z))
            if w is None:
                continue
            t0, t1, m, lo, hi, flat = w
            csv_rows.append(dict(quantity_id=qid, K=K, N=N, runs=runs, t_end=t_end, t0=t0,
                                 t1=t1, value=m, low=lo, high=hi, onset=math.nan,
                                 growth_factor=math.nan,
                                 paper=z_paper if qid == 4 else math.nan, zloc_min=zmin,
                                 zloc_max=zmax))
            paper = f"z = {z_paper} (of S)" if qid == 4 else "not reported"
            remark = ("a growth law only if it holds at other k cut-offs and boxes"
                      if qid == 6 and flat else "")
            lines.append(f"| {what}, {label}, {runs} runs | {paper} | flattest half decade "
                         f"t = {t0:.4g}..{t1:.4g}: mean {m:.3g} (range {lo:.3g}..{hi:.3g}); "
                         f"over t = {T_MIN:g}..{t_end:.4g}: {zmin:.3g}..{zmax:.3g} | "
                         f"{'flat' if flat else 'not flat'} | {remark} |")
        share = float(tab["largest_share_grid_mean"][-1])
        se = float(tab["largest_share_grid_se"][-1])
        csv_rows.append(dict(quantity_id=5, K=K, N=N, runs=runs, t_end=t_end, t0=t_end,
                             t1=t_end, value=share, low=share - 1.96 * se,
                             high=share + 1.96 * se, onset=math.nan, growth_factor=math.nan,
                             paper=math.nan, zloc_min=math.nan, zloc_max=math.nan))
        lines.append(f"| largest cluster's share of the occupied sites, {label}, t = {t_end:.4g}"
                     f" | not reported | {share:.3f} ± {1.96 * se:.3f} | – | S_grid is mostly "
                     f"one cluster when the share is large |")
    return csv_rows, lines


def cell(v):
    if isinstance(v, float):
        return "nan" if not math.isfinite(v) else f"{v:.6g}"
    return str(v)


def rewrite_csv(path, new_rows):
    with open(path) as f:
        text = f.read().splitlines()
    head = [x for x in text if x.startswith("#") and not x.startswith(HEAD_4_6[:24])]
    head.append(HEAD_4_6)
    body = [x for x in text if not x.startswith("#")]
    keys = body[0].split(",")
    kept = [x for x in body[1:] if x.split(",")[0] not in ("4", "5", "6")]
    with open(path, "w") as f:
        f.write("\n".join(head + [body[0]] + kept) + "\n")
        for r in new_rows:
            f.write(",".join(cell(r[k]) for k in keys) + "\n")


def rewrite_md(path, lines):
    with open(path) as f:
        text = f.read()
    if BEGIN in text:
        text = text[:text.index(BEGIN)] + text[text.index(END) + len(END) + 1:]
    block = (f"{BEGIN}\n\nWhat S measures (docs/validation.md), from the committed "
             f"dominance_*.csv:\n\n| quantity | paper | granagg | flat? | remark |\n"
             f"|---|---|---|---|---|\n" + "\n".join(lines) + f"\n{END}\n")
    with open(path, "w") as f:
        f.write(text.rstrip("\n") + "\n\n" + block)


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    root = sys.argv[1]
    dv = os.path.join(root, "docs", "validation")
    new_rows, lines = rows(dv)
    for p in (os.path.join(dv, "verdict.csv"),
              os.path.join(root, "data", "validation", "verdict.csv")):
        rewrite_csv(p, new_rows)
    rewrite_md(os.path.join(dv, "verdict.md"), lines)
    print(f"dominance_verdict: {len(new_rows)} rows (quantity_id 4-6) written")
    return 0


if __name__ == "__main__":
    sys.exit(main())
