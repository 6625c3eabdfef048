#!/usr/bin/env bash
# The method after the VAEs, on a budget of comparisons: rounds of comparisons answered by
# people-like simulated annotators (`retarget annotate simulate`), the translation network F on
# the last round, the rig head on every round's answers, the zero-annotation path, every
# method on the test faces, the evaluation per set (references, blends) and the error ladder.
# Needs trained VAEs; called by scripts/demo.sh, scripts/real_data.sh and scripts/budget_curve.sh.
#   HUMAN=datasets/human AVATAR=datasets/fox RUNS=runs TABLE=rig/correspondence.yaml \
#   PRIOR=proposed.yaml FACES=test_faces CONFIG=configs/train/quick/translation.yaml \
#   BUDGET=2000 OUT=out/method scripts/method.sh
# TABLE is the controller table the annotators read (each their own way) and the evaluation
# scores against; PRIOR the table `avatar meaning` proposes, which round 1 starts from and the
# rig head is regularised towards. BUDGET: comparisons in all.
# SEARCH=belief (the default) asks one comparison per expression per round, the pair with the
# most expected information under the belief over the rig head's map that every earlier answer
# updated (correspond/belief_search.h); the rig head is that belief's most likely map.
# ANNOTATION_BLENDS=N (default 47) also asks about N random training blends of the face
# model's shapes (`retarget dataset --blends`, a seed apart from the test faces'), so that
# shapes the recipes only show together are told apart; the last rounds ask about the
# references alone, for F. The paper's tournaments: SEARCH=champions (a round of
# 47 groups of 16 costs 705, the last round's groups shrink to fit) proposes each later round
# around each group's previous champion, SEARCH=map around the rig head of the rounds before.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
retarget="$build_dir/cli/retarget"
infer="$build_dir/infer/retarget-infer"
for v in HUMAN AVATAR RUNS TABLE PRIOR FACES CONFIG OUT; do
  [[ -n "${!v:-}" ]] || { echo "method: set $v (see the header of $0)" >&2; exit 2; }
done
budget="${BUDGET:-2000}"
# How rounds search (header): belief, champions or map.
search="${SEARCH:-belief}"
# One group per reference expression: the recipes the human dataset was built with.
recipes=$(sed -n 's/^recipes: //p' "$HUMAN/manifest.yaml" | head -1)
face_model=$(sed -n 's/^source: //p' "$HUMAN/manifest.yaml" | head -1)  # the face model the dataset was drawn from
groups=$(grep -c 'name:' "$recipes")
log() { echo "[$(date +%H:%M:%S)] method: $*"; }
mkdir -p "$OUT"
# The expressions the belief search asks about: the references, and training blends beside them.
annotate_human="$HUMAN"
annotate_groups=$groups
if [[ $search == belief ]] && ((${ANNOTATION_BLENDS:-47} > 0)); then
  annotate_human="$OUT/annotation_dataset"
  log "annotation dataset: the $groups references and ${ANNOTATION_BLENDS:-47} random training blends"
  "$retarget" dataset --face-model "$face_model" --recipes "$recipes" --blends "${ANNOTATION_BLENDS:-47}" \
    --people 8 --no-preview --out "$annotate_human" --force >"$OUT/annotation_dataset.log" 2>&1 ||
    { cat "$OUT/annotation_dataset.log" >&2; exit 1; }
  annotate_groups=$(grep -c 'name:' "$annotate_human/recipes.yaml")
fi

