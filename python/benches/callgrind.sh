#!/usr/bin/env bash
# Instructions per controller step from Python, counted by callgrind: the difference between
# N and 2N calls (N/20 and N/10 for the 999-UAV step) on the same 2N prepared arguments, so
# that start-up, set-up and building the arguments cancel. Repeatable whatever the machine's load.
#   python/benches/callgrind.sh [N]   (default 2000; uses .venv)
set -euo pipefail
cd "$(dirname "$0")"
n=${1:-2000}
py=../../.venv/bin/python
count() {
    local out
    out=$(mktemp)
    # One thread: the count of a parallel step would include the other thread's spinning.
    RAYON_NUM_THREADS=1 PYTHONHASHSEED=0 valgrind --tool=callgrind --callgrind-out-file="$out" \
        "$py" steps.py "$1" "$2" "$3" >/dev/null 2>&1
    callgrind_annotate "$out" 2>/dev/null | awk '/PROGRAM TOTALS/ { gsub(",", "", $1); print $1 }'
    rm -f "$out"
}
for mode in single many; do
    # Calls of Controllers.step: each steps 999 UAVs.
    [ "$mode" = many ] && n=$(( ${1:-2000} / 20 ))
    a=$(count "$mode" "$n" $((2 * n)))
    b=$(count "$mode" $((2 * n)) $((2 * n)))
    per=$(( (b - a) / n ))
    case $mode in
        single) echo "Controller.step, 8 neighbours: $per instructions per call" ;;
        many) echo "Controllers.step, 999 UAVs × 8 neighbours: $((per / 999)) instructions per UAV ($per per call)" ;;
    esac
done
