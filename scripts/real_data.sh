#!/usr/bin/env bash
# The real-data recipe (docs/usage/real-data.md) in one command: ICT people (../shared/data/ict-face, drawn from
# its identity modes) onto the shared Weboji rabbit, every step through the `retarget` CLI: the
# datasets and both VAEs, then scripts/method.sh (rounds of comparisons answered by people-like
# simulated annotators on a budget of comparisons, F, the rig head, the zero-annotation path,
# the evaluation on unseen people's references and blends beside the trivial answer, the error
# ladder). Needs the build (scripts/setup.sh) and ../shared/data (or $RETARGET_SHARED_DATA);
# never copies the data.
#   scripts/real_data.sh                 # quick profile into out/real-quick
#   PROFILE=good scripts/real_data.sh    # configs/train/good/ into out/real-good
# Knobs: PEOPLE (ICT people drawn, default 24: ~20% held out as unseen people), OUT, RIG (a rig
# folder or glTF; default configs/real/lapin), TABLE (its controller table: what the annotators
# read, each their own way, and what the evaluation scores against), BUDGET (comparisons in
# all, default 2000), BLENDS (random blends per unseen person, default 20), SKIP_VAES=1 (reuse
# the datasets and VAEs in OUT).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
profile="${PROFILE:-quick}"
out="${OUT:-$root/out/real-$profile}"
people="${PEOPLE:-24}"
rig="${RIG:-$root/configs/real/lapin}"
table="${TABLE:-$root/configs/real/lapin/correspondence.yaml}"
budget="${BUDGET:-2000}"
blends="${BLENDS:-20}"
shared="${RETARGET_SHARED_DATA:-$root/../shared/data}"
retarget="$build_dir/cli/retarget"
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
      --out "$out/runs/$vae" --force
    "$retarget" eval vae "$out/runs/$vae"
  done
fi

log "avatar meaning: the rig's controller table proposed by geometry alone (the prior)"
"$retarget" avatar meaning --rig "$rig" --face-model "$root/configs/real/ict/face_model.yaml" --no-names \
  --out "$out/proposed.yaml"
"$retarget" faces "$out/ict-ds" --blends "$blends" --blend-seed 7 --out "$out/faces" --force
HUMAN="$out/ict-ds" AVATAR="$out/avatar-ds" RUNS="$out/runs" TABLE="$table" PRIOR="$out/proposed.yaml" \
  FACES="$out/faces" CONFIG="$configs/translation.yaml" BUDGET="$budget" OUT="$out/method-$budget" \
  "$root/scripts/method.sh"
log "done: $out/method-$budget/evaluation/metrics.json"
