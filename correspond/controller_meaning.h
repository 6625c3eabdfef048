// Controller meaning, proposed: for any avatar rig, the table saying which human blendshapes each
// controller stands for (geometry/controller_correspondence.h, `correspondence.yaml`), with a
// confidence per controller and the evidence behind it, for a person to confirm (one picture per
// controller: the avatar at the controller's weight 1 beside the human face at the proposed
// shapes). The table feeds the simulated annotator, the evaluation and the rig-weight output.
//
// How a row is proposed:
//  (a) by name: a controller named like one of the face model's expressions, ignoring case and
//      separators and reading a Left/Right suffix as _L/_R (eyeBlinkLeft = eyeBlink_L =
//      eye_blink_l), gets {that expression: 1} with confidence 1;
//  (b) by geometry, for every other controller: each human blendshape h (its offset at weight 1
//      on the model's neutral, the mean identity) is carried onto the avatar's neutral by
//      deformation transfer (landmark pairs: the landmark names the face model and the rig
//      share), T_h = transfer(neutral + offset_h) - transfer(neutral). Then, with the bounded
//      least-squares rig fit (geometry/rig_weight_fit.h), over the vertices the rig moves where a
//      human face can move the avatar at all (some T_h moves them by more than `reach_floor` of
//      the largest; a controller's share of motion there is its `coverage`: a rabbit's smile that
//      also flicks its ears is judged by its mouth):
//       - what each controller is made of: its offset fitted by every T_h at weights in
//         [0, max_human_weight]; h's share of it is a_h <T_h, offset_c> / |offset_c|^2 (the shares
//         sum to the explained part, `explained_by_all`). The fit also matches landmark features,
//         measured on each face itself rather than through the transfer: per eye, the upper and
//         lower lid's motion upwards over the eye's opening; per brow point, its motion upwards
//         over the eye's width; the lip centres' motion upwards and each mouth corner's upwards
//         and outwards, over the mouth's width (only points both faces name; a lid point may be
//         the mean of the 68-point sets' inner and outer lid points). They count
//         `landmark_weight` times as much as the vertices (one scale per rig, so that over its
//         controllers the features' squared norm equals the offsets'), because a transfer onto a cartoon eye or mouth
//         can move the wrong skin, while "the upper lid comes down to the lower one" holds on
//         both faces;
//       - symmetry: the controllers whose motions are most alike, one mirrored, are paired as
//         mirror images, the most alike first (a controller may be its own, a symmetric one), and
//         each pair's shares are averaged, mirrored. The mirror is the avatar's own, from its
//         landmarks (the plane that swaps each name_left with its name_right; each vertex's image
//         the vertex nearest its reflection); a rig without such a pair compares the shares with
//         the human sides swapped (_L <-> _R) instead;
//       - main shapes: the largest share first, each human shape the main meaning of one
//         controller at most (name matches claim theirs first), a mirror pair taking a shape and
//         its mirror image together; near-alike human shapes (blink and squint) thereby go to the
//         controllers they suit best;
//       - the row: the main shape and the unclaimed shapes whose share is at least `min_share`
//         and `relative_keep` times the main one's (at most `max_shapes`), refitted alone to the
//         controller's offset. Confidence: the share of the offset (squared norm over those
//         vertices) that refit explains. Weights: see `Weights` (by default the main shape 1).
//      A row with no shape, a coverage below `min_coverage` or a confidence below
//      `min_confidence` (a mirror pair: their mean, so both sides are decided alike) becomes {}
//      (no human counterpart: ear wiggles, antennae). The forward fit, every T_h fitted by the rig's
//      controllers (F[c][h]: the weight controller c takes for human shape h at weight 1), is
//      kept as evidence and gives the `fitted` weights.
// Left and right come from the geometry, not from the names: the landmarks tell the two sides
// apart, so a controller named "Left" that moves the face's right side gets the human's _R
// shapes, and its evidence says that the name and the geometry disagree.
#pragma once

