// Human faces: a linear face model (neutral + identity modes + expression blendshapes), or a
// folder of captured meshes <subject>/<expression>.obj; and the expression recipes that say
// which expressions to build.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "geometry/mesh.h"
#include "geometry/metrics.h"

namespace retarget {

struct Blendshape {
  std::string name;
  Positions offset;  // #V x 3: shape minus neutral
};

// A person is neutral + sum_i c_i identity_i, c_i ~ N(0, 1); an expression of that person adds
// sum_j w_j expression_j (offsets independent of identity).
struct FaceModel {
  std::string name;
  std::string source;  // the YAML path, for messages
  std::string units = "cm";
  Mesh neutral;
  std::vector<Blendshape> identities;    // one standard deviation each
  std::vector<Blendshape> expressions;   // ARKit-style names
  std::map<std::string, int> landmarks;  // named landmark vertices (see Rig::landmarks)
  EyeLandmarks eyes;

  int expression_index(const std::string& name) const;  // -1 if absent
  // neutral + identity: coefficients #identities (missing trailing ones are 0).
  Positions person(const Eigen::VectorXd& identity) const;
  // person + expression weights given by name; throws retarget::Error for an unknown name.
  Positions expression(const Positions& person, const std::map<std::string, double>& weights) const;
};

// face_model.yaml (paths relative to the file):
//   name: ict
//   units: cm
//   neutral: neutral.obj
//   shapes: absolute            # or `offsets`
//   identities: [{name: identity000, file: identities/identity000.obj}, ...]
//   expressions: [{name: jawOpen, file: expressions/jawOpen.obj}, ...]
//   landmarks: {nose_tip: 123, ...}     # optional
//   eyes: {left: [..], right: [..]}     # optional
// Errors as for rigs (missing files, vertex counts naming both files, duplicate names).
FaceModel load_face_model(const std::string& path);
void write_face_model(const std::string& folder, const FaceModel& model);  // face_model.yaml + OBJs

struct ExpressionRecipe {
  std::string name;
  std::map<std::string, double> weights;  // blendshape name -> weight
};
// recipes: [{name: smile, weights: {mouthSmile_L: 1, mouthSmile_R: 1}}, ...]; duplicate
// recipe names are an error naming both entries.
std::vector<ExpressionRecipe> load_expression_recipes(const std::string& path);
// The weights of the recipe named `name`; throws retarget::Error naming `recipes_file` (where
// the recipes came from) when there is none.
std::map<std::string, double> recipe_weights(const std::vector<ExpressionRecipe>& recipes, const std::string& name,
                                             const std::string& recipes_file);
// The same format, atomically (load_expression_recipes reads it back).
void write_expression_recipes(const std::string& path, const std::vector<ExpressionRecipe>& recipes);

}  // namespace retarget
