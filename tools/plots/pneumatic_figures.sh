#!/usr/bin/env bash
# Runs the paper's pneumatic cases (config/pneumatic_rotary.yaml `cases:`)
# with the simulated rig and draws them side by side like seed 002's
# Figs. 4-11, into tools/plots/figures/pneumatic/ (or the folder given).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-$root/tools/plots/figures/pneumatic}
runs=$(mktemp -d)
trap 'rm -rf "$runs"' EXIT
mkdir -p "$out"
rigctl="$root/build/tools/rigctl"
config="$root/config/pneumatic_rotary.yaml"
for c in fig4a fig4c fig4e fig5a fig5c fig6 fig7 fig8 fig9 fig10 fig10_no_brake fig11_bladder fig11_coulomb unstable_ke74; do
  "$rigctl" run "$config" --case "$c" --fast --log "$runs/$c.lcm" --csv "$runs/$c.csv" >/dev/null
done
plot() { /usr/bin/python3 "$root/tools/plots/plot_cases.py" "$@"; }
plot --out "$out/fig04_gain_and_payload.png" --title "Fig. 4: proportional-to-error control, +-2 % bladder hysteresis" \
  "Ke 1.2, I 1.7:Ke 1.2=$runs/fig4a.csv" "Ke 3.7, I 1.7:Ke 3.7=$runs/fig4c.csv" "Ke 3.7, I 0.4:I 0.4=$runs/fig4e.csv"
plot --out "$out/fig05_coulomb_brake.png" --title "Fig. 5: +-8 % Coulomb friction from the brake" \
  "Ke 3.7, I 1.7:brake 8 %=$runs/fig5a.csv" "Ke 7.4, I 0.4:brake 8 %=$runs/fig5c.csv" \
  "Ke 7.4, I 0.4:no hysteresis, no brake=$runs/unstable_ke74.csv"
plot --out "$out/fig06_to_08_feedback.png" --title "Figs. 6-8: velocity, pressure and transient pressure feedback" \
  "velocity feedback:Ke 3.7=$runs/fig4c.csv" "velocity feedback:Ke 3.7, Kv 0.3=$runs/fig6.csv" \
  "pressure feedback:Ke 4.9, Kp 1.7 V/bar=$runs/fig7.csv" "pressure feedback:Ke 4.9, Ktp 1.7 V/bar transient=$runs/fig8.csv"
plot --out "$out/fig09_to_11_hysteresis.png" --title "Figs. 9-11: the kind and level of hysteresis" \
  "Fig. 9 (step):+-2 % bladder=$runs/fig4c.csv" "Fig. 9 (step):no hysteresis=$runs/fig9.csv" \
  "Fig. 10 (ramp):+-2 % bladder only=$runs/fig10_no_brake.csv" "Fig. 10 (ramp):+-10 % Coulomb=$runs/fig10.csv" \
  "Fig. 11 (step):+-6 % bladder=$runs/fig11_bladder.csv" "Fig. 11 (step):+-6 % Coulomb=$runs/fig11_coulomb.csv"
