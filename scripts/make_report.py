#!/usr/bin/python3
"""A self-contained report.html for a `granagg pair` results folder. It leads with the verdict (what
the study showed and what the validation study concluded, summary.json "verdict") and a few plain
lines per ensemble (the same as summary.txt); then the details (every fitted z with its window and
interval, fitted beta, the mean-field exponents, the paper's values beside them), the figures
(embedded as base64 PNG: the file can be mailed or archived alone), the steps' status and timings,
and every command that made the results.

usage: /usr/bin/python3 scripts/make_report.py PAIR_DIR      (writes PAIR_DIR/report.html)
Python standard library only.
"""
import base64
import html
import json
import math
import os
import shlex
import sys

CAPTIONS = {
    "fig1_temperature": "Fig. 1. Granular temperature T_g(t) of each ensemble (mean and standard "
    "error over runs) with kinetic theory: the viscoelastic cooling law, Haff's law with the same "
    "initial rate, and the t^-5/3 asymptote.",
    "fig2_snapshots": "Fig. 2. Projected slab |z - L/2| < 2 d of run 0 at three times, neutral "
    "(top) and charged (bottom, coloured by charge).",
    "fig3_nstick": "Fig. 3. N_stick: number of particles within contact range of each tracked "
    "particle, and their mean.",
    "fig4_charge": "Fig. 4. Mean |q|(t) and its rate d<|q|>/dt against the kinetic-theory law; "
    "N_s(s) of grid clusters at three times.",
    "fig5_growth": "Fig. 5. Mean cluster size S(t) (grid clusters) with the power-law fit over the "
    "fit window, the fitted mean field where available; inset: local slope z(t) with the paper's "
    "neutral and charged z.",
    "fig6_meanfield": "Fig. 6. MD S(t) against the mean-field S(t) of the fitted beta kernel, "
    "S_c S_MF(t / tau_c); inset: mean-squared displacement from t = 0.",
    "fig7_speed": "Fig. 7. Speed distribution f(v~), v~ = v / <v^2>^1/2, at the first and last "
    "frames against the Maxwellian.",
    "fig8_charge_speed": "Fig. 8. Charge-speed scatter (q~, v~) of the last analysed frame of "
    "every charged run.",
}


