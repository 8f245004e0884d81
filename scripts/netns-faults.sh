#!/usr/bin/env bash
# Distributed real-time flights with every agent in its own network namespace, under network
# faults. The world (the Zenoh router) runs in the root namespace and listens (--insecure) on a
# bridge address; each agent process runs in a namespace of its own, joined to the bridge by a
# veth pair. Flights are sequential (one at a time). Needs root, `ip netns`, iptables (the
# `statistic` match) and python3; no netem (delay is a userspace relay).
#
# Usage:
#   scripts/netns-faults.sh run [options]     fly runs, one result line per run in OUT/results.jsonl
#   scripts/netns-faults.sh summary OUT...    a table per scenario x fault from results.jsonl
#
# run options:
#   --scenario paper|FILE   built-in name or scenario TOML (default paper)
#   --fault F               none | loss | delay | stop | partition | worldstop (default none)
#                             loss:      --loss P random DROP, INPUT and OUTPUT, in every agent namespace
#                             delay:     a python asyncio relay per agent delays each chunk by
#                                        U(--delay-min-ms, --delay-max-ms), order preserved
#                             stop:      SIGSTOP the --victim's agent at --at-s for --stop-s, then SIGCONT
#                             partition: DROP everything in the --victim's namespace at --at-s for --cut-s
#                             worldstop: SIGSTOP the world at --at-s for --world-stop-s, then SIGCONT
#   --seeds A-B|A,B,..      seeds, one flight each (default 1)
#   --duration-s D          flight duration (default 40)
#   --victim N              disturbed UAV for stop/partition (default 3)
#   --at-s T                fault time into the flight (default 15; estimated, see below)
#   --stop-s S (5)  --cut-s S (10)  --world-stop-s S (1.5)  --loss P (0.05)
#   --delay-min-ms A (20)  --delay-max-ms B (60)
#   --out DIR               results folder (default /tmp/ns30/results)
#   --bin DIR               folder of proxform and proxform-agent (default this checkout's
#                           target/release: `cargo build --release --features net -p proxform-cli
#                           -p proxform-net`)
#   --lead-s L              flight start = all agents' TCP links established + L (default 0.75)
#   --rto-min-ms R          TCP's minimum retransmission timeout on the links (Linux: 200 ms;
#                           a route's rto_min), on both ends; default: the kernel's
#
# The flight's start is not printed by the world; the fault is timed from the moment every
# agent's TCP link to the world (or its relay's) is established, plus --lead-s. After the run
# the fault's time into the flight is re-estimated from the world's exit (exit - duration) and
# recorded (fault_at_est_s).
#
# Example (one paper run of each fault):
#   scripts/netns-faults.sh run --fault loss --seeds 1 --duration-s 40
#   scripts/netns-faults.sh summary /tmp/ns30/results
set -uo pipefail

die() { echo "netns-faults: $*" >&2; exit 2; }

cmd=${1:-}; shift || true

