#!/usr/bin/env bash
# The drive iteration of docs/drive-iteration.md section 8 and
# docs/benchmarks/drive-iteration.md: ISO 8608 road targets (class C at 2 m/s,
# class D at 1 m/s) reproduced by the simulated quarter car with its bearing
# friction, its laminar leakage and a worn piston seal the nominal model
# lacks, with the inverse from the nominal model, from the model a
# diagnosis of that rig extended, and from an FRF measured by rigctl
# identify. Plots go to docs/figures/drive_iteration/ (or the folder given);
# the numbers are printed. The diagnosis takes about 3 minutes; with
# REUSE_DIAGNOSIS=1 tests/data/quarter_car_worn_seal_diagnosis.json is used.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-$root/docs/figures/drive_iteration}
work=$(mktemp -d)
trap '[ -n "${KEEP_WORK:-}" ] || rm -rf "$work"' EXIT
mkdir -p "$out"
rigctl="$root/build/tools/rigctl"
config="$root/config/quarter_car.yaml"
rig=(--fast --no-realtime --effect cross_port_leakage)

if [ -n "${REUSE_DIAGNOSIS:-}" ]; then
  cp "$root/tests/data/quarter_car_worn_seal_diagnosis.json" "$work/diagnosis.json"
else
  # The same rig as `iterate --effect cross_port_leakage`: the config's
  # Karnopp friction (bearing_friction form 0 at level 1) and the worn seal.
  "$rigctl" make-run --rig quarter_car --config "$config" --effect bearing_friction --effect cross_port_leakage \
    --tolerance 0 --form 0 --out "$work/diagnosis-run.csv" > /dev/null 2>&1
  "$rigctl" diagnose --rig quarter_car --data "$work/diagnosis-run.csv" --config "$config" --json "$work/diagnosis.json" --quiet \
    | grep -E "^cause|fit"
fi
# Measured on the config's rig: identify has no hidden effects, so this FRF
# is the rig before its piston seal wore (an FRF older than the rig's state).
"$rigctl" identify "$config" --fast --no-realtime --response x_w --out "$work/frf.json" --log "$work/identify.lcm" \
  | grep -E "FRF|x_w"

for road in "C 2" "D 1"; do
  set -- $road
  name="class_$1"
  "$rigctl" road-target "$config" --class "$1" --speed "$2" --duration 20 --out "$work/$name.csv"
  for inverse in nominal: diagnosis:"--model $work/diagnosis.json" measured:"--frf $work/frf.json"; do
    label=${inverse%%:*}
    echo "== ISO 8608 class $1 at $2 m/s, inverse from: $label"
    # shellcheck disable=SC2086
    "$rigctl" iterate "$config" --target "$work/$name.csv" --channel x_w --out "$work/$name-$label" "${rig[@]}" \
      --tolerance 1 --max-iterations 8 ${inverse#*:} --plot | grep -E "iteration [0-9]|end:"
    cp "$work/$name-$label/iterations.png" "$out/${name}_${label}.png"
  done
done
