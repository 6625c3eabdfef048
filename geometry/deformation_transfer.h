// Deformation transfer (Sumner & Popovic 2004, "Deformation Transfer for Triangle Meshes"):
// copies a source mesh's deformation (rest S0 -> deformed S1..Sk) onto a target rest mesh T0
// of another topology, matching per-triangle deformation gradients.
//
// Two phases, both precomputed once in DeformationTransfer's constructor:
//  1. correspondence: S0 is deformed onto T0's surface (smooth, close to the identity,
//     landmarks met) and triangles of the two meshes are paired by centroid and normal;
//  2. transfer: the target's least-squares system for "each paired target triangle deforms
//     like its source triangle" is factorised, so each expression costs one right-hand
//     side and one solve.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <utility>
#include <vector>

#include "geometry/mesh.h"

namespace retarget {

// One user-given correspondence: a source vertex and the target vertex it lands on.
struct LandmarkPair {
  int source = 0;  // index into the source rest mesh's vertices
  int target = 0;  // index into the target rest mesh's vertices
};

struct DeformationTransferOptions {
  // How the source rest mesh is placed over the target before the correspondence phase,
  // estimated from the landmark positions (least squares, Umeyama). With `similarity`,
  // a source in other units or another pose (cm vs m, Z-up vs Y-up) needs no preparation,
  // and the transferred gradients are turned into the target's frame; `none` trusts that
  // both meshes already share one frame and one scale, as in the paper.
  enum class Prealignment { none, translation_scale, similarity };
  // How the transfer fixes translation, which deformation gradients do not see.
  // follow_source: each connected part of the target moves like the (barycentric)
  // corresponding points of the source surface, so a source that does not move leaves the
  // target where it is; keep_centroid: each part's centroid stays at its rest position.
  enum class TranslationAnchor { follow_source, keep_centroid };

  // --- correspondence phase; distances are measured in mean source edge lengths (after
  // the prealignment), so the weights do not depend on the meshes' units.
  double smoothness_weight = 1.0;  // w_S: adjacent source triangles deform alike
  double identity_weight = 0.001;  // w_I: each source triangle deforms little (> 0)
  // w_C per solve: vertex to closest valid target point. The first solve uses the current
  // shape's closest points only if its weight is > 0; later solves recompute them.
  std::vector<double> closest_point_weights = {0, 1, 10, 100, 1000, 5000};
  double landmark_weight = 0;        // 0: landmarks are hard constraints; > 0: soft, this weight
  double max_normal_angle_deg = 90;  // closest points and triangle pairs: normals within this angle
  double match_distance = 0;         // triangle pairing radius in target units; 0: automatic
                                     // (3 x the larger mean edge length of the two meshes)
  Prealignment prealignment = Prealignment::similarity;

  // --- transfer phase
  TranslationAnchor translation_anchor = TranslationAnchor::follow_source;

  // Throws retarget::Error naming the first invalid option ("deformation_transfer.<name>").
  void validate() const;
};

class DeformationTransfer {
 public:
  // What the constructor did, for logs and tests.
  struct Report {
    struct Step {
      double closest_point_weight = 0;
      int closest_points = 0;    // source vertices with a valid closest point in this solve
      double mean_distance = 0;  // after the solve: fitted source vertices to the target
      double max_distance = 0;   // surface, target units
    };
    std::vector<Step> steps;   // one per closest_point_weights entry
    double mean_distance = 0;  // fitted source vertices to the target surface, target units
    double max_distance = 0;
    double prealignment_scale = 1;  // source units -> target units
    double match_distance = 0;      // pairing radius used, target units
    int triangle_pairs = 0;
    int fallback_target_triangles = 0;    // nothing compatible within match_distance: paired
                                          // with the nearest compatible source triangle
    int identity_target_triangles = 0;    // nothing compatible at all: held to the identity
    int degenerate_source_triangles = 0;  // zero area: no gradient, zero weight
    int degenerate_target_triangles = 0;
    int target_components = 0;          // connected parts, one pinned vertex each
    double correspondence_seconds = 0;  // phase 1 solves, including closest points
    double pairing_seconds = 0;
    double factorisation_seconds = 0;  // transfer-phase assembly and Cholesky
  };

  // source_rest: the source rest mesh S0 (#Vs vertices); target_rest: T0 (#Vt vertices), any
  // topology; landmarks: at least 3 pairs, each source vertex at most once. Units and frames
  // may differ (see Prealignment). Throws retarget::Error on bad input (naming the landmark,
  // the index and the mesh) and on a failed factorisation.
  DeformationTransfer(const Mesh& source_rest, const Mesh& target_rest, std::vector<LandmarkPair> landmarks,
                      DeformationTransferOptions options = {});
  ~DeformationTransfer();
  DeformationTransfer(DeformationTransfer&&) noexcept;
  DeformationTransfer& operator=(DeformationTransfer&&) noexcept;

  // source_deformed: #Vs x 3, the source rest topology, source units and frame.
  // Returns #Vt x 3 target positions in target units and frame. Thread-safe (const).
  Positions transfer(const Positions& source_deformed) const;
  // Many expressions at once, one result each (OpenMP over expressions; results do not
  // depend on the thread count).
  std::vector<Positions> transfer(const std::vector<Positions>& source_deformed) const;

  // S0 deformed onto the target surface (the correspondence phase's result): #Vs x 3,
  // target units and frame.
  const Positions& fitted_source() const;
  // (source triangle, target triangle) pairs the transfer matches, sorted.
  const std::vector<std::pair<int, int>>& triangle_pairs() const;
  const Report& report() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One-off transfer of one expression; builds and discards a DeformationTransfer.
// Shapes as in DeformationTransfer::transfer. Returns #Vt x 3.
Positions deformation_transfer(const Mesh& source_rest, const Positions& source_deformed, const Mesh& target_rest,
                               const std::vector<LandmarkPair>& landmarks,
                               const DeformationTransferOptions& options = {});

}  // namespace retarget
