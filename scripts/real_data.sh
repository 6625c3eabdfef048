#!/usr/bin/env bash
# The README's real-data recipe in one command: ICT people (../shared/data/ict-face, drawn from
# its identity modes) onto the shared Weboji rabbit, every step through the `retarget` CLI, then
# the end-to-end evaluation beside the trivial answer and the error ladder. Needs the build
# (scripts/setup.sh) and ../shared/data (or $RETARGET_SHARED_DATA); never copies the data.
#   scripts/real_data.sh                 # quick profile into out/real-quick
#   PROFILE=good scripts/real_data.sh    # configs/train/good/ into out/real-good
# Knobs: PEOPLE (ICT people drawn, default 24: ~20% held out as unseen people), OUT, RIG
# (a rig folder or glTF; default configs/real/lapin), TABLE (its controller table), INITIAL
# (rig | dt: what y0 and the groups start from), BUDGET (comparisons in all, default 2000, the
# paper's total: 705 a round of 47 groups x 15, the last round stopped when it is spent; each
# later round's groups surround the previous round's champions), SPREAD / SPREAD_LATER (members of each group chosen for variety
# in the first / later rounds, default 8 / 0 of 16: later rounds refine locally),
# PROPOSALS (members of each later group generated from the rig around the previous champion,
# default 16 of 16: the dataset's samples are too sparse to refine a champion; 0 = dataset
# samples only), PROPOSALS_FIRST (members of each first-round group generated from the rig
# around the start, DT projected onto the rig, the start itself first, default 4: so that the
# first round, like every later one, can keep what it starts from; INITIAL=rig only),
# PROPOSAL_SIGMA (their step, a fraction of a controller's range, default 0.4),
# NOISE (the simulated annotators' perception noise in mm, default 0.05; they are people-like:
# each reads the controller table its own way and judges faces, `retarget annotate simulate
# --help`), BLENDS (random blends per unseen person beside the 47 references, default 20),
# SKIP_VAES=1 (reuse trained VAEs in OUT).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
profile="${PROFILE:-quick}"
out="${OUT:-$root/out/real-$profile}"
people="${PEOPLE:-24}"
rig="${RIG:-$root/configs/real/lapin}"
table="${TABLE:-$root/configs/real/lapin/correspondence.yaml}"
initial="${INITIAL:-rig}"
budget="${BUDGET:-2000}"
per_round=705
rounds=$(((budget + per_round - 1) / per_round))
blends="${BLENDS:-20}"
spread="${SPREAD:-8}"
spread_later="${SPREAD_LATER:-0}"
proposals="${PROPOSALS:-16}"
proposals_first="${PROPOSALS_FIRST:-4}"
[[ "$initial" == rig ]] || proposals_first=0  # proposals need a start on the rig
proposal_sigma="${PROPOSAL_SIGMA:-0.4}"
noise="${NOISE:-0.05}"
shared="${RETARGET_SHARED_DATA:-$root/../shared/data}"
retarget="$build_dir/cli/retarget"
infer="$build_dir/infer/retarget-infer"
configs="$root/configs/train/$profile"
[[ -d "$configs" ]] || { echo "real_data: no profile $configs" >&2; exit 2; }
[[ -d "$shared/ict-face" ]] || { echo "real_data: $shared/ict-face not found (set RETARGET_SHARED_DATA)" >&2; exit 2; }
mkdir -p "$out"
log() { echo "[$(date +%H:%M:%S)] $*"; }

if [[ "${SKIP_VAES:-0}" != 1 ]]; then
  log "datasets"
  "$retarget" dataset --face-model "$root/configs/real/ict/face_model.yaml" \
    --recipes "$root/configs/expressions/facewarehouse47.yaml" --people "$people" --out "$out/ict-ds" --force
  "$retarget" dataset --rig "$rig" --out "$out/avatar-ds" --force
  for vae in human_vae avatar_vae; do
    dataset="$out/$([[ $vae == human_vae ]] && echo ict-ds || echo avatar-ds)"
    log "training $vae ($profile profile)"
    /usr/bin/time -f "$vae: %e s wall" "$retarget" train "$configs/$vae.yaml" --set "data.dataset=$dataset" \
      --set "output=$out/runs/$vae" --force
    "$retarget" eval vae "$out/runs/$vae"
  done
