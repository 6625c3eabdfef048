// Geometric correspondences between a human expression set and an avatar (paper, section 5.1):
// for each human reference expression k, deformation transfer of the identity-averaged
// expression mesh onto the avatar neutral (landmark pairs) gives the initial avatar expression;
// its avatar-encoder mean is y0_k, and the P avatar dataset samples nearest to it in raw DR
// feature space (exact L2 search) form the group Y_k that the tournaments and L_G use.
//
// Beyond the paper (initial: rig, the default): the DT result is first projected onto the rig,
// i.e. replaced by the rig evaluated at the controller weights that best reproduce it
// (geometry/rig_weight_fit.h). A DT result lies off the avatar's expression manifold (it moves
// every vertex a little, and what it moves it moves the human way); the samples nearest to such
// a point in DR space are the ones that move least, so with the raw result (initial: dt, the
// paper) y0, every group and F all pointed at the neutral face. The projection is an
// expression the rig can make, and its nearest samples share its controllers.
//
// Also beyond the paper, for avatars whose expressions mean what no geometric transfer can carry
// (a rabbit raises its ears where a person raises their brows): the tournaments can only correct
// DT's semantics if a group holds a candidate near the right answer, and the samples nearest to a
// wrong transfer hold none. Two options let the annotators search instead:
// - spread: the last `spread` members of each group are chosen for variety, not nearness
//   (farthest-point sampling over the directions of the samples' rig weights, starting from the
//   near members, among the samples that move some controller past half its range), so that
//   a group also offers expressions the transfer did not suggest;
// - around: a later round starts each expression from its group's champion in an annotation
//   project over an earlier correspondence set (initial: champions): y0 is the champion's code and
//   the group its nearest samples, so each round of tournaments narrows in on what the
//   annotators chose. The translation network trains on the last round.
// - proposals: the last `proposals.count` members of each group are new rig expressions around
//   the start (correspond/rig_proposals.h), not dataset samples: needs a start on the rig (initial
//   rig or champions) and the avatar dataset's rig. They are stored in the folder and get the
//   sample ids N + k * count + j (N: the avatar dataset's sample count, k: the expression, j: the
//   proposal), so annotation projects, the simulated annotator and the translation network treat
//   them like dataset samples; Correspondences::candidate_features/candidate_weights resolve any
//   id.
//
// One folder per correspondence set:
//   correspondences.yaml  manifest: format, format_version, software_version, created, group_size,
//                         the human dataset (folder, name, fingerprint), the avatar dataset
//                         (folder, name, fingerprint), the avatar VAE run (folder, checkpoint),
//                         the landmark pairs used (name: [human vertex, avatar vertex]), the
//                         expressions (in order), the deformation transfer report; written last
//   correspondences.pt    tensors (torch.load gives a dict):
//                           y0          [K, La] float32  avatar encoder means of the DT results
//                           dt_features [K, Va, 9] float32  raw DR features of the DT results
//                           groups      [K, P] int64  avatar dataset sample indices, nearest first
//                           distances   [K, P] float32  raw-DR L2 distance of each to the DT result
//                           group_codes [K, P, La] float32  avatar encoder means of the group samples
//                           initial_weights [K, C] float64  initial: rig or champions: the rig
//                                                     weights of each projected DT result (of
//                                                     each champion sample)
//                           initial_features [K, Va, 9] float32  initial: rig or champions: their
//                                                     raw DR features (what y0 and the groups
//                                                     come from)
//                           proposal_weights [K, M, C] float64  proposals only: rig weights of
//                                                     the M proposals of each group
//                           proposal_features [K, M, Va, 9] float32  proposals only: their raw DR
//                                                     features
//   reference/<expression>.obj  the human reference meshes (the identity-averaged expressions)
//   dt/<expression>.obj         the DT results (avatar topology, avatar units)
//   dt_rig/<expression>.obj     initial: rig only: the DT results projected onto the rig
// Groups list their nearest members first (nearest first), then the spread members in the order
// they were picked, then the proposals (the start first); `distances` holds every member's raw-DR
// distance to its initial expression.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "correspond/rig_proposals.h"
#include "data/dataset.h"
#include "geometry/deformation_transfer.h"
#include "geometry/rig.h"

