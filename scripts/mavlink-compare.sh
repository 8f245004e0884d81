#!/usr/bin/env bash
# Flies a scenario with every follower's agent over MAVLink (the world's simulated vehicles, in
# real time) and in process, seed by seed, and prints the pass count and the medians over the
# seeds of each run's worst errors, side by side (the table in docs/mavlink.md).
#
#   scripts/mavlink-compare.sh OUT FIRST LAST [SCENARIO ARGS...]    e.g. /tmp/mc 1 50 --scenario paper
#   scripts/mavlink-compare.sh OUT                                   the table of what OUT holds
#
# One flight at a time (they are real time: about 35 s each for 30 s flights); a seed already
# in OUT is not flown again. PORTBASE (default 24000) is where the vehicles' UDP ports start:
# below Linux's ephemeral ports (32768-60999), which the world's own sockets may take.
# Needs the release build: cargo build --release --features net -p proxform-cli -p proxform-net
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
bin=${BIN:-$here/target/release/proxform}
out=$1; shift
mkdir -p "$out"
if [ $# -ge 2 ]; then
  first=$1; last=$2; shift 2
  for s in $(seq "$first" "$last"); do
    [ -f "$out/in-$s/summary.json" ] || "$bin" run "$@" --duration-s 30 --seed "$s" --no-figures --no-trajectories -q \
      --out "$out/in-$s" >/dev/null 2>&1 || true
    [ -f "$out/mav-$s/summary.json" ] || timeout 150 "$bin" run "$@" --distributed --clock realtime --agents-mavlink \
      --mavlink-port $(( ${PORTBASE:-24000} + 20 * (s % 50) )) --duration-s 30 --seed "$s" --no-figures \
      --no-trajectories -q --out "$out/mav-$s" >"$out/mav-$s.log" 2>&1 || echo "seed $s: exit $?"
  done
fi
python3 - "$out" <<'PY'
import glob, json, statistics, sys
out = sys.argv[1]
axes = ["x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg"]
mav, inp, passed, fails = {a: [] for a in axes}, {a: [] for a in axes}, 0, []
for path in sorted(glob.glob(f"{out}/mav-*/summary.json")):
    seed = path.split("mav-")[1].split("/")[0]
    try:
        m, i = json.load(open(path)), json.load(open(f"{out}/in-{seed}/summary.json"))
    except OSError:
        continue
    if m["pass_fraction"] == 1.0:
        passed += 1
    else:
        fails.append(seed)
    for a in axes:
        mav[a].append(m["worst_abs_error"][a])
        inp[a].append(i["worst_abs_error"][a])
n = len(mav["x_m"])
print(f"{passed}/{n} pass over MAVLink; failed seeds: {fails or 'none'}")
print(f"{'axis':10s} {'MAVLink':>9s} {'in process':>11s} {'ratio':>7s}   (medians over the seeds of the worst error)")
for a in axes:
    if n:
        x, y = statistics.median(mav[a]), statistics.median(inp[a])
        print(f"{a:10s} {x:9.4f} {y:11.4f} {x / y if y > 1e-9 else float('nan'):7.3f}")
PY
