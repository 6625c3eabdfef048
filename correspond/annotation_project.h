// An annotation project: the tournaments over one correspondence set's groups (paper, section
// 5.2), answered by people (`retarget annotate terminal`, the web tool) or by a simulated
// annotator that knows the ground truth (`retarget annotate simulate`), yielding the triplets
// the translation network's L_T is trained with.
//
// One folder per project:
//   project.yaml     format, format_version, software_version, created, the correspondence
//                    folder (absolute), the seed; written last
//   annotations.db   the annotation store (annotate/annotation_store.h): one group per
//                    expression, label = the expression's name, candidates = its group's avatar
//                    sample ids (nearest first), distances = their raw-DR distances to the DT
//                    result (the tie-break), seed = group_seed(seed, k); created in the
//                    order queue_order(seed, groups), which is the order the store hands
//                    their comparisons out
//   renders/         pictures for people (`annotate terminal`), made on demand
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "annotate/annotation_store.h"
#include "annotate/simulated_annotator.h"
#include "correspond/correspondence.h"
#include "data/dataset.h"
#include "geometry/controller_correspondence.h"
#include "geometry/mesh.h"

namespace retarget {

constexpr const char* kAnnotationProjectFormat = "retarget-annotation-project";
constexpr int kAnnotationProjectFormatVersion = 1;

struct AnnotationProjectOptions {
  // The tournaments' pairings (group k uses group_seed(seed, k)) and the order the queue hands
  // the groups out (queue_order): give each round its own, so that an expression is not answered
  // by the same person in every round.
  uint64_t seed = 1;
  bool force = false;  // replace an existing project (its answers are lost)
};

struct AnnotationProject {
  std::string folder;
  std::string created;          // UTC, ISO 8601
  std::string correspondences;  // the correspondence folder, absolute
  uint64_t seed = 1;

  std::string database() const;  // folder/annotations.db
  std::string renders() const;   // folder/renders
};

// The pairing seed of group k (0-based, in correspondence order): a mix of both, so that the
// groups' brackets are unrelated to each other.
uint64_t group_seed(uint64_t seed, int64_t k);

// The order the project's groups are created in, and so handed out (the store's queue is first
// come, first served): 0 .. groups - 1 shuffled by `seed`. Annotators taking turns at a queue in
// the same order every round would each answer the same expressions in every round, and an
// expression's correspondence would be one person's reading; shuffled, each round's groups reach
// different people.
std::vector<int64_t> queue_order(uint64_t seed, int64_t groups);

// Creates the project folder from a correspondence folder (load_correspondences), one group per
// expression. Throws retarget::Error naming the folder when it already holds a project (or any
// files) unless options.force, and for a correspondence folder that does not load.
AnnotationProject init_annotation_project(const std::string& correspondences, const std::string& folder,
                                          const AnnotationProjectOptions& options = {});

// Reads project.yaml. Throws retarget::Error naming the file for a folder that is not a
// project, another format or version, a missing key or a missing annotations.db.
AnnotationProject load_annotation_project(const std::string& folder);

// Pictures for people annotating: the human reference expression of a group and the avatar
// candidates, rendered on first use into project/renders/ (PNG, front view) and reused after.
// Candidates are rebuilt from their DR features on the avatar rest mesh and share one frame
// (the rest mesh's box, enlarged by 15%), so that sizes compare across pictures.
class AnnotationRenders {
 public:
  // Loads the correspondences and the avatar dataset. size: pixels per side.
  explicit AnnotationRenders(const AnnotationProject& project, int size = 384);
  ~AnnotationRenders();
  AnnotationRenders(AnnotationRenders&&) noexcept;
  AnnotationRenders& operator=(AnnotationRenders&&) noexcept;

  std::string anchor(const std::string& label);  // renders/human_<label>.png
  std::string candidate(int64_t sample);         // renders/avatar_<sample>.png

  // Turntable strips for the web tool (render_turntable: `frames` pictures side by side, yaw
  // -max_yaw_deg..+max_yaw_deg, same frames as above) as PNG bytes, cached in
  // renders/turntable-<frames>x<size>-<yaw>deg/.
  std::string anchor_turntable(const std::string& label, int frames, double max_yaw_deg);
  std::string candidate_turntable(int64_t sample, int frames, double max_yaw_deg);

 private:
  Mesh reference(const std::string& label) const;       // correspondences/reference/<label>.obj
  Positions candidate_positions(int64_t sample) const;  // rebuilt from its DR features
  std::filesystem::path turntable_folder(int frames, double max_yaw_deg) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Ground truth for the simulated annotator, from a human dataset built from a face model with
// expression recipes (Dataset::recipes) and the avatar rig's controller table (which human
// blendshapes each controller means). Per group, each candidate's score is the L2 distance
// between the avatar sample's rig weights (Dataset::weights, controllers in Dataset::controllers
// order) and the human expression's recipe weights mapped to controller weights
// (controller_weights_from_human); lower is better.
struct GroundTruth {
  CandidateScores scores;  // label -> sample id -> score
  // Per label, the mapped controller weights (Dataset::controllers order).
  std::map<std::string, std::vector<double>> controller_weights;
};

// The human dataset's expression recipes, for a simulated annotator: throws retarget::Error when
// it has none (a face-folder dataset: annotate by hand instead), they are missing, or the avatar
// dataset has no rig weights.
std::vector<ExpressionRecipe> simulation_recipes(const Dataset& human, const Dataset& avatar);

// table_source names the table in messages. Throws retarget::Error when the human dataset has
// no recipes (a face-folder dataset: annotate by hand instead), a recipe is missing for a group,
// or the table does not fit the avatar's controllers and the face model's blendshapes.
GroundTruth ground_truth_scores(const Correspondences& correspondences, const Dataset& human, const Dataset& avatar,
                                const ControllerCorrespondence& table, const std::string& table_source);

// The human blendshape names of the face model a dataset was built from (its face_model.yaml's
// `expressions` list, or the file itself), read without loading the meshes; empty if the model
// cannot be read.
std::vector<std::string> blendshape_names(const std::string& face_model);

// The triplets of a project folder or of an annotations .db file (AnnotationStore::triplets).
// Throws retarget::Error naming the path when it is neither, or the store does not open.
std::vector<Triplet> load_project_triplets(const std::string& project_or_db, bool include_derived);

}  // namespace retarget
