#!/usr/bin/env bash
# The main job on the bundled synthetic default, from a fresh machine (installs and builds
# first). Writes everything under $OUT (default out/demo):
#   synth/            the synthetic human face model and avatar rigs (retarget synth)
#   avatar/<name>/    the avatar's rig folder with proposed landmarks, eyes and parts (avatar init)
#   datasets/<name>/  DR-feature datasets of the default avatar and of the humans, each with
#                     preview.png (samples rebuilt from their features)
#   pictures/         rendered grids of the synthetic faces' expressions and the avatars' controllers
#   geometry/         the geometry-core demo: DR round trip and deformation transfer, with errors
#   runs/<name>/      the avatar and human VAEs (quick profile: configs/train/quick/), their
#                     metrics, checkpoints, evaluation (eval-best-test.json) and TorchScript export
#   avatar/<name>/proposed.yaml  the controller table `avatar meaning` proposes from the rig's
#                     geometry alone (--no-names): the prior round 1 starts from
#   test_faces/       the held-out people's 47 reference expressions and 20 random blends of the
#                     face model's shapes nobody annotated, as meshes (faces.yaml lists them)
#   method/           scripts/method.sh on BUDGET comparisons (default 2000, the paper's total):
#                     rounds/<r>/ (correspondences and the comparisons of three people-like
#                     simulated annotators, each with its own reading of the avatar's table,
#                     judging faces in mm), translation/ (F), bundle/, bundle-stage1/, the rig
#                     head (rig_head.yaml: blendshape weights -> controller weights from every
#                     decided comparison, the proposed table as prior) and the zero-annotation
#                     path (zero_annotation.yaml), each method's avatar meshes, and evaluation/:
#                     metrics.json (the neutral answer, DT alone, DT on the rig, stage 1, full,
#                     zero_annotation, rig_head; mm over all and moving vertices, per region,
#                     expression and set, rig-weight errors, fractions of the neutral answer),
#                     contact_sheet.png (the worst faces) and ladder/ladder.json (the error ladder)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
out="${OUT:-$root/out/demo}"
retarget="$build_dir/cli/retarget"
"$root/scripts/setup.sh"

avatar="${AVATAR:-fox}"
"$retarget" synth --out "$out/synth" --force
# The avatar as a new user brings it, a rig and nothing else: `avatar init` proposes its landmarks,
# eyes and parts from the rig alone (the generator's hand-made ones are not used; check
# $out/avatar/$avatar/landmarks.png). The controller table stays the generator's: it is the
# ground truth the simulated annotators and the evaluation score against.
"$retarget" avatar init "$out/synth/avatars/$avatar" --out "$out/avatar/$avatar" --force
cp "$out/synth/avatars/$avatar/correspondence.yaml" "$out/avatar/$avatar/correspondence.yaml"
"$retarget" dataset --rig "$out/avatar/$avatar" --out "$out/datasets/$avatar" --force
"$retarget" dataset --face-model "$out/synth/human/face_model.yaml" \
  --recipes "$root/configs/expressions/facewarehouse47.yaml" --out "$out/datasets/human" --force

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
    --out "$out/runs/$vae" --force
  "$retarget" eval vae "$out/runs/$vae"
  "$retarget" export "$out/runs/$vae" --out "$out/runs/$vae/export"
done
# The controller table proposed from the rig's geometry alone (no person, names not used: the
# generator's names would give the answer away), the test faces, and the method on a budget.
"$retarget" avatar meaning --rig "$out/avatar/$avatar" --face-model "$human/face_model.yaml" --no-names \
  --out "$out/avatar/$avatar/proposed.yaml"
"$retarget" faces "$out/datasets/human" --blends 20 --blend-seed 7 --out "$out/test_faces" --force
HUMAN="$out/datasets/human" AVATAR="$out/datasets/$avatar" RUNS="$out/runs" \
  TABLE="$out/avatar/$avatar/correspondence.yaml" PRIOR="$out/avatar/$avatar/proposed.yaml" \
  FACES="$out/test_faces" CONFIG="$root/configs/train/quick/translation.yaml" BUDGET="${BUDGET:-2000}" \
  OUT="$out/method" "$root/scripts/method.sh"
echo "demo: everything is in $out (pictures in $out/pictures, dataset previews in $out/datasets/*/preview.png,
  the end-to-end result in $out/method/evaluation/contact_sheet.png and metrics.json)"
