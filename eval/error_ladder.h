// The error ladder: where the end-to-end error of a retargeting comes from. The method's chain
// (human mesh -> human encoder -> F -> avatar decoder -> mesh) is cut at every joint and each
// part is scored on its own, against the same ground truth as the trivial answer, so that each
// rung reads both in mm and as a fraction of doing nothing:
//
//   1 avatar VAE, held-out rig samples     the avatar dataset's test split, features -> normalise
//                                          -> encoder mean -> decoder -> mesh, vs the rig at the
//                                          stored weights
//   2 avatar VAE, ground-truth expressions each reference expression's ground-truth rig mesh ->
//                                          DR -> encoder mean -> decoder -> mesh: the ground-truth
//                                          avatar code through the decoder, the best any F can do
//   3 human VAE, unseen people             the human test split through the human VAE vs the
//                                          identity-averaged target (trivial: the mean face)
//   4 deformation transfer (DT) result     the correspondences' dt/<expression>.obj vs the truth
//   5 DT projected onto the rig            the rig at the weights that best reproduce each DT
//                                          result (geometry/rig_weight_fit.h): what y0 starts
//                                          from with `correspond --initial rig`
//   6 y0 through the decoder               decode(y0_k) vs the truth
//   7 F, training people                   decode(F(human encoder mean)) of every training-split
//                                          human sample whose expression has a correspondence
//   8 F, unseen people                     the same on the human test split
//   9 F, unseen blends                     with `faces` (data/test_faces.h): the same chain on the
//                                          faces of the set "blends", random blends nobody
//                                          annotated, each against the rig at its blend's weights
//                                          through the table
//  10 avatar VAE, ground-truth blends      with `faces`: each blend's true rig mesh -> DR ->
//                                          encoder mean -> decoder -> mesh (as rung 2): the
//                                          floor of any method through the avatar decoder there
//
// Meshes come from features as the runtime makes them: the avatar's still vertices held at rest
// (data/still_vertices.h), each VAE's outputs denormalised in its decoder's ranges.
//
// Ground truth of a human expression: its recipe's blendshape weights (the human dataset's
// recipes file) mapped through the controller table (geometry/controller_correspondence.h,
// rig_weights_from_human) and evaluated on the rig. The trivial answer is the avatar's neutral
// mesh on the avatar rungs and the human rest mesh (the mean face) on rung 3.
//
// Errors (geometry/expression_error.h): rigid alignment of each output onto its truth, then the
// mean per-vertex distance over every vertex, over the vertices the rig moves, and per face
// region (geometry/rig_footprint.h: the rig's controllers classified by their table rows'
// human shapes; on the human rung, the identity-averaged targets classified by their recipes).
// Units: mm with the mesh scaled so that its eye centres are 10 cm apart (millimetres_per_unit);
// a dataset without eye landmarks is scored in its mesh units (the rung says so).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "geometry/expression_error.h"

namespace retarget {

struct ErrorLadderOptions {
  std::string correspondences;      // correspondence folder (correspond/correspondence.h); required
  std::string translation;          // translation run folder (translate/translation_run.h); required
  std::string checkpoint = "last";  // F's checkpoint: "last" or "stage<N>"
  // Controller table; empty: correspondence.yaml beside the avatar rig (its folder, or the
  // folder of its .gltf/.glb).
  std::string table;
  std::string out;          // folder of ladder.json; empty: <translation>/ladder
  std::string faces;        // a folder written by `retarget faces --blends N`: adds rungs 9 and 10; empty: none
  int64_t batch = 64;       // samples per network pass and per batch of mesh reconstructions, >= 1
  bool anchors = true;      // hold the avatar's still vertices at rest, as the bundle does
  bool part_motion = true;  // move the avatar's rigid parts with its rig, as the bundle does (geometry/part_motion.h)
  void validate() const;    // throws retarget::Error naming the option (--correspondences, ...)
};

// One rung's figures. All means are means over the rung's items of the per-item means
// (ExpressionErrorSum::averaged()), in `unit`.
struct LadderRung {
  int number = 0;           // 1 .. 9, in the order above
  std::string key;          // JSON name: avatar_vae_test, avatar_vae_truth, human_vae_test, dt, dt_rig, y0,
                            //   f_train, f_test
  std::string name;         // "avatar VAE, held-out rig samples", ...
  std::string side;         // "avatar" or "human": whose mesh is scored
  std::string truth;        // what the outputs are compared with
  std::string trivial;      // the trivial answer scored beside them
  std::string unit = "mm";  // "mm", or "units" for a dataset without eye landmarks
  int64_t samples = 0;
  ExpressionErrorSum error;          // the rung's outputs (averaged)
  ExpressionErrorSum trivial_error;  // the trivial answer on the same items (averaged)
  double fraction = 0;               // error.mean / trivial_error.mean (NaN when the latter is 0)
  double moving_fraction = 0;        // the same over the moving vertices
  // Per expression (every rung but 1, whose items are random rig samples): the rung's and the
  // trivial answer's averaged errors over that expression's items.
  std::map<std::string, ExpressionErrorSum> expression_error, expression_trivial;
  double seconds = 0;
};

struct ErrorLadder {
  std::vector<LadderRung> rungs;                                // 1 .. 8 (9 with faces)
  std::string translation, checkpoint, correspondences, table;  // as read (absolute paths)
  std::string human_vae, human_checkpoint, avatar_vae, avatar_checkpoint;
  std::string human_dataset, avatar_dataset, rig;
  int translation_epoch = 0;
  double avatar_mm_per_unit = 1, human_mm_per_unit = 1;
  int avatar_vertices = 0, avatar_moving = 0;                // the rig's footprint: vertices, moving vertices
  int human_vertices = 0, human_moving = 0;                  // the targets' footprint
  std::map<std::string, int> avatar_regions, human_regions;  // region -> vertex count
  std::string json_path;                                     // out/ladder.json
  double seconds = 0;
};

// Scores every rung and writes out/ladder.json atomically:
//   {format: "retarget-error-ladder", format_version: 1, translation, checkpoint, epoch,
//    correspondences, human_vae: {run, checkpoint}, avatar_vae: {run, checkpoint},
//    human_dataset, avatar_dataset, rig, table, avatar_mm_per_unit, human_mm_per_unit,
//    footprint: {avatar: {vertices, moving, regions: {mouth: n, ...}}, human: {...}},
//    rungs: [{rung, key, name, side, truth, trivial, unit, samples,
//             error: {mean, moving_mean, mean_of_max, max, regions: {mouth: x, ...}},
//             trivial_error: {same fields}, fraction, moving_fraction,
//             expressions: {name: {samples, mean, moving_mean, trivial_mean, trivial_moving_mean}},
//             seconds}, ...],
//    seconds}
// Figures are in each rung's `unit`; a figure that does not exist (a rung without samples, a
// fraction of a zero trivial error) is null. Throws retarget::Error for bad options, runs or
// folders that do not load, a translation run trained against another avatar VAE than the
// correspondences', a human dataset without expression recipes (no ground truth), an expression
// without a recipe, or a rig or table that does not fit the avatar dataset.
ErrorLadder error_ladder(const ErrorLadderOptions& options);

// The ladder as a text table, one row per rung: rung | n | mean mm | moving mm | neutral mm |
// neutral moving mm | x neutral (moving).
std::string ladder_table(const ErrorLadder& ladder);

}  // namespace retarget