namespace retarget {

constexpr const char* kCorrespondenceFormat = "retarget-correspondences";
constexpr int kCorrespondenceFormatVersion = 1;

// Where a round of comparisons starts each expression when earlier rounds decide it: worked out
// outside this library, by the orchestration of rounds (pipeline/round_starts.h: an earlier
// round's champions, or the belief search over every earlier round's answers), and handed in as
// a rule build_correspondences calls once its inputs are loaded.
struct RoundStartInputs {
  const std::vector<std::string>& names;  // the expressions, in tensor order (K)
  const Dataset& human;
  const Dataset& avatar;
  const Rig& rig;  // the avatar dataset's rig (empty when the options need none)
};

struct RoundStarts {
  torch::Tensor weights;         // [K, C] float64: each expression's start on the rig
  torch::Tensor features;        // [K, Va, 9] float32, or undefined: the rig's mesh at `weights`
  torch::Tensor pairs;           // [K, 2, C] float64: the pair each group asks (belief search), or undefined
  int evidence_comparisons = 0;  // the decided comparisons the starts rest on
};

using RoundStartRule = std::function<RoundStarts(const RoundStartInputs&)>;

struct CorrespondenceOptions {
  int group_size = 16;                   // P, >= 2 and <= the avatar dataset's sample count
  std::vector<std::string> expressions;  // human reference expressions by name; empty: all of them
  // Landmark pairs: empty = every landmark name the two datasets' rest meshes share (at least 3);
  // else a file read by read_landmark_pairs (human = source, avatar = target).
  std::string landmarks_file;
  std::string checkpoint = "best";  // of the avatar VAE run: "best" or "last"
  DeformationTransferOptions transfer;
  // What y0 and the groups start from: "rig" (the DT result projected onto the rig; needs the
  // avatar dataset's rig to be readable), "dt" (the raw DT result, as the paper), "champions"
  // (the champions of the project `around`) or "table" (the rig at the weights the controller
  // table `start_table` gives each recipe, e.g. `avatar meaning`'s: the annotators then correct
  // a proposed reading instead of searching from the transfer; `start_table` may also be a
  // controller map, geometry/controller_map.h: the rig head fitted to earlier rounds).
  std::string initial = "rig";
  std::string start_table;      // initial "table": the controller table; else empty
  double projection_ridge = 0;  // >= 0: the rig fit's ridge (RigWeightFitOptions::ridge)
  // Group members chosen for variety (above): 0 <= spread < group_size; needs rig weights in the
  // avatar dataset.
  int spread = 0;
  // Members generated from the rig around the start (above): spread + proposals.count <=
  // group_size, and at least one dataset member when spread > 0.
  RigProposalOptions proposals;
  // An annotation project folder whose finished tournaments give each expression's start
  // (initial must then be "champions"; the project's correspondences must use the same avatar
  // dataset). Empty: start from the transfer. Recorded in the manifest; `round_starts` reads it.
  std::string around;
  // Rounds chosen by the belief search (correspond/belief_rounds.h), beyond the paper's fixed
  // tournaments: each group is the pair of rig expressions with the most expected information
  // about its expression under the map belief that starts at `start_table` and has observed
  // every decided comparison of `evidence` (the earlier rounds' annotation projects, in order);
  // the start is what the belief bets on. Needs initial "table", group_size 2, no spread and no
  // proposals (the pair is stored as the group's 2 proposals). Recorded in the manifest;
  // `round_starts` computes them.
  bool informative = false;
  std::vector<std::string> evidence;
  // The starts of a round that earlier rounds decide (initial "champions", or informative):
  // pipeline/round_starts.h's champions_of(around) or belief_search_round(...). Required then.
  RoundStartRule round_starts;
  bool force = false;                   // replace the files of a non-empty output folder
  std::ostream* progress = &std::cerr;  // log lines (nullptr: none)
  void validate() const;                // throws retarget::Error naming "correspond.<field>"
};

struct Correspondences {
  std::string folder;
  std::string created;
  int group_size = 0;  // P
  std::string human_dataset, human_name, human_fingerprint;
  std::string avatar_dataset, avatar_name, avatar_fingerprint;
  std::string avatar_vae_run, avatar_vae_checkpoint;
  std::vector<std::string> expressions;  // K, in tensor order
  std::vector<LandmarkPair> landmarks;   // the deformation transfer's pairs: human -> avatar vertex
  std::string initial = "dt";            // "rig", "dt" or "champions" (folders written before the option: "dt")
  std::string around;                    // initial == "champions": the annotation project, absolute
  std::string start_table;               // initial == "table": the controller table, absolute
  int spread = 0;                        // the last `spread` members of each group were chosen for variety
  torch::Tensor y0;                      // [K, La] float32
  torch::Tensor dt_features;             // [K, Va, 9] float32
  torch::Tensor groups;                  // [K, P] int64
  torch::Tensor distances;               // [K, P] float32
  torch::Tensor group_codes;             // [K, P, La] float32
  torch::Tensor initial_weights;         // [K, C] float64 (initial "rig", "champions" or "table"; else undefined)
  torch::Tensor initial_features;        // [K, Va, 9] float32 (initial "rig", "champions" or "table"; else undefined)
  int64_t avatar_samples = 0;            // N: the avatar dataset's sample count; ids >= N are proposals
  RigProposalOptions proposals;          // proposals.count == 0: none
  bool informative = false;              // the proposals are the belief search's pairs
  std::vector<std::string> evidence;     // informative: the rounds it observed, absolute
  int evidence_comparisons = 0;          // informative: their decided comparisons
  torch::Tensor proposal_weights;        // [K, M, C] float64 (proposals only; else undefined)
  torch::Tensor proposal_features;       // [K, M, Va, 9] float32 (proposals only; else undefined)