fi

tag="$initial"
projects=()
for ((round = 1; round <= rounds; ++round)); do
  if ((round == 1)); then
    log "correspondences (initial: $initial, $spread varied members and $proposals_first proposed by the rig per group), round 1 of tournaments"
    "$retarget" correspond --human "$out/ict-ds" --avatar "$out/avatar-ds" --avatar-vae "$out/runs/avatar_vae" \
      --initial "$initial" --spread "$spread" --proposals "$proposals_first" --proposal-sigma "$proposal_sigma" \
      --proposal-seed 1 --out "$out/corr-$tag" --force
  else
    previous="$tag"
    tag="$initial-r$round"
    log "correspondences around the champions of round $((round - 1)) ($proposals proposed by the rig), round $round of tournaments"
    "$retarget" correspond --human "$out/ict-ds" --avatar "$out/avatar-ds" --avatar-vae "$out/runs/avatar_vae" \
      --around "$out/annotation-$previous" --spread "$spread_later" --proposals "$proposals" \
      --proposal-sigma "$proposal_sigma" --proposal-seed "$round" --out "$out/corr-$tag" --force
  fi
  "$retarget" annotate init --correspondences "$out/corr-$tag" --out "$out/annotation-$tag" --force
  left=$((budget - (round - 1) * per_round))
  "$retarget" annotate simulate "$out/annotation-$tag" --table "$table" --noise "$noise" --seed "$round" \
    --budget "$((left < per_round ? left : 0))"
  projects+=(--annotation "$out/annotation-$tag")
done

log "translation on the last round's groups and triplets"
"$retarget" train "$configs/translation.yaml" --set "data.human_vae=$out/runs/human_vae" \
  --set "data.avatar_vae=$out/runs/avatar_vae" --set "data.correspondences=$out/corr-$tag" \
  --set "data.triplets=$out/annotation-$tag" --set "output=$out/runs/translation-$tag" --force
"$retarget" export "$out/runs/translation-$tag" --out "$out/bundle-$tag"
"$retarget" export "$out/runs/translation-$tag" --checkpoint stage1 --out "$out/bundle-$tag-stage1"

log "the rig head: champions against recipes, avatar meaning's table as prior; and the prior alone"
"$retarget" avatar meaning --rig "$rig" --face-model "$root/configs/real/ict/face_model.yaml" \
  --out "$out/proposed.yaml"
"$retarget" rig-map fit --correspondences "$out/corr-$initial" "${projects[@]}" --prior "$out/proposed.yaml" \
  --out "$out/rig_head-$tag.yaml"
"$retarget" rig-map fit --correspondences "$out/corr-$initial" --prior "$out/proposed.yaml" \
  --out "$out/zero_annotation.yaml"

log "unseen people (references and $blends blends each) through every method, evaluation and ladder"
"$retarget" faces "$out/ict-ds" --blends "$blends" --blend-seed 7 --out "$out/faces" --force
"$infer" --bundle "$out/bundle-$tag" "$out/faces" --out "$out/full-$tag"
"$infer" --bundle "$out/bundle-$tag-stage1" "$out/faces" --out "$out/stage1-$tag"
"$retarget" rig-map apply "$out/rig_head-$tag.yaml" --faces "$out/faces" --correspondences "$out/corr-$tag" \
  --out "$out/rig_head-$tag"
"$retarget" rig-map apply "$out/zero_annotation.yaml" --faces "$out/faces" --correspondences "$out/corr-$tag" \
  --out "$out/zero_annotation"
"$retarget" eval retarget --faces "$out/faces" --correspondences "$out/corr-$tag" --table "$table" \
  --method "stage1=$out/stage1-$tag" --method "full=$out/full-$tag" --method "zero_annotation=$out/zero_annotation" \
  --method "rig_head=$out/rig_head-$tag" --out "$out/eval-$tag"
"$retarget" eval ladder --correspondences "$out/corr-$tag" --translation "$out/runs/translation-$tag" \
  --table "$table" --out "$out/ladder-$tag"
log "done: $out/eval-$tag/metrics.json, contact_sheet.png; $out/ladder-$tag/ladder.json"
