#!/usr/bin/env bash
# The main job (README): installs what is missing, builds, and runs the mean-field demo --
# the z(beta) table from the full Smoluchowski equation and S(t) for beta = 2 and 3 with the
# three solvers -- plus a small MD run of the viscoelastic gas (the quick preset) compared with
# kinetic theory, then draws the figures. About a minute on 2 cores after the build.
# (Issue 6 replaces this with the paired MD / mean-field demo.)
#   usage: bash scripts/demo.sh [OUTDIR]     (default: results/demo-<date>-<time>; never reused)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
BUILD_DIR=${GRANAGG_BUILD_DIR:-build}
G="$BUILD_DIR/bin/granagg"

OUT=${1:-results/demo-$(date +%Y%m%d-%H%M%S)}
if [ -e "$OUT" ]; then echo "demo: $OUT already exists; name another folder" >&2; exit 2; fi
mkdir -p "$OUT"
echo "== granagg demo -> $OUT ($("$G" --version))"

echo "-- z(beta) from the full Smoluchowski equation (sectional solver, S up to 1e8)"
"$G" smol zbeta --beta-min 2 --beta-max 4 --count 9 --out "$OUT/zbeta.csv"

for beta in 2 3; do
  echo "-- S(t) for beta = $beta"
  "$G" smol --beta $beta --method sectional --t-end 1e7 --s-end 1e9 --out "$OUT/S_beta${beta}_sectional.csv"
  "$G" smol --beta $beta --method discrete --s-end 1e4 --t-end 1e7 --out "$OUT/S_beta${beta}_discrete.csv"
  "$G" smol --beta $beta --method mono --t-end 1e7 --out "$OUT/S_beta${beta}_mono.csv"
done

echo "-- kinetic theory: restitution and cooling of the viscoelastic gas"
"$G" kinetic restitution --v 0.01,0.05,0.1,0.5,1,2 --out "$OUT/restitution.csv"
"$G" kinetic cooling --t-end 1000 --out "$OUT/cooling.csv"

echo "-- MD: the quick preset (N = 2000 viscoelastic gas to t = 50)"
"$G" md --preset quick --out "$OUT/md-quick"

/usr/bin/python3 scripts/plot_meanfield.py "$OUT"
echo "== done: tables (CSV with provenance headers) and figures in $OUT"
