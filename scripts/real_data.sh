#!/usr/bin/env bash
# The README's real-data recipe in one command: ICT people (../shared/data/ict-face, drawn from
# its identity modes) onto the shared Weboji rabbit, every step through the `retarget` CLI, then
# the end-to-end evaluation beside the trivial answer and the error ladder. Needs the build
# (scripts/setup.sh) and ../shared/data (or $RETARGET_SHARED_DATA); never copies the data.
#   scripts/real_data.sh                 # quick profile into out/real-quick
#   PROFILE=good scripts/real_data.sh    # configs/train/good/ into out/real-good
# Knobs: PEOPLE (ICT people drawn, default 24: ~20% held out as unseen people), OUT, RIG
# (a rig folder or glTF; default configs/real/lapin), TABLE (its controller table), INITIAL
# (rig | dt: what y0 and the groups start from), SKIP_VAES=1 (reuse trained VAEs in OUT).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
profile="${PROFILE:-quick}"
out="${OUT:-$root/out/real-$profile}"
people="${PEOPLE:-24}"
rig="${RIG:-$root/configs/real/lapin}"
table="${TABLE:-$root/configs/real/lapin/correspondence.yaml}"
initial="${INITIAL:-rig}"
shared="${RETARGET_SHARED_DATA:-$root/../shared/data}"
retarget="$build_dir/train/retarget"
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

log "correspondences (initial: $initial), annotation, translation"
"$retarget" correspond --human "$out/ict-ds" --avatar "$out/avatar-ds" --avatar-vae "$out/runs/avatar_vae" \
  --initial "$initial" --out "$out/corr-$initial" --force
"$retarget" annotate init --correspondences "$out/corr-$initial" --out "$out/annotation-$initial" --force
"$retarget" annotate simulate "$out/annotation-$initial" --table "$table"
"$retarget" train "$configs/translation.yaml" --set "data.human_vae=$out/runs/human_vae" \
  --set "data.avatar_vae=$out/runs/avatar_vae" --set "data.correspondences=$out/corr-$initial" \
  --set "data.triplets=$out/annotation-$initial" --set "output=$out/runs/translation-$initial" --force
"$retarget" export "$out/runs/translation-$initial" --out "$out/bundle-$initial"
"$retarget" export "$out/runs/translation-$initial" --checkpoint stage1 --out "$out/bundle-$initial-stage1"

log "unseen people through retarget-infer, evaluation and ladder"
"$retarget" faces "$out/ict-ds" --out "$out/faces" --force
"$infer" --bundle "$out/bundle-$initial" "$out/faces" --out "$out/full-$initial"
"$infer" --bundle "$out/bundle-$initial-stage1" "$out/faces" --out "$out/stage1-$initial"
"$retarget" eval retarget --faces "$out/faces" --correspondences "$out/corr-$initial" --table "$table" \
  --method "stage1=$out/stage1-$initial" --method "full=$out/full-$initial" --out "$out/eval-$initial"
"$retarget" eval ladder --correspondences "$out/corr-$initial" --translation "$out/runs/translation-$initial" \
  --table "$table" --out "$out/ladder-$initial"
log "done: $out/eval-$initial/metrics.json, contact_sheet.png; $out/ladder-$initial/ladder.json"
