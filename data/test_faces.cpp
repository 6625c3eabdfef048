#include "data/test_faces.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <set>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "data/dataset.h"
#include "geometry/face_folder.h"
#include "geometry/face_model.h"
#include "geometry/mesh_io.h"
#include "geometry/topology_fingerprint.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

constexpr const char* kFacesFormat = "retarget-faces";

std::string known_list(const std::vector<std::string>& names) {
  std::string out;
  for (size_t i = 0; i < names.size() && i < 30; ++i) out += (i ? ", " : "") + names[i];
  if (names.size() > 30) out += ", ...";
  return out;
}

// The entries of `wanted` (all of `known` when empty), each checked against `known`.
std::vector<std::string> pick(const std::vector<std::string>& known, const std::vector<std::string>& wanted,
                              const std::string& what, const std::string& where) {
  if (wanted.empty()) return known;
  for (const std::string& name : wanted)
    if (std::find(known.begin(), known.end(), name) == known.end())
      throw Error(where, fmt::format("unknown {} '{}'; known: {}", what, name, known_list(known)));
  return wanted;
}

// Distinct blends among the faces (each is written once per subject).
size_t blends_written(const TestFaces& faces) {
  std::set<std::string> names;
  for (const TestFace& f : faces.faces)
    if (f.set == kBlendSet) names.insert(f.expression);
  return names.size();
}

int index_of(const std::vector<std::string>& names, const std::string& name) {
  return static_cast<int>(std::find(names.begin(), names.end(), name) - names.begin());
}

}  // namespace

void TestFacesOptions::validate() const {
  if (split != "test" && split != "train" && split != "all")
    throw Error("faces.split", fmt::format("expected test, train or all, got '{}'", split));
  blends.validate("faces.blends");
  if (!references && blends.count == 0)
    throw Error("faces.references", "no references and no blends: nothing to write");
}

std::vector<std::string> TestFaces::sets() const {
  std::vector<std::string> out;
  for (const char* set : {kReferenceSet, kBlendSet})
    if (std::any_of(faces.begin(), faces.end(), [&](const TestFace& f) { return f.set == set; })) out.push_back(set);
  return out;
}