  // The features y0 was encoded from: initial_features when defined, else dt_features.
  const torch::Tensor& start_features() const { return initial_features.defined() ? initial_features : dt_features; }

  int64_t expression_count() const { return static_cast<int64_t>(expressions.size()); }
  // A candidate's raw DR features [Va, 9] float32 and rig weights [C] float64, whether a sample of
  // `avatar` (the dataset these correspondences were built on) or a proposal. Throws
  // retarget::Error naming the folder for an id that is neither, or (weights) for a dataset
  // without rig weights.
  torch::Tensor candidate_features(const Dataset& avatar, int64_t id) const;
  torch::Tensor candidate_weights(const Dataset& avatar, int64_t id) const;
  // Every valid candidate id is below this: N + K * M.
  int64_t candidate_count() const { return avatar_samples + expression_count() * proposals.count; }

  // Index of `expression` in `expressions`; throws retarget::Error naming the folder if absent.
  int64_t expression_index(const std::string& expression) const;
};

// Builds the correspondences of the human dataset folder and the avatar dataset folder with the
// avatar VAE run folder (trained on that avatar dataset: its fingerprint must match) into
// `out_folder`. Throws retarget::Error for bad options, unknown expressions, fewer than three
// shared landmarks, mismatched datasets, or a non-empty out_folder without options.force.
Correspondences build_correspondences(const std::string& human_dataset, const std::string& avatar_dataset,
                                      const std::string& avatar_vae_run, const std::string& out_folder,
                                      const CorrespondenceOptions& options = {});

// What build_correspondences did, for the command's summary.
struct CorrespondenceReport {
  int landmark_pairs = 0;
  DeformationTransfer::Report transfer;  // the correspondence phase: fit distances in avatar units
  double seconds = 0;                    // wall time of the whole build, of which:
  double load_seconds = 0;               //   datasets and the VAE read
  double reconstruction_seconds = 0;     //   reference meshes from the targets
  double transfer_seconds = 0;           //   deformation transfer (set-up included) and DR features
  double search_seconds = 0;             //   the nearest-sample search
  double encode_seconds = 0;             //   encoder means of the DT results and the group samples
  double write_seconds = 0;
};

// The same, also filling `report` when it is not null.
Correspondences build_correspondences(const std::string& human_dataset, const std::string& avatar_dataset,
                                      const std::string& avatar_vae_run, const std::string& out_folder,
                                      const CorrespondenceOptions& options, CorrespondenceReport* report);

// Reads and checks a correspondence folder (format, version, tensor shapes against the
// manifest). Throws retarget::Error naming the file and what is wrong.
Correspondences load_correspondences(const std::string& folder);

// Throws retarget::Error naming both fingerprints when the human or avatar dataset differs from
// the one the correspondences were built from (by topology fingerprint and name).
void check_correspondences(const Correspondences& correspondences, const Dataset& human, const Dataset& avatar);

}  // namespace retarget