left=$budget
round=0
projects=()
previous=""
while ((left >= groups)); do
  round=$((round + 1))
  size=$((left / groups + 1))
  ((size > 16)) && size=16
  [[ $search == belief ]] && size=2
  corr="$OUT/rounds/$round/correspondences"
  project="$OUT/rounds/$round/annotation"
  if [[ $search == belief ]]; then
    evidence=()
    for p in "${projects[@]}"; do [[ $p == --annotation ]] || evidence+=(--evidence "$p"); done
    mkdir -p "$OUT/rounds"
    # Blends and references while the budget lasts, then the references alone (F trains on them).
    round_human="$HUMAN" cost=$groups
    ((left - annotate_groups >= groups)) && round_human="$annotate_human" cost=$annotate_groups
    ((round % 5 == 1)) && log "round $round: one informative pair per expression of $round_human, the belief after $((round - 1)) rounds"
    "$retarget" correspond --human "$round_human" --avatar "$AVATAR" --avatar-vae "$RUNS/avatar_vae" \
      --start-table "$PRIOR" --informative "${evidence[@]}" --out "$corr" --force >"$OUT/rounds/$round.log" 2>&1 ||
      { cat "$OUT/rounds/$round.log" >&2; exit 1; }
  elif ((round == 1)); then
    # From the proposed table's reading of each recipe on the rig: the start itself, rig
    # proposals around it and, in full groups, dataset samples chosen for variety.
    spread=$((size >= 16 ? 8 : 0))
    proposals=$((size >= 16 ? 4 : size - 1))
    log "round 1: groups of $size from the proposed table ($spread varied, $proposals proposed by the rig)"
    "$retarget" correspond --human "$HUMAN" --avatar "$AVATAR" --avatar-vae "$RUNS/avatar_vae" \
      --start-table "$PRIOR" --group-size "$size" --spread "$spread" --proposals "$proposals" --proposal-seed 1 \
      --out "$corr" --force
  elif [[ $search == champions ]]; then
    log "round $round: groups of $size proposed by the rig around round $((round - 1))'s champions"
    "$retarget" correspond --human "$HUMAN" --avatar "$AVATAR" --avatar-vae "$RUNS/avatar_vae" \
      --around "$previous" --group-size "$size" --proposals "$size" --proposal-seed "$round" --out "$corr" --force
  else
    # Around what every comparison so far says: the rig head fitted to the rounds before, which
    # pools the evidence of all expressions, with steps that shrink as the search narrows.
    sigma=$(awk -v r="$round" 'BEGIN { printf "%.3f", 0.4 * 0.7 ^ (r - 1) }')
    log "round $round: groups of $size proposed by the rig (step $sigma) around the rig head of rounds 1-$((round - 1))"
    mkdir -p "$OUT/rounds/$round"
    "$retarget" rig-map fit --correspondences "$OUT/rounds/1/correspondences" "${projects[@]}" --prior "$PRIOR" \
      --out "$OUT/rounds/$round/start_map.yaml"
    "$retarget" correspond --human "$HUMAN" --avatar "$AVATAR" --avatar-vae "$RUNS/avatar_vae" \
      --start-table "$OUT/rounds/$round/start_map.yaml" --group-size "$size" --proposals "$size" \
      --proposal-sigma "$sigma" --proposal-seed "$round" --out "$corr" --force
  fi
  if [[ $search == belief ]]; then  # quiet: many small rounds
    "$retarget" annotate init --correspondences "$corr" --out "$project" --force >/dev/null
    "$retarget" annotate simulate "$project" --table "$TABLE" --seed "$round" >>"$OUT/rounds/$round.log" 2>&1
  else
    "$retarget" annotate init --correspondences "$corr" --out "$project" --force
    "$retarget" annotate simulate "$project" --table "$TABLE" --seed "$round"
  fi
  if [[ $search == belief ]]; then left=$((left - cost)); else left=$((left - groups * (size - 1))); fi
  previous="$project"
  projects+=(--annotation "$project")
done
((round > 0)) || { echo "method: a budget of $budget cannot pay one comparison per group ($groups)" >&2; exit 2; }
log "$round rounds, $((budget - left)) comparisons of $budget"

log "translation on round $round's groups and triplets"
"$retarget" annotate export "$previous" --out "$previous/triplets.csv"
"$retarget" train "$CONFIG" --set "data.human_vae=$RUNS/human_vae" --set "data.avatar_vae=$RUNS/avatar_vae" \
  --set "data.correspondences=$OUT/rounds/$round/correspondences" --set "data.triplets=$previous" \
  --out "$OUT/translation" --force
"$retarget" export "$OUT/translation" --out "$OUT/bundle"
"$retarget" export "$OUT/translation" --checkpoint stage1 --out "$OUT/bundle-stage1"

log "the rig head on every round's champions, and the proposed table alone (no person)"
head_mode=()
[[ $search == belief ]] && head_mode=(--belief)  # the belief's most likely map
"$retarget" rig-map fit --correspondences "$OUT/rounds/1/correspondences" "${projects[@]}" --prior "$PRIOR" \
  "${head_mode[@]}" --out "$OUT/rig_head.yaml"
"$retarget" rig-map fit --correspondences "$OUT/rounds/1/correspondences" --prior "$PRIOR" \
  --out "$OUT/zero_annotation.yaml"

log "every method on $FACES, the evaluation per set and the ladder"
"$infer" --bundle "$OUT/bundle" "$FACES" --out "$OUT/full"
"$infer" --bundle "$OUT/bundle-stage1" "$FACES" --out "$OUT/stage1"
for map in rig_head zero_annotation; do  # the rig head through the runtime, as users run it
  "$infer" --bundle "$OUT/bundle" --rig-map "$OUT/$map.yaml" --face-model "$face_model" "$FACES" --out "$OUT/$map"
done
"$retarget" eval retarget --faces "$FACES" --correspondences "$OUT/rounds/$round/correspondences" --table "$TABLE" \
  --method "stage1=$OUT/stage1" --method "full=$OUT/full" --method "zero_annotation=$OUT/zero_annotation" \
  --method "rig_head=$OUT/rig_head" --out "$OUT/evaluation"
"$retarget" eval ladder --correspondences "$OUT/rounds/$round/correspondences" --translation "$OUT/translation" \
  --table "$TABLE" --faces "$FACES" --out "$OUT/evaluation/ladder"
log "done: $OUT/evaluation/metrics.json"