TestFaces write_test_faces(const std::string& dataset_folder, const std::string& folder,
                           const TestFacesOptions& options) {
  options.validate();
  if (fs::exists(folder) && !fs::is_directory(folder)) throw Error(folder, "exists and is not a folder");
  if (fs::exists(folder) && !fs::is_empty(folder) && !options.force)
    throw Error(folder, "exists and is not empty; pass --force to replace the faces in it");
  const Dataset d = load_dataset(dataset_folder);
  if (d.kind != DatasetKind::human) throw Error(dataset_folder, "is an avatar dataset; expected a human one");

  const std::vector<std::string>& split_subjects = options.split == "test"    ? d.test_subjects
                                                   : options.split == "train" ? d.train_subjects
                                                                              : d.subjects;
  const std::vector<std::string> subjects =
      pick(split_subjects, options.subjects, fmt::format("subject (of the {} split)", options.split), "--subjects");
  std::vector<std::string> expressions = pick(d.expressions, options.expressions, "expression", "--expressions");
  // Without the references, each subject's neutral face is still written: deformation transfer
  // (the evaluation's baseline) carries a face's displacement from it.
  if (!options.references) {
    const bool neutral = std::find(d.expressions.begin(), d.expressions.end(), "neutral") != d.expressions.end();
    expressions = neutral ? std::vector<std::string>{"neutral"} : std::vector<std::string>{};
  }
  if (options.blends.count > 0 && d.recipes.empty())
    throw Error(dataset_folder,
                "is built from a face folder, which has no blendshapes to blend; --blends needs a face-model dataset");

  fs::create_directories(folder);
  fs::remove(fs::path(folder) / "faces.yaml");
  TestFaces result;
  result.folder = folder;
  result.dataset = fs::absolute(dataset_folder).lexically_normal().string();
  result.fingerprint = d.fingerprint;
  result.recipes = d.recipes;

  auto write_one = [&](const std::string& subject, const std::string& expression, const Positions& positions,
                       const std::map<std::string, double>& weights, const char* set) {
    TestFace face{fmt::format("{}_{}.obj", subject, expression), subject, expression, weights, set};
    write_mesh((fs::path(folder) / face.file).string(), with_positions(d.rest, positions));
    result.faces.push_back(std::move(face));
  };

  if (!d.recipes.empty()) {
    const FaceModel model = load_face_model(d.source);
    if (topology_fingerprint(model.neutral) != d.fingerprint)
      throw Error(d.source, fmt::format("topology fingerprint {} differs from the dataset's {} ({})",
                                        topology_fingerprint(model.neutral), d.fingerprint, dataset_folder));
    if (!d.identity.defined()) throw Error(dataset_folder, "a face-model dataset without identity coefficients");
    const std::vector<ExpressionRecipe> recipes = load_expression_recipes(d.recipes);
    std::vector<std::string> shapes;
    for (const Blendshape& b : model.expressions) shapes.push_back(b.name);
    const std::vector<ExpressionRecipe> blends = random_blends(shapes, options.blends, recipes);
    const torch::Tensor identity = d.identity.contiguous();
    const int64_t modes = identity.size(1);
    for (const std::string& subject : subjects) {
      const int p = index_of(d.subjects, subject);
      const Eigen::VectorXd c = Eigen::Map<const Eigen::VectorXd>(identity.data_ptr<double>() + p * modes, modes);
      const Positions person = model.person(c);
      for (const std::string& expression : expressions) {
        const auto recipe = std::find_if(recipes.begin(), recipes.end(),
                                         [&](const ExpressionRecipe& r) { return r.name == expression; });
        if (recipe == recipes.end())
          throw Error(d.recipes,
                      fmt::format("has no recipe '{}' (the dataset {} names it)", expression, dataset_folder));
        write_one(subject, expression, model.expression(person, recipe->weights), recipe->weights, kReferenceSet);
      }
      for (const ExpressionRecipe& blend : blends)
        write_one(subject, blend.name, model.expression(person, blend.weights), blend.weights, kBlendSet);
    }
  } else {
    const FaceFolder faces = open_face_folder(d.source);
    for (const std::string& subject : subjects) {
      const int s = faces.subject_index(subject);
      if (s < 0)
        throw Error(d.source, fmt::format("has no subject '{}' (the dataset {} names it)", subject, dataset_folder));
      for (const std::string& expression : expressions) {
        const int e = faces.expression_index(expression);
        if (e < 0)
          throw Error(d.source,
                      fmt::format("has no expression '{}' (the dataset {} names it)", expression, dataset_folder));
        write_one(subject, expression, faces.read(s, e), {}, kReferenceSet);
      }
    }
  }

  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "format" << YAML::Value << kFacesFormat;
  out << YAML::Key << "dataset" << YAML::Value << result.dataset;
  out << YAML::Key << "fingerprint" << YAML::Value << result.fingerprint;
  out << YAML::Key << "recipes" << YAML::Value << result.recipes;
  out << YAML::Key << "faces" << YAML::Value << YAML::BeginSeq;
  for (const TestFace& face : result.faces) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "file" << YAML::Value << face.file;
    out << YAML::Key << "subject" << YAML::Value << face.subject;
    out << YAML::Key << "expression" << YAML::Value << face.expression;
    if (face.set != kReferenceSet) out << YAML::Key << "set" << YAML::Value << face.set;
    out << YAML::Key << "weights" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (const auto& [name, weight] : face.weights) out << YAML::Key << name << YAML::Value << weight;
    out << YAML::EndMap << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  write_file_atomically((fs::path(folder) / "faces.yaml").string(), [&](std::ostream& s) { s << out.c_str() << "\n"; });
  log::info("wrote {} meshes of {} subjects x ({} expressions + {} blends) into {}", result.faces.size(),
            subjects.size(), expressions.size(), blends_written(result), folder);
  return result;
}

TestFaces load_test_faces(const std::string& folder) {
  const std::string path = (fs::path(folder) / "faces.yaml").string();
  if (!fs::exists(path)) throw Error(folder, "has no faces.yaml (write one with `retarget faces`)");
  const ConfigNode root = ConfigNode::load_file(path);
  root.reject_unknown_keys({"format", "dataset", "fingerprint", "recipes", "faces"});
  if (root.child("format").as<std::string>() != kFacesFormat)
    root.child("format").fail(fmt::format("expected {}", kFacesFormat));
  TestFaces result;
  result.folder = folder;
  root.get_required("dataset", result.dataset);
  root.get_required("fingerprint", result.fingerprint);
  root.get("recipes", result.recipes);
  const ConfigNode faces = root.child("faces");
  if (!faces.is_sequence()) faces.fail("expected a list");
  for (size_t i = 0; i < faces.size(); ++i) {
    const ConfigNode f = faces.at(i);
    f.reject_unknown_keys({"file", "subject", "expression", "weights", "set"});
    TestFace face;
    f.get_required("file", face.file);
    f.get_required("subject", face.subject);
    f.get_required("expression", face.expression);
    if (f.has("set")) {
      const std::string set = f.child("set").as<std::string>();
      if (set != kReferenceSet && set != kBlendSet)
        f.child("set").fail(fmt::format("expected {} or {}, got \"{}\"", kReferenceSet, kBlendSet, set));
      face.set = set == kBlendSet ? kBlendSet : kReferenceSet;
    }
    if (face.file.empty() || fs::path(face.file).filename() != face.file)
      f.child("file").fail("expected a file name inside the folder");
    if (f.has("weights")) {
      const ConfigNode w = f.child("weights");
      if (!w.is_null() && !w.is_map()) w.fail("expected a map of blendshape weights");
      for (const auto& entry : w.yaml()) {
        const std::string name = entry.first.as<std::string>();
        face.weights[name] = w.child(name).as<double>();
      }
    }
    result.faces.push_back(std::move(face));
  }
  return result;
}

}  // namespace retarget
