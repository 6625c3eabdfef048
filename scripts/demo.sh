#!/usr/bin/env bash
# The main job on the bundled synthetic default, from a fresh machine (installs and builds
# first). Writes everything under $OUT (default out/demo):
#   synth/            the synthetic human face model and avatar rigs (retarget synth)
#   datasets/<name>/  DR-feature datasets of the default avatar and of the humans, each with
#                     preview.png (samples rebuilt from their features)
#   pictures/         rendered grids of the synthetic faces' expressions and the avatars' controllers
#   geometry/         the geometry-core demo: DR round trip and deformation transfer, with errors
#   runs/<name>/      the avatar and human VAEs (quick profile: configs/train/quick/), their
#                     metrics, checkpoints, evaluation (eval-best-test.json) and TorchScript export
# Later stages (correspondences, translation, inference) are added as they land.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
out="${OUT:-$root/out/demo}"
retarget="$build_dir/train/retarget"
"$root/scripts/setup.sh"

avatar="${AVATAR:-fox}"
"$retarget" synth --out "$out/synth" --force
"$retarget" dataset --rig "$out/synth/avatars/$avatar" --out "$out/datasets/$avatar" --force
"$retarget" dataset --face-model "$out/synth/human/face_model.yaml" \
  --recipes "$root/configs/expressions/facewarehouse47.yaml" --people 24 --out "$out/datasets/human" --force

mkdir -p "$out/pictures"
human="$out/synth/human"
"$retarget" render "$human/neutral.obj" "$human"/expressions/{jawOpen,mouthSmile_L,eyeBlink_L,browInnerUp_L,mouthPucker}.obj \
  --title "synthetic human: blendshapes" --out "$out/pictures/human_blendshapes.png"
for rig in "$out"/synth/avatars/*/; do
  name=$(basename "$rig")
  targets=$(ls "$rig"*.obj | grep -v '/neutral.obj$' | head -n 7)
  # shellcheck disable=SC2086
  "$retarget" render "$rig/neutral.obj" $targets --title "avatar $name: controllers" \
    --out "$out/pictures/avatar_$name.png"
done
"$retarget" demo --out "$out/geometry"

# The VAEs (quick profile), their reconstruction error in mm and their TorchScript export.
for vae in avatar_vae human_vae; do
  dataset="$out/datasets/$([[ $vae == avatar_vae ]] && echo "$avatar" || echo human)"
  "$retarget" train "$root/configs/train/quick/$vae.yaml" --set "data.dataset=$dataset" \
    --set "output=$out/runs/$vae" --force
  "$retarget" eval vae "$out/runs/$vae"
  "$retarget" export "$out/runs/$vae" --out "$out/runs/$vae/export"
done
echo "demo: everything is in $out (pictures in $out/pictures, dataset previews in $out/datasets/*/preview.png)"
