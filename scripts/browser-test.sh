#!/usr/bin/env bash
# The browser test of report.html (part of .ci/run): Debian's chromium (installed with apt when
# missing) driven by playwright-core (pinned in scripts/browser/package-lock.json, installed with
# npm into target/browser-test). Two output folders are made, the paper's (20 runs) and a
# 100-UAV swarm's, and scripts/browser/report-test.mjs opens each report.html from disk: no
# network request, the 3-D view drawn, scrubbing moves the UAVs to where trajectories.csv has
# them, every UAV listed, playing moves time on. Screenshots are kept in target/browser-test/.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
work=$root/target/browser-test
mkdir -p "$work"
chromium=${CHROMIUM:-$(command -v chromium || true)}
if [ -z "$chromium" ]; then
    echo "browser test: installing Debian's chromium"
    sudo=""; [ "$(id -u)" -ne 0 ] && sudo=sudo
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends chromium >/dev/null
    chromium=$(command -v chromium)
fi
# playwright-core, as pinned, once per change of the lock file.
cp scripts/browser/package.json scripts/browser/package-lock.json scripts/browser/report-test.mjs "$work/"
if ! cmp -s scripts/browser/package-lock.json "$work/.installed" 2>/dev/null; then
    (cd "$work" && npm ci --silent --no-audit --no-fund)
    cp scripts/browser/package-lock.json "$work/.installed"
fi
# The binary as the tests built it (the same features: nothing is rebuilt).
cargo build --release --workspace --all-features --bin proxform --quiet
bin=$root/target/release/proxform
rm -rf "$work/paper" "$work/swarm100"
# (Exit 1 is a flight that failed its criterion: its report is tested all the same.)
"$bin" run --scenario paper --runs 20 -q --out "$work/paper" >/dev/null || [ $? -eq 1 ]
"$bin" run --scenario swarm --uavs 100 --duration-s 30 -q --no-figures --out "$work/swarm100" >/dev/null || [ $? -eq 1 ]
CHROMIUM=$chromium node "$work/report-test.mjs" --shots "$work" "$work/paper" "$work/swarm100"