#include <string>
#include <vector>

#include "geometry/controller_correspondence.h"
#include "geometry/deformation_transfer.h"
#include "geometry/face_model.h"
#include "geometry/rig.h"
#include "render/render.h"

namespace retarget {

struct ControllerMeaningOptions {
  // Map controllers named like a face model expression directly ((a) above); off: geometry for all.
  bool match_names = true;
  // Geometry ((b) above):
  double ridge = 1e-3;  // >= 0: the forward rig fit's ridge (RigWeightFitOptions::ridge, scale-free)
  // A human shape enters a row when its share of the controller's motion (in the fit of every
  // human shape's transfer to the controller's offset) is at least `min_share` and at least
  // `relative_keep` times the largest share; at most `max_shapes` of them, the largest first.
  double min_share = 0.03;      // in (0, 1)
  double relative_keep = 0.4;   // in (0, 1]
  int max_shapes = 4;           // >= 1
  double min_confidence = 0.1;  // in [0, 1): rows explained less than this become {}
  // The fits and confidences are measured where a human face can move the avatar: the vertices
  // the rig moves that some transferred human shape moves by more than this share of the largest
  // such motion. A controller whose motion lies mostly elsewhere (ears, antennae) has a low
  // coverage; below `min_coverage` its row is {}.
  double reach_floor = 0.1;     // in [0, 1)
  double min_coverage = 0.05;   // in [0, 1)
  double max_human_weight = 3;  // > 0: the human weights the fits may use, [0, this]
  // How much what each face does at the landmarks both name counts in the shares' fit, against
  // the vertices (1: as much; 0: vertices only). See "landmark features" above.
  double landmark_weight = 1;  // >= 0
  // Two controllers may be paired as mirror images when the cosine between one's motion,
  // mirrored, and the other's (or, without the avatar's mirror, between their shares with the
  // sides swapped) is at least this.
  double mirror_likeness = 0.7;  // in (0, 1]
  // The table's weights in a row: `unit`: the human weights of the kept shapes' fit to the
  // controller's offset, divided by the main shape's (controller at 1 = main shape at 1: a
  // transfer's magnitude on a stylised face is not trusted; measured on the synthetic avatars,
  // the rig weights the table gives for each human shape at 1 are nearer the truth this way than
  // with either other choice); `human`: those weights as fitted;
  // `fitted`: t_h = F[c][h] / sum F[c][h']^2 (human shape h at 1 -> the controller weight the rig
  // fit of its transfer gives).
  enum class Weights { unit, human, fitted };
  Weights weights = Weights::unit;
  DeformationTransferOptions transfer;  // human neutral -> avatar neutral
  // Throws retarget::Error naming "controller_meaning.<field>" (or the transfer's option).
  void validate() const;
};

// One human shape's evidence for one controller.
struct MeaningCandidate {
  std::string shape;        // human blendshape name
  double share = 0;         // its share of the controller's motion in the fit of every human shape
  double fitted = 0;        // F[c][h]: the controller's weight in the rig fit of shape h's transfer
  double human_weight = 0;  // its weight in the kept shapes' fit to the controller (0: not kept)
  double table_weight = 0;  // its table entry (0 when the shape is not kept)
  bool kept = false;        // in the proposed row
};

struct ControllerMeaningRow {
  std::string controller;
  std::string method;  // "name", "geometry" or "none" (no human counterpart found, or a placeholder)
  // 0..1: the share of the controller's offset the row's shapes explain (1 for "name" rows).
  double confidence = 0;
  // 0..1: the share of the controller's motion (squared, over the vertices the rig moves) that
  // lies where a human face can move the avatar (1 for "name" rows); the confidences are
  // measured there.
  double coverage = 0;
  // 0..1: the share a non-negative combination of every human shape's transfer explains (how
  // human-like the controller is at all; 1 for "name" rows).
  double explained_by_all = 0;
  std::string mirror;      // the controller found to be its mirror image ("" for none; itself if symmetric)
  std::string main_shape;  // the row's main shape (table weight 1 by default); "" for {}
  std::vector<MeaningCandidate> candidates;  // the largest shares first (6), then any other kept shape
  // The side of the face the controller moves, from the geometry: "left" or "right" when the
  // human shapes of that side (_L, ...) explain at least twice as much of it as the other side's
  // (evidence as for the main shapes); "" for both or neither.
  std::string side;
  // Set when the controller's name says one side (Left/_L ...) and `side` the other:
  // "named left, but moves the face's right side (browDown_R): geometry kept"; the row follows
  // the geometry.
  std::string note;
};

struct ControllerMeaning {
  ControllerCorrespondence table;          // a row for every controller ({} = no counterpart)
  std::vector<ControllerMeaningRow> rows;  // in the rig's controller order
  std::vector<std::string> landmarks;      // the landmark names paired (empty: names only)
  int moving_vertices = 0;                 // the rig vertices the controllers move
  int human_reach_vertices = 0;            // those a human face can move: the confidences are measured there
  bool transferred = false;                // whether deformation transfer ran
  DeformationTransfer::Report transfer;    // its correspondence phase (when transferred)
  double seconds = 0;                      // wall time

