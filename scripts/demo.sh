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
#   correspondences/  deformation transfer of the 47 human reference expressions onto the avatar,
#                     projected onto the rig: y0 codes and groups of 16 (the 4 nearest avatar
#                     samples, 8 chosen for variety and 4 rig expressions around the start, the
#                     start itself first, so that round 1 can keep it)
#   annotation/       round 1: the tournament store (annotations.db) answered by three simulated
#                     annotators, each with its own reading of the avatar's controller table,
#                     judging faces in mm (correspond/perceived_scores.h)
#   correspondences-<r>/, annotation-<r>/  later rounds: groups of 16 rig expressions proposed
#                     around the previous round's champions, their tournaments; the last
#                     round's triplets.csv; F trains on the last round. BUDGET (default 2000,
#                     the paper's total) is the number of comparisons in all: 705 a round
#                     (47 groups x 15), the last round stopped when the budget is spent
#   rig_head.yaml, zero_annotation.yaml  the rig head: human blendshape weights -> controller
#                     weights, fitted to the champions with `avatar meaning`'s table as prior
#                     (avatar/<name>/proposed.yaml), and that prior alone (no person at all)
#   runs/translation/ the translation network F (three stages), checkpoints per stage
#   bundle/, bundle-stage1/  the retargeting bundles (full and stage 1 only) for retarget-infer
#   test_faces/       the held-out people's 47 reference expressions and 20 random blends of the
#                     face model's shapes nobody annotated, as meshes (faces.yaml lists them)
#   retargeted/, retargeted-stage1/, rig_head/, zero_annotation/  each method's avatar meshes
#   evaluation/       metrics.json (the neutral answer, DT alone, DT projected onto the rig, stage 1,
#                     full: mm over all and over moving vertices, per region and expression, rig-weight
#                     errors, fractions of the neutral answer), contact_sheet.png (the worst faces:
#                     human | DT | DT on the rig | stage 1 | full | ground truth) and ladder/ladder.json
#                     (the error ladder: where the error comes from)
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
    --set "output=$out/runs/$vae" --force
  "$retarget" eval vae "$out/runs/$vae"
  "$retarget" export "$out/runs/$vae" --out "$out/runs/$vae/export"
done
# Correspondences, rounds of tournaments answered by simulated annotators (each later round's
# groups are rig proposals around the previous round's champions), the translation network and
# its bundles.
"$retarget" correspond --human "$out/datasets/human" --avatar "$out/datasets/$avatar" \
  --avatar-vae "$out/runs/avatar_vae" --spread 8 --proposals 4 --proposal-seed 1 --out "$out/correspondences" --force
# The annotation budget: comparisons in all, 705 per round (47 groups x 15 comparisons).
budget="${BUDGET:-2000}"
per_round=705
rounds=$(((budget + per_round - 1) / per_round))
simulate() {  # project, round: the round's share of the budget
  local left=$((budget - ($2 - 1) * per_round))
  "$retarget" annotate simulate "$1" --table "$out/avatar/$avatar/correspondence.yaml" \
    --budget "$((left < per_round ? left : 0))" --seed "$2"
}
"$retarget" annotate init --correspondences "$out/correspondences" --out "$out/annotation" --force
simulate "$out/annotation" 1
previous="$out/annotation"
projects=("$out/annotation")
for ((round = 2; round <= rounds; ++round)); do
  "$retarget" correspond --human "$out/datasets/human" --avatar "$out/datasets/$avatar" \
    --avatar-vae "$out/runs/avatar_vae" --around "$previous" --proposals 16 --proposal-seed "$round" \
    --out "$out/correspondences-$round" --force
  "$retarget" annotate init --correspondences "$out/correspondences-$round" --out "$out/annotation-$round" --force
  simulate "$out/annotation-$round" "$round"
  previous="$out/annotation-$round"
  projects+=("$out/annotation-$round")
done
last="$([[ $rounds -ge 2 ]] && echo "-$rounds" || echo "")"
"$retarget" annotate export "$out/annotation$last" --out "$out/annotation$last/triplets.csv"
"$retarget" train "$root/configs/train/quick/translation.yaml" --set "data.human_vae=$out/runs/human_vae" \
  --set "data.avatar_vae=$out/runs/avatar_vae" --set "data.correspondences=$out/correspondences$last" \
  --set "data.triplets=$out/annotation$last" --set "output=$out/runs/translation" --force
"$retarget" export "$out/runs/translation" --out "$out/bundle"
"$retarget" export "$out/runs/translation" --checkpoint stage1 --out "$out/bundle-stage1"

# The rig head: the champions' rig weights against their recipes, `avatar meaning`'s table (no
# person involved) as the prior; and that prior alone, the zero-annotation path.
"$retarget" avatar meaning --rig "$out/avatar/$avatar" --face-model "$human/face_model.yaml" \
  --out "$out/avatar/$avatar/proposed.yaml"
annotations=()
for p in "${projects[@]}"; do annotations+=(--annotation "$p"); done
"$retarget" rig-map fit --correspondences "$out/correspondences" "${annotations[@]}" \
  --prior "$out/avatar/$avatar/proposed.yaml" --out "$out/rig_head.yaml"
"$retarget" rig-map fit --correspondences "$out/correspondences" --prior "$out/avatar/$avatar/proposed.yaml" \
  --out "$out/zero_annotation.yaml"

# The held-out people (the 47 references and 20 blends nobody annotated) through every method,
# and the check against the rig's ground truth, per set.
"$retarget" faces "$out/datasets/human" --blends 20 --blend-seed 7 --out "$out/test_faces" --force
"$build_dir/infer/retarget-infer" --bundle "$out/bundle" "$out/test_faces" --out "$out/retargeted"
"$build_dir/infer/retarget-infer" --bundle "$out/bundle-stage1" "$out/test_faces" --out "$out/retargeted-stage1"
for map in rig_head zero_annotation; do
  "$retarget" rig-map apply "$out/$map.yaml" --faces "$out/test_faces" --correspondences "$out/correspondences" \
    --out "$out/$map"
done
"$retarget" eval retarget --faces "$out/test_faces" --correspondences "$out/correspondences$last" \
  --method "stage1=$out/retargeted-stage1" --method "full=$out/retargeted" \
  --method "zero_annotation=$out/zero_annotation" --method "rig_head=$out/rig_head" --out "$out/evaluation"
# Where the error comes from, rung by rung, each beside the neutral answer.
"$retarget" eval ladder --correspondences "$out/correspondences$last" --translation "$out/runs/translation" \
  --out "$out/evaluation/ladder"
echo "demo: everything is in $out (pictures in $out/pictures, dataset previews in $out/datasets/*/preview.png,
  the end-to-end result in $out/evaluation/contact_sheet.png and metrics.json)"
