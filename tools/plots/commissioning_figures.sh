#!/usr/bin/env bash
# Commissions both simulated rigs from a proportional stabiliser, as the
# README's "Commissioning" section shows: rigctl identify, rigctl tune (FRF
# design and relay Ziegler-Nichols), the tuned loop measured again, and the
# standard step test of the start, the shipped, the tuned and the relay
# gains. Plots go to docs/figures/commissioning/ (or the folder given); the
# numbers (BENCHMARKS.md "Commissioning") are printed.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-$root/docs/figures/commissioning}
work=$(mktemp -d)
trap '[ -n "${KEEP_WORK:-}" ] || rm -rf "$work"' EXIT
mkdir -p "$out"
rigctl="$root/build/tools/rigctl"

# rig, stabiliser edit (sed), target phase margin, amplitude for the check of the tuned loop
commission() {
  local rig=$1 edit=$2 pm=$3 gain=$4
  local dir="$work/$rig" config="$root/config/$rig.yaml"
  mkdir -p "$dir"
  sed -e "$edit" "$config" > "$dir/start.yaml"
  echo "== $rig (start: stabiliser gain $gain, target phase margin $pm deg)"
  "$rigctl" identify "$dir/start.yaml" --fast --out "$dir/frf.json" --log "$dir/id.lcm" --plot "$out/${rig}_frf.png" | grep -E "amplitude|FRF|plant"
  "$rigctl" tune "$dir/start.yaml" --frf "$dir/frf.json" --phase-margin "$pm" --out "$dir/tuned.yaml" \
    --json "$dir/tune.json" --plot "$out/${rig}_tuned.png" | grep -E "gains|predicted"
  "$rigctl" tune "$dir/start.yaml" --method relay --fast --frf "$dir/frf.json" --out "$dir/zn.yaml" --log "$dir/relay.lcm" \
    | grep -E "limit cycle|gains|predicted \("
  # The check's excitation swings the valve as much as the first one did
  # (quarter car: its demand gain grew from the stabiliser's to the tuned kp).
  local check=()
  if [ "$rig" = quarter_car ]; then
    check=(--amplitude "$(/usr/bin/python3 -c "import json; print(0.0025 * $gain / json.load(open('$dir/tune.json'))['gains']['kp'])")")
  fi
  "$rigctl" identify "$dir/tuned.yaml" --fast --out "$dir/check.json" --log "$dir/check.lcm" "${check[@]}" >/dev/null
  echo "tuned loop identified again:"
  { "$rigctl" tune "$dir/tuned.yaml" --frf "$dir/check.json" --phase-margin "$pm" 2>&1 || true; } | grep "measured"
  for gains in start:"$dir/start.yaml" shipped:"$config" tuned:"$dir/tuned.yaml" relay-zn:"$dir/zn.yaml"; do
    "$rigctl" run "${gains#*:}" --fast --csv "$dir/${gains%%:*}.csv" --log "$dir/${gains%%:*}.lcm" >/dev/null
    echo -n "step test, ${gains%%:*} gains: "
    "$rigctl" tune "${gains#*:}" --evaluate "$dir/${gains%%:*}.csv" | sed 's/^.*csv: //'
  done
}

commission quarter_car 's/^  kp: 80.0 /  kp: 20.0 /; s/^  ki: 60.0 /  ki: 0.0 /' 60 20
commission pneumatic_rotary 's/^  ke: 3.7 /  ke: 2.5 /' 80 2.5
