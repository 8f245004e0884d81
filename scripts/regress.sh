#!/usr/bin/env bash
# Runs a fixed set of scenarios with a given binary and writes every output file into one
# folder, so two builds can be compared byte for byte:
#   scripts/regress.sh BIN OUTDIR   then   diff -r OUTDIR_A OUTDIR_B
# Figures are skipped (fonts and rasterising are not what a refactor should change).
set -euo pipefail
bin=$1; out=$2
here="$(cd "$(dirname "$0")/.." && pwd)"
mkdir -p "$out"
run() { local name=$1; shift; "$bin" run -q --no-figures --out "$out/$name" "$@" >"$out/$name.txt" 2>&1 || echo "exit $?" >>"$out/$name.txt"; }
run paper1000 --runs 1000 --no-trajectories
run paper --runs 3
run paper-noadjust --no-adjust
run paper-h3 --horizon 3 --runs 2
run paper-cv --predictor constant-velocity --runs 2
run swarm --scenario swarm --uavs 300 --duration-s 20
run swarm-parallel --scenario swarm --uavs 3000 --duration-s 3
run fwv --scenario fixed-wing-v --runs 20
for f in "$here"/scenarios/*.toml; do
  b=$(basename "$f" .toml)
  case "$b" in compare-*) continue;; esac
  run "file-$b" "$f" --runs 4
done
for m in leader_follower consensus flocking; do run "method-$m" --method "$m" --runs 3; done
"$bin" compare -q --no-figures --seeds 3 --duration-s 30 --out "$out/compare" >"$out/compare.txt" 2>&1 || echo "exit $?" >>"$out/compare.txt"
