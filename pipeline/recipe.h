// The recipe of `retarget pipeline`: the whole method as one typed, validated YAML file
// (configs/recipes/demo.yaml, configs/recipes/real.yaml). A recipe may be built on another
// (`base:`, core/config_base.h) and takes `--set key.path=value` overrides. Relative paths are
// read against the file that wrote them (a recipe or its base), or against the working folder
// for a value given with --set.
//
//   human:       the people: a face model (or `synthetic`), the expression recipes, how many people
//   avatar:      the rig (a folder, a glTF file or synthetic/<name>), `avatar init` or not, the
//                controller table the simulated annotators read and the evaluation scores against
//   profile:     a folder of training configs (avatar_vae.yaml, human_vae.yaml, translation.yaml,
//                cyclegan.yaml: the CycleGAN+LFD baseline)
//   training:    --set overrides for each of the four trainings, and `processes`: data-parallel
//                workers for the VAEs and F (`retarget train --nproc`; 1: one process)
//   test_faces:  the unseen people's references and random blends the evaluation scores
//   method:      the budget of comparisons, how rounds search, the method's folder in the run
//   annotators:  simulated (with `retarget annotate simulate`'s settings) or people (the web tool)
//   extras:      pictures of the inputs and the geometry demo
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/config.h"

namespace retarget {

struct RecipeHuman {
  std::string face_model = "synthetic";  // a face_model.yaml, or "synthetic" (retarget synth, into RUN/synth)
  std::string recipes;                   // expression recipes YAML: one group of comparisons per recipe
  int people = 0;                        // people drawn for the human dataset (0: the dataset command's default)
  bool synthetic() const { return face_model == "synthetic"; }
};

struct RecipeAvatar {
  std::string rig;             // a rig folder or .gltf/.glb, or "synthetic/<name>" (retarget synth's)
  bool init = false;           // `avatar init`: landmarks, eyes and parts proposed from the rig alone
  std::string table;           // the controller table ("": the rig's correspondence.yaml)
  bool meaning_names = false;  // `avatar meaning` may read the controllers' names
  int samples = 0;             // rig samples in the avatar dataset (0: the dataset command's default)
  bool synthetic() const { return rig.rfind("synthetic/", 0) == 0; }
  std::string synthetic_name() const { return rig.substr(10); }
};

struct RecipeTestFaces {
  int blends = 20;  // random blends per unseen person, beside the references
  int blend_seed = 7;
};

// How rounds of comparisons search (scripts' SEARCH): "belief" asks one informative pair per
// expression per round under the belief every answer updated; "champions" runs the paper's
// tournaments around each group's last champion; "map" around the rig head of the rounds before.
struct RecipeMethod {
  std::string folder = "method";  // under the run folder
  int budget = 2000;              // comparisons in all
  std::string search = "belief";
  int annotation_blends = 47;  // belief: random training blends asked about beside the references
  int annotation_people = 8;   // people of the annotation dataset
};

struct RecipeAnnotators {
  std::string kind = "simulated";  // simulated | people
  // simulated: options of `retarget annotate simulate` by their long names without dashes
  // (noise: 0.05, annotators: 3, oracle: true, reading-seed: 2 for another panel of people, ...);
  // each round's seed is its number, the readings the same in every round.
  std::map<std::string, std::string> simulate;
  double poll_seconds = 10;  // people: how often the pipeline looks for new answers
};

struct RecipeExtras {
  bool pictures = false;       // RUN/pictures: the human's blendshapes and the avatar's controllers
  bool geometry_demo = false;  // RUN/geometry: `retarget demo` (DR round trip, deformation transfer)
};

struct Recipe {
  std::string file;  // the recipe as given
  RecipeHuman human;
  RecipeAvatar avatar;
  std::string profile;  // folder with avatar_vae.yaml, human_vae.yaml, translation.yaml, cyclegan.yaml
  // --set overrides per training ("avatar_vae", "human_vae", "translation", "cyclegan"), e.g. training.epochs=3.
  std::map<std::string, std::vector<std::string>> training;
  int training_processes = 1;  // `training.processes`: --nproc of the VAEs' and F's trainings, 1..256
  RecipeTestFaces test_faces;
  RecipeMethod method;
  RecipeAnnotators annotators;
  RecipeExtras extras;
  std::string text;  // the merged recipe as YAML, for the run folder's record

  // Throws retarget::Error naming the key path for a value out of range or missing files.
  void validate() const;
};

// Reads the recipe at `path` (with its bases) and applies `overrides` ("a.b=value"). Unknown
// keys, wrong types and bad values throw retarget::Error naming the file, line and key path.
Recipe load_recipe(const std::string& path, const std::vector<std::string>& overrides);

// The simulate settings recipes may name (retarget annotate simulate's options).
const std::vector<std::string>& simulate_setting_names();

}  // namespace retarget
