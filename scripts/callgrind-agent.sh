#!/usr/bin/env bash
# Instructions per agent step (8 neighbours) for each variant of the robust settings, counted
# by callgrind: the difference between N and 2N steps, so that start-up and set-up cancel.
# Repeatable whatever the machine's load.
#   scripts/callgrind-agent.sh [N]   (default 20000)
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-20000}
cargo build --release -q -p proxform-core --example agent_steps
bin=target/release/examples/agent_steps
count() {
    local out
    out=$(mktemp)
    valgrind --tool=callgrind --callgrind-out-file="$out" "$bin" "$1" "$2" >/dev/null 2>&1
    callgrind_annotate "$out" 2>/dev/null | awk '/PROGRAM TOTALS/ { gsub(",", "", $1); print $1 }'
    rm -f "$out"
}
for v in paper avoid isolation own_check robust robust_singer; do
    a=$(count "$v" "$n")
    b=$(count "$v" $((2 * n)))
    echo "$v: $(( (b - a) / n )) instructions per step"
done