# ---------------------------------------------------------------------------------------------
# summary
# ---------------------------------------------------------------------------------------------
if [[ "$cmd" == "summary" ]]; then
  [[ $# -ge 1 ]] || die "summary OUT..."
  python3 - "$@" <<'PY'
import json, sys, os, collections
rows = []
for d in sys.argv[1:]:
    p = os.path.join(d, "results.jsonl") if os.path.isdir(d) else d
    with open(p) as f:
        rows += [json.loads(l) for l in f if l.strip()]
groups = collections.OrderedDict()
for r in rows:
    groups.setdefault((r["scenario"], r["fault"]), []).append(r)
hdr = ("scenario", "fault", "runs", "exit0", "others PASS", "others within allowed", "others worst x/y/z m", "others worst a/b/g deg",
       "victim final<0.5m", "victim worst x/y/z m", "uncontrolled", "missing(med/max)", "late(max)", "lost(max)", "hung")
print("\t".join(hdr))
for (sc, fa), rs in groups.items():
    n = len(rs)
    ex0 = sum(1 for r in rs if r["exit"] == 0)
    op = sum(1 for r in rs if r["others_pass"])
    ow_ = sum(1 for r in rs if r.get("others_within"))
    ow = [max((r["others_worst"][i] for r in rs if r["others_worst"]), default=float("nan")) for i in range(6)]
    vic = [r for r in rs if r.get("victim")]
    vf = f'{sum(1 for r in vic if r["victim_returned"])}/{len(vic)}' if vic else "-"
    vw = [max((r["victim_worst"][i] for r in vic if r["victim_worst"]), default=float("nan")) for i in range(3)] if vic else None
    unc = sum(1 for r in rs if r.get("uncontrolled"))
    miss = sorted(r["distributed"].get("missing", -1) for r in rs)
    late = max(r["distributed"].get("late", -1) for r in rs)
    lost = max(r["distributed"].get("lost", -1) for r in rs)
    hung = sum(1 for r in rs if r.get("hung"))
    print("\t".join(map(str, (sc, fa, n, f"{ex0}/{n}", f"{op}/{n} = {op/n:.2f}", f"{ow_}/{n}",
        "/".join(f"{v:.3f}" for v in ow[:3]), "/".join(f"{v:.3f}" for v in ow[3:]),
        vf, "/".join(f"{v:.2f}" for v in vw) if vw else "-", f"{unc}/{n}",
        f"{miss[len(miss)//2]}/{miss[-1]}", late, lost, hung))))
print()
print("timing (flight s, medians over runs): fault start/length est., others first/last outside allowed, victim first outside / back inside for good")
import statistics
def med(v):
    v = [x for x in v if x is not None]
    return round(statistics.median(v), 2) if v else None
for (sc, fa), rs in groups.items():
    print(sc, fa, "fault", med([r.get("fault_at_est_s") for r in rs]), med([r.get("fault_len_s") for r in rs]),
          "| others out", med([r.get("others_first_out_t") for r in rs]), med([r.get("others_last_out_t") for r in rs]),
          "steps", med([r.get("others_out_steps") for r in rs]),
          "| victim", med([r.get("victim_first_out_t") for r in rs]), med([r.get("victim_rejoin_t") for r in rs]))
print()
print("per run: scenario fault seed exit FAILs victim_final_maxabs rejoin_t fault_at_est_s distributed | real time")
for r in rows:
    fails = [u for u, v in r["results"].items() if v != "PASS"]
    print(r["scenario"], r["fault"], r["seed"], r["exit"], ",".join(fails) or "-",
          None if r.get("victim_final_maxabs") is None else round(r["victim_final_maxabs"], 3),
          r.get("victim_rejoin_t"), r.get("fault_at_est_s"),
          "|", r["distributed_raw"].replace("distributed: ", "")[:200], "|", r["realtime_raw"].replace("real time: ", "")[:160],
          ("| " + r["uncontrolled"]) if r.get("uncontrolled") else "", ("| HUNG" if r.get("hung") else ""),
          ("| agent output: " + r["agent_output"][:200]) if r.get("agent_output") else "")
PY
  exit $?
fi

[[ "$cmd" == "run" ]] || { sed -n '2,40p' "$0"; exit 2; }

# ---------------------------------------------------------------------------------------------
# run: options
# ---------------------------------------------------------------------------------------------
scenario=paper fault=none seeds=1 duration=40 victim=3 at_s=15 stop_s=5 cut_s=10 wstop_s=1.5
loss=0.05 dmin=20 dmax=60 out=/tmp/ns30/results lead_s=0.75 rto_min_ms=""
bin="$(cd "$(dirname "$0")/.." && pwd)/target/release"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --scenario) scenario=$2; shift 2;;
    --fault) fault=$2; shift 2;;
    --seeds) seeds=$2; shift 2;;
    --duration-s) duration=$2; shift 2;;
    --victim) victim=$2; shift 2;;
    --at-s) at_s=$2; shift 2;;
    --stop-s) stop_s=$2; shift 2;;
    --cut-s) cut_s=$2; shift 2;;
    --world-stop-s) wstop_s=$2; shift 2;;
    --loss) loss=$2; shift 2;;
    --delay-min-ms) dmin=$2; shift 2;;
    --delay-max-ms) dmax=$2; shift 2;;
    --out) out=$2; shift 2;;
    --bin) bin=$2; shift 2;;
    --lead-s) lead_s=$2; shift 2;;
    --rto-min-ms) rto_min_ms=$2; shift 2;;
    *) die "unknown option $1";;
  esac