def num(x, prec=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    return f"{x:.{prec}f}"


def interval(d, prec=3):
    if not d or d.get("value") is None:
        return "n/a"
    s = num(d["value"], prec)
    if d.get("low") is not None and d.get("high") is not None:
        s += f" [{num(d['low'], prec)}, {num(d['high'], prec)}]"
    return s


def esc(s):
    return html.escape(str(s))


def main():
    if len(sys.argv) != 2 or not os.path.isdir(sys.argv[1]):
        sys.exit("usage: make_report.py PAIR_DIR (a `granagg pair` results folder)")
    d = sys.argv[1]
    path = os.path.join(d, "summary.json")
    if not os.path.exists(path):
        sys.exit(f"make_report: {path} not found (run granagg pair first)")
    with open(path) as f:
        s = json.load(f)
    paper = s.get("paper", {})
    out = []
    w = out.append
    w("<!DOCTYPE html><html><head><meta charset='utf-8'>")
    w(f"<title>granagg pair: {esc(s.get('study', ''))}</title>")
    w("<style>"
      "body{font-family:sans-serif;max-width:1100px;margin:2em auto;line-height:1.4;color:#222}"
      "table{border-collapse:collapse;margin:1em 0}"
      "td,th{border:1px solid #bbb;padding:4px 8px;text-align:left}"
      "th{background:#eee}img{max-width:100%;border:1px solid #ddd}figure{margin:2em 0}"
      "pre{background:#f6f6f6;padding:8px;overflow-x:auto;font-size:12px}"
      ".small{color:#666;font-size:90%}</style>")
    w("</head><body>")
    w(f"<h1>Paired MD / mean-field study <code>{esc(s.get('study', ''))}</code></h1>")
    w(f"<p class='small'>{esc(s.get('granagg', ''))}; backend: {esc(s.get('backend', ''))}; "
      f"{esc(s.get('cores', ''))} cores; "
      f"written {esc(s.get('written', ''))}; folder <code>{esc(s.get('out', ''))}</code>.<br>"
      f"Physics: {esc(paper.get('reference', 'Singh & Mazza, Phys. Rev. E (2018)'))}. "
      "Reduced units: d = m = T0 = 1.</p>")

    verdict = s.get("verdict") or []
    if verdict:
        w("<h2>Verdict</h2><p class='small'>What this study showed, and what the validation study "
          "(docs/validation.md: larger and longer ensembles) concluded. A growth exponent z is "
          "given only where S(t) is a power law (a flat local slope) and its interval "
          "excludes 0.</p><ul>")
        for line in verdict:
            w(f"<li>{esc(line)}</li>")
        w("</ul>")
    if any(e.get("summary") for e in s.get("ensembles", [])):
        w("<h2>Per ensemble</h2>")
        for e in s.get("ensembles", []):
            lines = e.get("summary") or []
            if not lines:
                continue
            w(f"<h3>{esc(lines[0])}</h3><ul>")
            for line in lines[1:]:
                w(f"<li>{esc(line.strip())}</li>")
            w("</ul>")
        folder = s.get("out", d)
        size = s.get("results_bytes")
        if size:
            w(f"<p class='small'>The results folder takes {size / 2**20:.0f} MiB "
              "(mostly runs/: the trajectories); delete it with "
              f"<code>rm -r {esc(shlex.quote(folder))}</code>. "
              "The same summary as text: summary.txt.</p>")

    w("<h2>Details: every fitted number</h2>")
    w("<p class='small'>For reference, not results: two least-squares fits of ln S on ln t over "
      "different windows. analyze's window is the last decade of the runs; fit-beta's is the "
      "longest stretch at the end over which the local slope is flat. Where S(t) is not a power "
      "law (regime onset or none, below) each fit's value is set by its window, and an interval "
      "over few runs may reach below 0: the verdict above then reports no z. beta from the "
      "full-curve fit is \"not determined\" where it ends at a bound of its search range.</p>")
    w("<table><tr><th>K</th><th>runs</th><th>N</th><th>t_end</th>"
      "<th>z (analyze, grid clusters, 95% interval)</th>"
      "<th>fit window</th><th>z (fit-beta)</th><th>beta from z</th>"
      "<th>beta, full-curve fit</th><th>paper z</th></tr>")
    for e in s.get("ensembles", []):
        win = e.get("z_analyze_window") or [None, None]
        fw = e.get("fit_window") or [None, None]
        if e.get("fit_beta") == "done":
            fit_note = f"<br><span class='small'>window [{num(fw[0], 3)}, {num(fw[1], 3)}]</span>"
        else:
            fit_note = f"<br><span class='small'>{esc(e.get('fit_beta', ''))}</span>"
        beta_note = (f"<br><span class='small'>{esc(e['fit_notes'])}</span>"
                     if e.get("fit_notes") else "")
        w(f"<tr><td>{esc(e['K'])}</td><td>{esc(e.get('runs'))}</td><td>{esc(e.get('N'))}</td>"
          f"<td>{esc(e.get('t_end'))}</td>"
          f"<td>{interval(e.get('z_analyze'))}</td><td>[{num(win[0], 3)}, {num(win[1], 3)}]</td>"
          f"<td>{interval(e.get('z'))}{fit_note}</td><td>{interval(e.get('beta_from_z'), 2)}</td>"
          f"""<td>{interval(e.get('beta_fit'), 2)
                  if e.get('beta_fit_determined', True) or e.get('fit_beta') != 'done'
                  else 'not determined (at a bound of the search range)'}{beta_note}</td>"""
          f"<td>{esc(e.get('paper_z'))} &plusmn; {esc(e.get('paper_z_pm'))}</td></tr>")
    w("</table>")
    w("<h2>Which regime are these numbers in?</h2>")
    w("<p class='small'>A growth exponent is a result only where S(t) has left its onset and its "
      "local slope is flat (docs/model.md section 11). Regime of the ensemble-mean S_grid at the "
      "end of the runs: <b>none</b> (S has not doubled), <b>onset</b> (S grows but the local slope "
      "over the last half decade still changes by more than 25 %), <b>scaling</b> "
      "(flat within 25 %). Beside it, the validation study's number for the same K "
      "(docs/validation.md, data/validation/verdict.csv), so that a demo is not read "
      "as a result.</p>")
    w("<table><tr><th>K</th><th>growth of S_grid</th><th>onset time t_c</th>"
      "<th>regime</th><th>why</th>"
      "<th>asymptotic beta 3z/(3-z)</th><th>validation study</th></tr>")
    for e in s.get("ensembles", []):
        w(f"<tr><td>{esc(e['K'])}</td><td>x{num(e.get('growth_factor'), 3)}</td>"
          f"<td>{num(e.get('onset_time'), 3)} &plusmn; {num(e.get('onset_time_se'), 2)}</td>"
          f"<td><b>{esc(e.get('regime', 'unknown'))}</b></td>"
          f"<td class='small'>{esc(e.get('regime_reason', ''))}</td>"
          f"""<td>{interval(e.get('beta_asymptotic'), 2)
                  if e.get('beta_asymptotic_applicable')
                  else 'not applicable (no scaling regime)'}</td>"""
          f"<td class='small'>{esc(e.get('validation') or 'no validation row for this K')}"
          "</td></tr>")
    w("</table>")
    w("<h2>Mean field (Smoluchowski equation, beta kernel, sectional solver)</h2>")
    w("<table><tr><th>beta</th><th>z local at S ~ 250</th><th>z local at S ~ 1650</th>"
      "<th>z asymptotic</th><th>3 beta/(beta+3)</th><th>paper</th></tr>")
    for m in s.get("meanfield", []):
        w(f"<tr><td>{esc(m['beta'])}</td><td>{num(m.get('z_local_S250'))}</td>"
          f"<td>{num(m.get('z_local_S1650'))}</td>"
          f"<td>{num(m.get('z_asymptotic'), 4)}</td><td>{num(m.get('z_scaling'), 4)}</td>"
          f"<td>{esc(m.get('paper_z'))}</td></tr>")
    pz = s.get("paper", {})
    w(f"</table><p class='small'>The paper's {esc(pz.get('z_meanfield_beta2'))} (beta = 2) and "
      f"{esc(pz.get('z_meanfield_beta3'))} (beta = 3) are local slopes near S ~ 250 and S ~ 1650; "
      "the full equation converges to 3 beta/(beta+3) (docs/model.md section 12).</p>")

    w("<h2>Figures</h2>")
    figs = os.path.join(d, "figures")
    names = (sorted(n[:-4] for n in os.listdir(figs) if n.endswith(".png"))
             if os.path.isdir(figs) else [])
    if not names:
        w("<p>No figures (scripts/plot_figures.py did not run).</p>")
    for n in names:
        with open(os.path.join(figs, n + ".png"), "rb") as f:
            data = base64.b64encode(f.read()).decode("ascii")
        w(f"<figure><img alt='{esc(n)}' src='data:image/png;base64,{data}'>"
          f"<figcaption>{esc(CAPTIONS.get(n, n))} "
          f"<span class='small'>(figures/{esc(n)}.png, .pdf)</span></figcaption></figure>")

    w("<h2>Steps and timings</h2><table><tr><th>step</th><th>status</th></tr>")
    for k, v in s.get("steps", {}).items():
        w(f"<tr><td>{esc(k)}</td><td>{esc(v)}</td></tr>")
    w("</table><table><tr><th>stage</th><th>wall time (s, this invocation)</th></tr>")
    for k, v in s.get("timings_s", {}).items():
        w(f"<tr><td>{esc(k)}</td><td>{esc(v)}</td></tr>")
    w("</table>")
    w("<h2>Commands</h2><p class='small'>The pair command first, then every subprocess it ran "
      "(all invocations, including earlier interrupted ones), in order. Configuration: "
      f"<code>{esc(s.get('config', ''))}</code>.</p><pre>")
    for c in s.get("commands", []):
        w(esc(c))
    w("</pre>")
    cfg = os.path.join(d, "config", "pair.toml")
    if os.path.exists(cfg):
        with open(cfg) as f:
            w("<h3>config/pair.toml</h3><pre>" + esc(f.read()) + "</pre>")
    w("</body></html>")
    with open(os.path.join(d, "report.html"), "w") as f:
        f.write("\n".join(out))
    print(f"make_report: wrote {os.path.join(d, 'report.html')}")


if __name__ == "__main__":
    main()
