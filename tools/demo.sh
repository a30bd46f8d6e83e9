#!/usr/bin/env bash
# README command 1: set up, build, and run the simulated quarter-car step test
# of seed paper 000 in real time, then write its CSV and plots. Installs only
# what building, running and plotting need and builds only the program
# (tools/scripts/setup.sh --program); tools/test.sh adds the rest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/scripts/setup.sh" --program --plots
cd "$root"
mkdir -p runs
stamp=$(date +%Y%m%d-%H%M%S)
build/tools/rigctl run config/quarter_car.yaml --log "runs/quarter_car-$stamp.lcm" --csv "runs/quarter_car-$stamp.csv" "$@"
/usr/bin/python3 tools/plots/plot_run.py "runs/quarter_car-$stamp.csv" --out "runs/quarter_car-$stamp-plots"
