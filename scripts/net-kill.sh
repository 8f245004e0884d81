#!/usr/bin/env bash
# A distributed paper flight in real time whose UAV2 agent is killed (SIGKILL) at 40 s and
# restarted at 60 s: the others keep the formation (as with scenarios/paper-remove-uav2.toml),
# UAV2 leaves the flight and rejoins its slot. Needs a build with the network agent:
#   cargo build --release --features net -p proxform-cli -p proxform-net
#   scripts/net-kill.sh [OUTDIR]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release
out=${1:-out/net-kill}
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
endpoint=tcp/127.0.0.1:$port
swarm=kill-$$
pids=()
cleanup() { for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
"$bin/proxform" world --clock realtime --listen "$endpoint" --swarm "$swarm" --no-figures --out "$out" > "$out.txt" 2> "$out.err" &
world=$!
pids+=("$world")
sleep 0.5
agent() { "$bin/proxform-agent" --scenario paper --uav "$1" --swarm "$swarm" --connect "$endpoint" --idle-exit-s 5 & pids+=("$!"); }
for u in 2 3 4 5 6; do agent "$u"; done
victim=${pids[1]}
# t = 0 comes about 0.5 s after every agent has announced itself.
sleep 41
kill -9 "$victim"
echo "killed UAV2's agent (pid $victim) at about 40 s"
sleep 20
agent 2
echo "restarted UAV2's agent (pid ${pids[-1]}) at about 60 s"
status=0
wait "$world" || status=$?
cat "$out.txt" | sed -n '1,12p'
cat "$out.err"
awk -F, 'NR > 1 && $2 == 2 { if (last != "" && $1 - last > 1) print "UAV2 out of the flight from", last, "s to", $1, "s"; last = $1 }' "$out/trajectories.csv"
exit $status
