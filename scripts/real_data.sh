#!/usr/bin/env bash
# The README's real-data recipe in one command: ICT people (../shared/data/ict-face, drawn from
# its identity modes) onto the shared Weboji rabbit, every step through the `retarget` CLI, then
# the end-to-end evaluation beside the trivial answer and the error ladder. Needs the build
# (scripts/setup.sh) and ../shared/data (or $RETARGET_SHARED_DATA); never copies the data.
#   scripts/real_data.sh                 # quick profile into out/real-quick
#   PROFILE=good scripts/real_data.sh    # configs/train/good/ into out/real-good
# Knobs: PEOPLE (ICT people drawn, default 24: ~20% held out as unseen people), OUT, RIG
# (a rig folder or glTF; default configs/real/lapin), TABLE (its controller table), INITIAL
# (rig | dt: what y0 and the groups start from), ROUNDS (rounds of tournaments, default 8: each
# later round's groups surround the previous round's champions; the champions stop improving
# after about 8 on the rabbit), SPREAD / SPREAD_LATER (members of each group chosen for variety
# in the first / later rounds, default 8 / 0 of 16: later rounds refine locally),
# PROPOSALS (members of each later group generated from the rig around the previous champion,
# default 16 of 16: the dataset's samples are too sparse to refine a champion; 0 = dataset
# samples only), PROPOSALS_FIRST (members of each first-round group generated from the rig
# around the start, DT projected onto the rig, the start itself first, default 4: so that the
# first round, like every later one, can keep what it starts from; INITIAL=rig only),
# PROPOSAL_SIGMA (their step, a fraction of a controller's range, default 0.4),
# NOISE (the simulated annotators' perception noise, in rig-weight distance; default 0.05),
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
rounds="${ROUNDS:-8}"
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
  "$retarget" annotate simulate "$out/annotation-$tag" --table "$table" --noise "$noise"
done

log "translation on the last round's groups and triplets"
"$retarget" train "$configs/translation.yaml" --set "data.human_vae=$out/runs/human_vae" \
  --set "data.avatar_vae=$out/runs/avatar_vae" --set "data.correspondences=$out/corr-$tag" \
  --set "data.triplets=$out/annotation-$tag" --set "output=$out/runs/translation-$tag" --force
"$retarget" export "$out/runs/translation-$tag" --out "$out/bundle-$tag"
"$retarget" export "$out/runs/translation-$tag" --checkpoint stage1 --out "$out/bundle-$tag-stage1"

log "unseen people through retarget-infer, evaluation and ladder"
"$retarget" faces "$out/ict-ds" --out "$out/faces" --force
"$infer" --bundle "$out/bundle-$tag" "$out/faces" --out "$out/full-$tag"
"$infer" --bundle "$out/bundle-$tag-stage1" "$out/faces" --out "$out/stage1-$tag"
"$retarget" eval retarget --faces "$out/faces" --correspondences "$out/corr-$tag" --table "$table" \
  --method "stage1=$out/stage1-$tag" --method "full=$out/full-$tag" --out "$out/eval-$tag"
"$retarget" eval ladder --correspondences "$out/corr-$tag" --translation "$out/runs/translation-$tag" \
  --table "$table" --out "$out/ladder-$tag"
log "done: $out/eval-$tag/metrics.json, contact_sheet.png; $out/ladder-$tag/ladder.json"
