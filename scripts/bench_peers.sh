#!/usr/bin/env bash
# Times gearbif's event-driven DOP853 and Taylor methods and heyoka on the gear in one run
# (not part of CI). Builds gearbif in release, installs heyoka into a local venv under
# target/ (never committed), and writes docs/tables/peers.md and docs/tables/peers.csv with the
# machine, date and commit in the header. Workloads and error measure: scripts/bench_peers.py.
#
# Usage: scripts/bench_peers.sh [--tols 1e-6,1e-8,1e-10,1e-12] [--min-time 1.0]
#                               [--workloads lock_co,lock_ctr,eta0,stickslip]
# Takes a few minutes on 2 cores; run it on a quiet machine (the timings are wall times).
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/peer-venv
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet heyoka numpy
fi
cargo build --release --quiet
commit=$(git rev-parse --short HEAD)
if ! git diff --quiet HEAD -- src; then commit="$commit (with uncommitted changes)"; fi
"$venv/bin/python" scripts/bench_peers.py --gearbif target/release/gearbif --commit "$commit" "$@"
