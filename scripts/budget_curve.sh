#!/usr/bin/env bash
# Error against the annotation budget: scripts/method.sh once per budget on datasets and VAEs
# that a demo or real-data run already made, then one CSV and one plot (gnuplot) of every
# method's error as a fraction of the neutral answer's, on the references and on the unseen
# blends, in mm over moving vertices and in active rig weights.
#   RUN=out/demo scripts/budget_curve.sh                      # after scripts/demo.sh
#   RUN=out/real-quick KIND=real scripts/budget_curve.sh      # after scripts/real_data.sh
# Knobs: BUDGETS (default "250 700 2000 5600"), AVATAR (demo: fox), OUT (default RUN/budget),
# PLOT_ONLY=1 (only the CSV and the plot, from the evaluations already in OUT).
# Writes OUT/<budget>/ (method.sh's folders), OUT/curve.csv and OUT/curve.png.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
run="${RUN:?set RUN to a finished demo or real-data output folder}"
kind="${KIND:-demo}"
out="${OUT:-$run/budget}"
budgets="${BUDGETS:-250 700 2000 5600}"
mkdir -p "$out"
if [[ $kind == demo ]]; then
  avatar="${AVATAR:-fox}"
  export HUMAN="$run/datasets/human" AVATAR_DS="$run/datasets/$avatar" RUNS="$run/runs" FACES="$run/test_faces"
  export TABLE="$run/avatar/$avatar/correspondence.yaml" PRIOR="$run/avatar/$avatar/proposed.yaml"
  export CONFIG="$root/configs/train/quick/translation.yaml"
else
  export HUMAN="$run/ict-ds" AVATAR_DS="$run/avatar-ds" RUNS="$run/runs" FACES="$run/faces"
  export TABLE="${TABLE:-$root/configs/real/lapin/correspondence.yaml}" PRIOR="$run/proposed.yaml"
  export CONFIG="$root/configs/train/${PROFILE:-quick}/translation.yaml"
fi
if [[ "${PLOT_ONLY:-0}" != 1 ]]; then
  for b in $budgets; do
    AVATAR="$AVATAR_DS" BUDGET="$b" OUT="$out/$b" "$root/scripts/method.sh"
  done
fi

python3 - "$out" $budgets <<'PY'
import json, sys
out, budgets = sys.argv[1], sys.argv[2:]
methods = ["dt_rig", "zero_annotation", "stage1", "full", "rig_head"]
with open(f"{out}/curve.csv", "w") as f:
    f.write("budget,set,method,moving_fraction_of_neutral,weight_active_fraction_of_neutral,moving_mm\n")
    for b in budgets:
        m = json.load(open(f"{out}/{b}/evaluation/metrics.json"))
        for s in ("references", "blends"):
            for name in methods:
                r = m["sets"][s]["methods"][name]
                f.write(f"{b},{s},{name},{r['moving_fraction_of_neutral']:.4f},"
                        f"{r['weight_active_fraction_of_neutral']:.4f},{r['moving_mm']:.4f}\n")
print(open(f"{out}/curve.csv").read())
PY

if command -v gnuplot >/dev/null; then
  gnuplot <<GP
set terminal pngcairo size 1200,500 font ",10" noenhanced
set output "$out/curve.png"
set datafile separator ","
set multiplot layout 1,2
set logscale x
set xlabel "annotation budget (comparisons)"
set ylabel "x neutral answer (mm over moving vertices)"
set key top right
set yrange [0:*]
do for [s in "references blends"] {
  set title s
  plot for [m in "dt_rig zero_annotation stage1 full rig_head"] \
    "< awk -F, '\$2==\"".s."\" && \$3==\"".m."\"' $out/curve.csv" using 1:4 with linespoints title m
}
unset multiplot
GP
  echo "budget_curve: $out/curve.csv, $out/curve.png"
else
  echo "budget_curve: $out/curve.csv (gnuplot not found: no plot; scripts/setup.sh installs it)"
fi
