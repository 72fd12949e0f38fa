#!/usr/bin/env bash
# The main job (README): installs what is missing, builds, and runs the quick paired MD /
# mean-field study (issue 6, docs/pair.md): neutral (K = 0) and charged (K = 5) granular gases,
# 3 MD runs each, their analysis, the Smoluchowski mean field (S(t) for beta = 2 and 3, z(beta)),
# the beta fit, the paper's eight figures, summary.txt, summary.json and a self-contained
# report.html.
# Under 10 minutes on 2 cores after the build (data/pair/quick.toml states the sizes; the measured
# time is in docs/validation.md, "The demo"). Both ensembles aggregate; the summary leads with the
# verdict (what the demo showed, what the validation study concluded), then per ensemble the
# growth, onset and regime, the local slope, and one z or why there is none. It ends with the
# size of the results (83 MiB: the runs are analysed during the run and store no particle frames)
# and the command that deletes them.
#   usage: bash scripts/demo.sh [OUTDIR]     (default: results/demo-<date>-<time>; never reused)
#   GRANAGG_BUILD_DIR   build folder (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
BUILD_DIR=${GRANAGG_BUILD_DIR:-build}
G="$BUILD_DIR/bin/granagg"

OUT=${1:-results/demo-$(date +%Y%m%d-%H%M%S)}
if [ -e "$OUT" ]; then echo "demo: $OUT already exists; name another folder" >&2; exit 2; fi
mkdir -p "$(dirname "$OUT")"
echo "== granagg demo -> $OUT ($("$G" --version))"
START=$(date +%s)

# MD ensembles -> analysis -> mean field -> fit-beta -> figures -> report.html + summary.json.
# Interrupted? Run `$G pair --preset quick --out $OUT` again: finished runs are not redone.
"$G" pair --preset quick --out "$OUT"

echo "== done in $(( $(date +%s) - START )) s. The verdict: $OUT/summary.txt (printed above)"
echo "   and $OUT/report.html (figures in $OUT/figures/, every number in $OUT/summary.json)."
echo "== The results take $(du -sh "$OUT" | cut -f1) on disk (checkpoints and in-situ tables in $OUT/runs/)."
echo "   Delete them with: rm -r $(printf '%q' "$OUT")"
