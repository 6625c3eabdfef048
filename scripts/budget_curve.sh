#!/usr/bin/env bash
# Error against the annotation budget: the method (`retarget pipeline`) once per budget on the
# datasets and VAEs of a pipeline run (they are up to date, so only the method's stages run, each
# budget into RUN/budget/<budget>/), then one CSV and one plot (gnuplot) of every method's error
# as a fraction of the neutral answer's, on the references and on the unseen blends, in mm over
# moving vertices and in active rig weights.
#   RUN=out/demo scripts/budget_curve.sh                                  # after scripts/demo.sh
#   RUN=out/real-quick RECIPE=configs/recipes/real.yaml scripts/budget_curve.sh   # after scripts/real_data.sh
# Knobs: BUDGETS (default "250 700 2000 5600"), RECIPE (default configs/recipes/demo.yaml), OUT
# (default RUN/budget; inside RUN), PLOT_ONLY=1 (only the CSV and the plot, from the evaluations
# already in OUT). Extra arguments go to the pipeline (--set ...).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
run="$(realpath "${RUN:?set RUN to a finished pipeline run folder}")"
recipe="${RECIPE:-$root/configs/recipes/demo.yaml}"
out="$(realpath -m "${OUT:-$run/budget}")"
budgets="${BUDGETS:-250 700 2000 5600}"
[[ "$out" == "$run"/* ]] || { echo "budget_curve: OUT must be inside RUN ($run)" >&2; exit 2; }
mkdir -p "$out"
if [[ "${PLOT_ONLY:-0}" != 1 ]]; then
  for b in $budgets; do
    "${BUILD_DIR:-$root/build}/cli/retarget" pipeline "$recipe" --out "$run" --set "method.budget=$b" \
      --set "method.folder=${out#"$run"/}/$b" "$@"
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

# The plot: `retarget plot` (plot/budget_plot.cpp, gnuplot) into OUT/curve.png.
"${BUILD_DIR:-$root/build}/cli/retarget" plot "$out" --out "$out"
echo "budget_curve: $out/curve.csv, $out/curve.png"
