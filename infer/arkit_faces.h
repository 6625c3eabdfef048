// ARKit takes as human face meshes: each frame's weights (infer/arkit_take.h) applied to one
// person of a linear face model (geometry/face_model.h), and the check that the face model is
// one a bundle's human side can take: its vertex count, topology and units.
//
// The meshes are in the face model's vertex order, units and frame (the ICT model and the
// synthetic human: cm). A bundle's human rest is the rest of the human dataset it was trained
// on; a dataset made from a face model (`retarget dataset human --face-model`) has the model's
// neutral as its rest, so the model's faces have the bundle's human topology vertex for vertex.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "geometry/face_model.h"
#include "geometry/mesh.h"
#include "infer/arkit_take.h"

namespace retarget {

// Identity coefficients as `--identity` takes them: "0.5,-1.2,0" (comma-separated finite numbers,
// blanks allowed; a person is neutral + sum_i c_i identity_i, one standard deviation per unit).
// Throws retarget::Error(option, ...) naming the entry (from 1) that is empty or not a finite number.
Eigen::VectorXd parse_identity(const std::string& text, const std::string& option = "--identity");

class ArkitFaces {
 public:
  // model: the face model the take's names were matched against (the take's `expressions` must be
  // the model's expression names, in its order); identity: coefficients, at most one per identity
  // mode (missing trailing ones are 0; none: the model's mean face, its neutral). Throws
  // retarget::Error naming the model for too many coefficients or one that is not finite.
  explicit ArkitFaces(FaceModel model, const Eigen::VectorXd& identity = Eigen::VectorXd());

  const FaceModel& model() const { return model_; }
  const Positions& person() const { return person_; }  // #V x 3: the face every frame starts from
  std::vector<std::string> expression_names() const;   // the model's, in its order

  // Frame `frame` (from 0) of `take`: #V x 3 positions, exactly
  // model.expression(person(), {expression name: weight}) for the frame's weights. Throws
  // retarget::Error when the take was matched against other expression names.
  Positions frame(const ArkitTake& take, int frame) const;
  // The same positions with the model neutral's faces (Mesh::source names the take and frame).
  Mesh mesh(const ArkitTake& take, int frame) const;

 private:
  FaceModel model_;
  Positions person_;
};

// How the face model's neutral sits against a bundle's human rest.
struct FaceModelRestFit {
  double largest_difference = 0;  // max over vertices of |neutral - rest|, in the model's units
  double rest_size = 0;           // the rest's bounding-box diagonal, the same units
  bool same = true;               // largest_difference <= 1e-4 rest_size
};

// Checks that the face model's faces can go through a bundle whose human rest is `human_rest`
// (human_units: the bundle's human units, "" if unknown). Throws retarget::Error(model.source, ...)
// saying which differs and what to do, for another vertex count, another topology (the
// fingerprint, geometry/topology_fingerprint.h: same vertex count, other faces or vertex order)
// or other units (both known). A neutral that is not the rest (a face-folder dataset's mean
// face, or another model of the same topology) only warns (log::warn): the faces are the
// model's, the bundle measures them against its own rest.
FaceModelRestFit check_face_model_for_bundle(const FaceModel& model, const Mesh& human_rest,
                                             const std::string& human_units);

// The faces of the face model at `face_model` (face_model.yaml or its folder), for the person of
// `identity` (coefficients; empty: the mean face), checked against a bundle's human side
// (check_face_model_for_bundle): what retarget-infer --arkit and --stream drive.
ArkitFaces load_arkit_faces(const std::string& face_model, const std::vector<double>& identity, const Mesh& human_rest,
                            const std::string& human_units);

}  // namespace retarget
