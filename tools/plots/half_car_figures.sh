#!/usr/bin/env bash
# Runs `rigctl compare` on the half car (config/half_car.yaml: the paper's
# bump, passive vs fuzzy vs skyhook vs LQR) and draws the responses like
# seed 001's Figs. 6-27 into tools/plots/figures/half_car/ (or the folder given),
# with the report's text (report.txt) and metrics (metrics.json).
#   tools/plots/half_car_figures.sh [FIGDIR] [--case NAME]
# RIGCTL=path/to/rigctl picks another build (default build/tools/rigctl).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$root/tools/plots/figures/half_car
case_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --case) case_args=(--case "$2"); shift 2 ;;
    *) out=$1; shift ;;
  esac
done
runs=$(mktemp -d)
trap 'rm -rf "$runs"' EXIT
mkdir -p "$out"
rigctl=${RIGCTL:-$root/build/tools/rigctl}
cd "$root"
"$rigctl" compare config/half_car.yaml "${case_args[@]}" --out "$runs" | grep -v -e '^  csv: ' -e '^  metrics: ' > "$out/report.txt"
cp "$runs/metrics.json" "$out/metrics.json"
cat "$out/report.txt"
# The paper's bump comes at 0.5 s (the rear wheel 0.134 s later): the
# window shows the passive car settling, the zoom the first half second of
# the response. Other cases are drawn whole.
span=(--window 0.4 5.0 --zoom 0.45 1.0)
[ ${#case_args[@]} -eq 0 ] || span=()
/usr/bin/python3 "$root/tools/plots/plot_suspension.py" "$runs" --out "$out" "${span[@]}" \
  --title "Half car, passive vs active suspension (rigctl compare config/half_car.yaml${case_args[*]:+ ${case_args[*]}})"