  // The row of `controller`; throws retarget::Error naming the controller if absent.
  const ControllerMeaningRow& row(const std::string& controller) const;
};

// Proposes the table for `rig` against `face` (both in their own units and frames; the transfer
// aligns them by the shared landmarks). Deterministic: the same inputs give the same table.
// Throws retarget::Error (naming the rig or face model file) for: a rig without controllers or
// whose controllers all move nothing, a face model without expressions, and, when some controller
// needs geometry, fewer than 3 landmark names shared by the rig and the face model (listing both
// sets); and what deformation transfer throws. A controller that moves nothing (a placeholder
// morph) is no error: its row is {} with method "none" and a note saying so.
ControllerMeaning propose_controller_meaning(const Rig& rig, const FaceModel& face,
                                             const ControllerMeaningOptions& options = {});

// The header comment block of a correspondence.yaml written from `meaning`: how it was made and,
// per controller, its method, confidence, main evidence and note (one line each).
std::string controller_meaning_header(const Rig& rig, const FaceModel& face, const ControllerMeaning& meaning);

// Writes `meaning.table` to `path` (write_controller_correspondence, atomically) with
// controller_meaning_header as its comment block and the confidence after each row:
//   smileLeft: {mouthSmile_L: 1.12}  # confidence 0.87 (geometry)
// The file reads back with load_controller_correspondence.
void write_controller_meaning(const std::string& path, const Rig& rig, const FaceModel& face,
                              const ControllerMeaning& meaning);

struct MeaningPictureOptions {
  int size = 256;         // pixels per picture (square), 64..2048
  void validate() const;  // throws retarget::Error naming "meaning_picture.size"
};

// The picture a person confirms a row by: the avatar's neutral and the avatar at the controller's
// weight 1 (clamped to its range), beside the human neutral and the human face at the row's
// weights, captioned, with a title line giving the row and its confidence. Size:
// 4 * size x (title band + size + caption band). Throws retarget::Error for an unknown controller.
Image controller_meaning_picture(const Rig& rig, const FaceModel& face, const ControllerMeaning& meaning,
                                 const std::string& controller, const MeaningPictureOptions& options = {});

// Human-readable side of a name: "left" for a Left/_L/_l/L suffix or a Left/left word, "right"
// likewise, "" for neither (eyeBrowLeftDown -> left, mouthSmile_R -> right, jawOpen -> "").
std::string name_side(const std::string& name);

// The key names are compared by: lower case, separators (_ - . space) dropped, a trailing
// "left"/"right" shortened to "l"/"r" (eyeBlinkLeft, eyeBlink_L and eye_blink_l -> "eyeblinkl").
std::string meaning_name_key(const std::string& name);

}  // namespace retarget
