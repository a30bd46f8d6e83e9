#!/usr/bin/env bash
# The rig-health figure of docs/rig-health.md: a simulated 200 h durability
# series (20 blocks 10 h apart, the leakage conductance growing to +50 %),
# each block calibrated into a catalog, the trends with their bands and
# alarms drawn by plot_health.py into docs/figures/rig_health/ (or the
# folder given).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-$root/docs/figures/rig_health}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
rigctl="$root/build/tools/rigctl"
cd "$root"
"$rigctl" make-series --out "$work/series" --blocks 20 --seed ${SEED:-1} --leakage-growth 0.5 2>/dev/null
for f in "$work"/series/block-*.csv; do
  "$rigctl" health analyse "$f" --catalog "$work/catalog.sqlite" --rig-name series --window 20 \
    --config config/quarter_car.yaml >/dev/null
done
"$rigctl" health report --catalog "$work/catalog.sqlite" --rig series --json "$work/trends.json" \
  --html "$work/report.html"
/usr/bin/python3 "$root/tools/plots/plot_health.py" "$work/trends.json" --out "$out/trends.png" \
  --parameters R_l,beta,kv_scale,tau_r