done
case "$fault" in none|loss|delay|stop|partition|worldstop) ;; *) die "unknown fault $fault";; esac
[[ $EUID -eq 0 ]] || die "needs root"
command -v iptables >/dev/null || die "needs iptables (apt-get install -y iptables)"
[[ -x "$bin/proxform" && -x "$bin/proxform-agent" ]] || die "no proxform/proxform-agent in $bin"
if [[ "$seeds" == *-* ]]; then seedlist=$(seq "${seeds%-*}" "${seeds#*-}"); else seedlist=${seeds//,/ }; fi
mkdir -p "$out"

if [[ "$scenario" == */* || "$scenario" == *.toml ]]; then
  scenario=$(readlink -f "$scenario"); [[ -f "$scenario" ]] || die "no scenario file $scenario"
  world_sc=("$scenario"); scname=$(basename "$scenario" .toml)
else
  world_sc=(--scenario "$scenario"); scname=$scenario
fi
nuav=$("$bin/proxform" world --print-scenario "${world_sc[@]}" 2>/dev/null | grep -c '^\[\[formation.slot\]\]')
navigator=$("$bin/proxform" world --print-scenario "${world_sc[@]}" 2>/dev/null | sed -n 's/^navigator = \([0-9]*\)$/\1/p' | head -1)
[[ "$nuav" -ge 2 ]] || die "cannot read the scenario's UAVs"
navigator=${navigator:-1}
uavs=(); for ((u = 1; u <= nuav; u++)); do [[ $u -ne $navigator ]] && uavs+=("$u"); done
hv=""; [[ "$fault" == stop || "$fault" == partition ]] && hv=$victim

# ---------------------------------------------------------------------------------------------
# namespaces: bridge nf<pid>b (10.231.0.1/24) in the root namespace, one namespace per agent
# ---------------------------------------------------------------------------------------------
tag=nf$$
br=${tag}b
host_ip=10.231.0.1
pids=()          # every process this script started
declare -A agent_pid
stopped=()       # processes left SIGSTOPped (SIGCONT before ending them)

ns_of() { echo "${tag}u$1"; }
kill_pid() {  # end one pid this script started: CONT, TERM, wait up to 3 s, KILL
  local p=$1 i
  kill -0 "$p" 2>/dev/null || return 0
  kill -CONT "$p" 2>/dev/null; kill -TERM "$p" 2>/dev/null
  for i in $(seq 30); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
  kill -0 "$p" 2>/dev/null && kill -KILL "$p" 2>/dev/null
  wait "$p" 2>/dev/null || true
}
cleanup() {
  local p u
  for p in "${stopped[@]}"; do kill -CONT "$p" 2>/dev/null; done
  for p in "${pids[@]}"; do kill_pid "$p"; done
  for u in "${uavs[@]}"; do ip link del "${tag}h$u" 2>/dev/null; ip netns del "$(ns_of "$u")" 2>/dev/null; done  # its iptables rules go with it
  ip link del "$br" 2>/dev/null
  true
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# Leftovers of a run that was killed (its bridge holds the same address): removed when the
# script that made them is gone.
for old in $(ip -o link show type bridge | sed -n 's/^[0-9]*: \(nf[0-9]*\)b[:@].*/\1/p'); do
  kill -0 "${old#nf}" 2>/dev/null && die "another run ($old) is going on: one at a time"
  for n in $(ip netns list | awk '{print $1}' | grep "^${old}u"); do ip netns del "$n"; done
  for l in $(ip -o link show | sed -n "s/^[0-9]*: \(${old}h[0-9]*\)@.*/\1/p"); do ip link del "$l" 2>/dev/null; done
  ip link del "${old}b" 2>/dev/null
done
ip link add "$br" type bridge || die "cannot make the bridge"
ip addr add "$host_ip/24" dev "$br"; ip link set "$br" up
for u in "${uavs[@]}"; do
  ns=$(ns_of "$u")
  ip netns add "$ns" || die "cannot add namespace $ns"
  ip link add "${tag}h$u" type veth peer name "${tag}a$u" || die "veth"
  ip link set "${tag}a$u" netns "$ns"
  ip link set "${tag}h$u" master "$br"; ip link set "${tag}h$u" up
  ip netns exec "$ns" ip addr add "10.231.0.$((u + 1))/24" dev "${tag}a$u"
  ip netns exec "$ns" ip link set "${tag}a$u" up
  ip netns exec "$ns" ip link set lo up
  if [[ -n "$rto_min_ms" ]]; then
    ip netns exec "$ns" ip route replace 10.231.0.0/24 dev "${tag}a$u" rto_min "${rto_min_ms}ms" || die "rto_min"
  fi
done
if [[ -n "$rto_min_ms" ]]; then
  ip route replace 10.231.0.0/24 dev "$br" rto_min "${rto_min_ms}ms" || die "rto_min"
fi
sleep 1  # bridge ports forwarding

free_port() { python3 -c 'import socket,sys; s=socket.socket(); s.bind((sys.argv[1],0)); print(s.getsockname()[1])' "$host_ip"; }
now() { date +%s.%N; }
sleep_until() { local d; d=$(python3 -c "import sys,time; print(max(0.0, float(sys.argv[1]) - time.time()))" "$1"); sleep "$d"; }
ipt_all() { local u; for u in "${uavs[@]}"; do ip netns exec "$(ns_of "$u")" iptables "$@"; done; }

# the delay relay: listen on HOST:LPORT, forward to HOST:RPORT, each chunk delayed U(a, b) ms, FIFO
read -r -d '' RELAY_PY <<'PY'
import asyncio, random, signal, socket, sys, time
lhost, lport, rhost, rport, dmin, dmax, seed = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4]), float(sys.argv[5]) / 1e3, float(sys.argv[6]) / 1e3, int(sys.argv[7])
rng = random.Random(seed)
stats = {"up": [0, 0.0, 0.0], "down": [0, 0.0, 0.0]}  # chunks, sum of delay, max delay (as applied)
def nodelay(w):
    s = w.get_extra_info("socket")
    if s is not None: s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
async def pump(reader, writer, name):
    loop = asyncio.get_running_loop(); q = asyncio.Queue()
    async def rx():
        try:
            while True:
                data = await reader.read(65536)
                q.put_nowait((loop.time(), loop.time() + rng.uniform(dmin, dmax), data))
                if not data: return
        except Exception:
            q.put_nowait((loop.time(), loop.time(), b""))
    async def tx():
        try:
            while True:
                t0, due, data = await q.get()
                d = due - loop.time()
                if d > 0: await asyncio.sleep(d)
                if not data: break
                writer.write(data); await writer.drain()
                st = stats[name]; dl = loop.time() - t0; st[0] += 1; st[1] += dl; st[2] = max(st[2], dl)
        finally:
            writer.close()
    await asyncio.gather(rx(), tx())
async def handle(cr, cw):
    try:
        sr, sw = await asyncio.open_connection(rhost, rport)
    except Exception as e:
        print("relay: connect failed", e, file=sys.stderr, flush=True); cw.close(); return
    nodelay(cw); nodelay(sw)
    await asyncio.gather(pump(cr, sw, "up"), pump(sr, cw, "down"), return_exceptions=True)
def report(*_):
    for k, (n, s, m) in stats.items():
        print(f"relay {k}: {n} chunks, delay mean {1e3*s/max(n,1):.1f} ms, max {1e3*m:.1f} ms", file=sys.stderr, flush=True)
    sys.exit(0)
async def main():
    signal.signal(signal.SIGTERM, report)
    srv = await asyncio.start_server(handle, lhost, lport)
    async with srv: await srv.serve_forever()
asyncio.run(main())
PY

# parse one run into a JSON line
read -r -d '' PARSE_PY <<'PY'
import json, re, sys, csv, gzip, os, math
rd, meta = sys.argv[1], json.loads(sys.argv[2])
def rd_text(p):
    try:
        with open(os.path.join(rd, p), errors="replace") as f: return f.read()
    except OSError: return ""
wout, werr = rd_text("world.out"), rd_text("world.err")
both = wout + "\n" + werr
res, rows, allowed = {}, {}, None
num = r"(-?[\d.]+|NaN|inf)"
for l in wout.splitlines():
    m = re.match(r"^allowed\s+" + r"\s+".join([num] * 6), l)
    if m: allowed = [float(x) for x in m.groups()]
    m = re.match(r"^UAV(\d+)\s+" + r"\s+".join([num] * 6) + r"\s+(\S+)\s+(\S+)\s*$", l)
    if m:
        u = m.group(1); rows[u] = [float(x) for x in m.groups()[1:7]]; res[u] = m.group(9)
# summary.json has a row per UAV (the printed table shows at most 10 followers)
try:
    with open(os.path.join(rd, "out", "summary.json")) as f: sj = json.load(f)
    ax = ("x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg")
    for u, w, fl, ps in zip(sj["per_uav"], sj["per_uav_worst"], sj["per_uav_runs_flown"], sj["per_uav_runs_passed"]):
        rows[str(u)] = [w[a] for a in ax]; res[str(u)] = "PASS" if ps == fl else "FAIL"
    allowed = [sj["allowable_error"][a] for a in ax]
except (OSError, KeyError, ValueError, TypeError):
    pass
victim = meta.get("victim") or None
others = [u for u in res if u != str(victim)]
r = dict(meta)
r["results"] = res
r["rows"] = rows
r["allowed"] = allowed
r["others_pass"] = bool(res) and all(res[u] == "PASS" for u in others) and meta["exit_hint"] != "hung"
r["others_worst"] = [max(rows[u][i] for u in others) for i in range(6)] if others else None
# the same judged on the numbers: every other UAV's worst |error| within the allowed one, on every axis
r["others_within"] = bool(others) and allowed is not None and all(rows[u][i] <= allowed[i] + 1e-9 for u in others for i in range(6))
unc = [l.strip() for l in both.splitlines() if "uncontrolled" in l]
r["uncontrolled"] = " ".join(unc)
dl = next((l.strip() for l in werr.splitlines() + wout.splitlines() if l.startswith("distributed:")), "")
rl = next((l.strip() for l in werr.splitlines() + wout.splitlines() if l.startswith("real time:")), "")
r["distributed_raw"], r["realtime_raw"] = dl, rl
def grab(pat, s, f=float):
    m = re.search(pat, s); return f(m.group(1)) if m else None
r["distributed"] = {k: grab(p, dl, int) for k, p in {
    "processes": r"(\d+) agent process", "in_time": r"(\d+) decisions in time", "missing": r"(\d+) missing",
    "late": r"(\d+) late", "undecodable": r"(\d+) undecodable", "other_key": r"(\d+) on another",
    "refused": r"(\d+) refused", "lost": r"(\d+) lost to"}.items()}
r["distributed"]["rtt_median_ms"] = grab(r"round trip median ([\d.]+) ms", dl)
r["distributed"]["rtt_p99_ms"] = grab(r"round trip median [\d.]+ ms, p99 ([\d.]+) ms", dl)
r["realtime"] = {"late_steps": grab(r"(\d+) of \d+ steps began late", rl, int), "steps": grab(r"\d+ of (\d+) steps", rl, int),
    "fell_behind": grab(r"behind (\d+) time", rl, int), "paused_s": grab(r"paused the flight ([\d.]+) s", rl),
    "update_age_median_ms": grab(r"updates were ([\d.]+) ms old", rl), "update_age_p99_ms": grab(r"updates were [\d.]+ ms old \(median\), ([\d.]+) ms", rl),
    "command_age_median_ms": grab(r"commands were ([\d.]+) ms old", rl), "command_age_p99_ms": grab(r"commands were [\d.]+ ms old \(median\), ([\d.]+) ms", rl)}
other_lines = [l.strip() for l in werr.splitlines() if l.strip() and not l.startswith(("distributed:", "real time:", "world: serving"))]
r["world_err_other"] = " || ".join(other_lines)[:1000]
# trajectories: the victim's last second, its worst error and when it came back within the allowed errors
tp = os.path.join(rd, "out", "trajectories.csv")
r["victim_final_maxabs"] = r["victim_final_norm"] = r["victim_worst"] = r["victim_rejoin_t"] = None
r["victim_returned"] = None
if victim and os.path.exists(tp):
    vt = []
    with open(tp) as f:
        for row in csv.DictReader(f):
            if row["uav"] == str(victim):
                vt.append((float(row["t_s"]), abs(float(row["err_x_m"])), abs(float(row["err_y_m"])), abs(float(row["err_z_m"]))))
    if vt:
        tend = vt[-1][0]
        last = [v for v in vt if v[0] >= tend - 1.0 + 1e-9]
        r["victim_final_maxabs"] = max(max(v[1:]) for v in last)
        r["victim_final_norm"] = math.sqrt(sum(x * x for x in vt[-1][1:]))
        r["victim_returned"] = r["victim_final_maxabs"] < 0.5
        r["victim_worst"] = [max(v[i] for v in vt) for i in (1, 2, 3)]
        if allowed:
            # the last time it was outside the allowed x/y/z errors (None: never)
            out_t = [v[0] for v in vt if v[1] > allowed[0] or v[2] > allowed[1] or v[3] > allowed[2]]
            r["victim_first_out_t"] = out_t[0] if out_t else None
            r["victim_rejoin_t"] = (out_t[-1] + 0.1) if out_t else None
            r["victim_out_s"] = round(len(out_t) * 0.1, 1)
# the other UAVs: when they were outside the allowed errors (the within_allowable column)
r["others_first_out_t"] = None; r["others_out_steps"] = None
if os.path.exists(tp):
    ot = []
    with open(tp) as f:
        for row in csv.DictReader(f):
            if row["uav"] in others and row.get("within_allowable") == "0":
                ot.append(float(row["t_s"]))
    r["others_first_out_t"] = min(ot) if ot else None
    r["others_last_out_t"] = max(ot) if ot else None
    r["others_out_steps"] = len(ot)
ao = []
for fn in sorted(os.listdir(rd)):
    if fn.startswith("agent") and fn.endswith(".log"):
        t = rd_text(fn).strip()
        if t: ao.append(f"{fn}: {t[:300]}")
r["agent_output"] = " || ".join(ao)
rl_ = []
for fn in sorted(os.listdir(rd)):
    if fn.startswith("relay") and fn.endswith(".log"):
        rl_.append(fn + ": " + rd_text(fn).strip().replace("\n", "; "))
r["relay"] = " || ".join(rl_)
print(json.dumps(r))
PY

# ---------------------------------------------------------------------------------------------
# one flight
# ---------------------------------------------------------------------------------------------
one_run() {
  local seed=$1 rd port swarm wpid t_launch t_conn t_fault t_end deadline u ns ep n rc=0 hint=ok
  rd=$out/$scname-$fault-s$seed-$(date +%H%M%S)
  mkdir -p "$rd"
  port=$(free_port); swarm=nf-$$-$seed
  for u in "${uavs[@]}"; do ip netns exec "$(ns_of "$u")" iptables -F; done
  [[ "$fault" == loss ]] && {
    ipt_all -A INPUT -m statistic --mode random --probability "$loss" -j DROP
    ipt_all -A OUTPUT -m statistic --mode random --probability "$loss" -j DROP
  }
  local relay_pids=()
  declare -A connect
  for u in "${uavs[@]}"; do connect[$u]=tcp/$host_ip:$port; done
  if [[ "$fault" == delay ]]; then
    for u in "${uavs[@]}"; do
      local rp; rp=$(free_port)
      python3 -c "$RELAY_PY" "$host_ip" "$rp" "$host_ip" "$port" "$dmin" "$dmax" "$((seed * 1000 + u))" 2> "$rd/relay$u.log" &
      pids+=("$!"); relay_pids+=("$!")
      connect[$u]=tcp/$host_ip:$rp
    done
  fi
  t_launch=$(now)
  "$bin/proxform" world --clock realtime --listen "tcp/$host_ip:$port" --insecure --swarm "$swarm" \
    --wait-agents-s 60 --duration-s "$duration" --seed "$seed" --no-figures -q --out "$rd/out" "${world_sc[@]}" \
    > "$rd/world.out" 2> "$rd/world.err" &
  wpid=$!; pids+=("$wpid")
  # wait (<= 10 s) for the world to listen (and the relays)
  deadline=$(( $(date +%s) + 10 ))
  while [[ $(date +%s) -lt $deadline ]]; do ss -Hltn "( sport = :$port )" | grep -q . && break; sleep 0.05; done
  sleep 0.2
  for u in "${uavs[@]}"; do
    ns=$(ns_of "$u")
    ip netns exec "$ns" "$bin/proxform-agent" --scenario "$scenario" --uav "$u" --swarm "$swarm" \
      --connect "${connect[$u]}" --idle-exit-s 30 --wait-s 20 > "$rd/agent$u.log" 2>&1 &
    agent_pid[$u]=$!; pids+=("$!")
  done
  # every agent's link established (<= 60 s)
  deadline=$(( $(date +%s) + 60 )); t_conn=""
  while [[ $(date +%s) -lt $deadline ]] && kill -0 "$wpid" 2>/dev/null; do
    n=$(ss -Htn state established "( sport = :$port )" | wc -l)
    [[ $n -ge ${#uavs[@]} ]] && { t_conn=$(now); break; }
    sleep 0.05
  done
  [[ -z "$t_conn" ]] && { echo "netns-faults: not every agent connected within 60 s (seed $seed)" >&2; t_conn=$(now); hint=noconnect; }
  local t0 fstart="" fend=""
  t0=$(python3 -c "import sys; print(float(sys.argv[1]) + float(sys.argv[2]))" "$t_conn" "$lead_s")
  if [[ "$fault" == stop || "$fault" == partition || "$fault" == worldstop ]]; then
    sleep_until "$(python3 -c "import sys; print(float(sys.argv[1]) + float(sys.argv[2]))" "$t0" "$at_s")"
    case "$fault" in
      stop)
        fstart=$(now); kill -STOP "${agent_pid[$victim]}"; stopped+=("${agent_pid[$victim]}")
        sleep "$stop_s"; kill -CONT "${agent_pid[$victim]}"; fend=$(now);;
      partition)
        ns=$(ns_of "$victim")
        fstart=$(now)
        ip netns exec "$ns" iptables -I INPUT 1 -j DROP; ip netns exec "$ns" iptables -I OUTPUT 1 -j DROP
        sleep "$cut_s"
        ip netns exec "$ns" iptables -D INPUT -j DROP; ip netns exec "$ns" iptables -D OUTPUT -j DROP; fend=$(now);;
      worldstop)
        fstart=$(now); kill -STOP "$wpid"; stopped+=("$wpid")
        sleep "$wstop_s"; kill -CONT "$wpid"; fend=$(now);;
    esac
  fi
  # the world's end (<= duration + 90 s after the links)
  deadline=$(python3 -c "import sys; print(float(sys.argv[1]) + float(sys.argv[2]) + 90)" "$t_conn" "$duration")
  while kill -0 "$wpid" 2>/dev/null; do
    if python3 -c "import sys,time; sys.exit(0 if time.time() > float(sys.argv[1]) else 1)" "$deadline"; then
      echo "netns-faults: the world hung (seed $seed); killing it" >&2; hint=hung; kill_pid "$wpid"; break
    fi
    sleep 0.2
  done
  wait "$wpid"; rc=$?
  t_end=$(now)
  # agents still alive 3 s after the world's end
  sleep 3
  local alive=()
  for u in "${uavs[@]}"; do kill -0 "${agent_pid[$u]}" 2>/dev/null && alive+=("$u"); done
  for u in "${uavs[@]}"; do kill_pid "${agent_pid[$u]}"; done
  for p in "${relay_pids[@]}"; do kill_pid "$p"; done
  for u in "${uavs[@]}"; do ip netns exec "$(ns_of "$u")" iptables -F; done
  local meta
  meta=$(python3 - "$scname" "$fault" "$seed" "$rc" "$hint" "$hv" "$t_launch" "$t_conn" "$t_end" "$duration" "$fstart" "$fend" "$rd" "${alive[*]:-}" <<'PY'
import json, sys
a = sys.argv[1:]
t_launch, t_conn, t_end, dur = float(a[6]), float(a[7]), float(a[8]), float(a[9])
start_est = t_end - dur
m = {"scenario": a[0], "fault": a[1], "seed": int(a[2]), "exit": int(a[3]), "exit_hint": a[4], "hung": a[4] == "hung",
     "victim": int(a[5]) if a[5] else None, "duration_s": dur, "dir": a[12],
     "conn_after_launch_s": round(t_conn - t_launch, 2), "start_est_after_conn_s": round(start_est - t_conn, 2),
     "agents_alive_3s_after_world": a[13]}
if a[10]:
    m["fault_at_est_s"] = round(float(a[10]) - start_est, 2); m["fault_len_s"] = round(float(a[11]) - float(a[10]), 2)
print(json.dumps(m))
PY
)
  python3 -c "$PARSE_PY" "$rd" "$meta" >> "$out/results.jsonl"
  [[ -f "$rd/out/trajectories.csv" ]] && gzip -f "$rd/out/trajectories.csv"
  tail -1 "$out/results.jsonl" | python3 -c 'import json, sys
r = json.loads(sys.stdin.read())
print(r["scenario"], r["fault"], "seed", r["seed"], "exit", r["exit"], "FAIL", [u for u, v in r["results"].items() if v != "PASS"],
      "others_pass", r["others_pass"], "victim_final", r["victim_final_maxabs"], "fault_at", r.get("fault_at_est_s"), "|", r["distributed_raw"][13:110])'
}

for s in $seedlist; do one_run "$s"; done
