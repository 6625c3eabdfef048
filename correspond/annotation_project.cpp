#include "correspond/annotation_project.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/random.h"
#include "core/timer.h"
#include "geometry/face_model.h"
#include "geometry/mesh_io.h"
#include "geometry/reconstruction.h"
#include "render/render.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

constexpr const char* kProjectFile = "project.yaml";
constexpr const char* kDatabase = "annotations.db";
constexpr uint64_t kGroupStream = 200;  // mix_seed's stream for the groups' pairing seeds
constexpr uint64_t kQueueStream = 201;  // mix_seed's stream for the order the groups are queued in

}  // namespace

std::vector<std::string> blendshape_names(const std::string& face_model) {
  try {
    fs::path path(face_model);
    if (fs::is_directory(path)) path /= "face_model.yaml";
    if (!fs::is_regular_file(path)) return {};
    const ConfigNode root = ConfigNode::load_file(path.string());
    std::vector<std::string> names;
    const ConfigNode list = root.child("expressions");
    for (size_t i = 0; i < list.size(); ++i) names.push_back(list.at(i).child("name").as<std::string>());
    return names;
  } catch (const Error&) {
    return {};
  }
}

std::string AnnotationProject::database() const { return (fs::path(folder) / kDatabase).string(); }
std::string AnnotationProject::renders() const { return (fs::path(folder) / "renders").string(); }

uint64_t group_seed(uint64_t seed, int64_t k) { return mix_seed(seed, kGroupStream, static_cast<uint64_t>(k)); }

std::vector<int64_t> queue_order(uint64_t seed, int64_t groups) {
  Random random(mix_seed(seed, kQueueStream));
  return random.permutation(groups);
}

AnnotationProject init_annotation_project(const std::string& correspondences, const std::string& folder,
                                          const AnnotationProjectOptions& options) {
  if (folder.empty()) throw Error("--out", "give a folder for the annotation project");
  const fs::path dir(folder);
  if (fs::exists(dir)) {
    if (!fs::is_directory(dir)) throw Error(folder, "exists and is not a folder");
    if (!fs::is_empty(dir) && !options.force)
      throw Error(folder, fs::exists(dir / kProjectFile)
                              ? "already holds an annotation project; pass --force to start it again (its answers "
                                "are lost)"
                              : "exists and is not empty; pass --force to make the project in it");
  }
  const Correspondences c = load_correspondences(correspondences);

  // Project file first (so a half-made folder is not a project), then the store's files.
  fs::remove(dir / kProjectFile);
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) fs::remove(dir / (std::string(kDatabase) + suffix));
  fs::remove_all(dir / "renders");
  fs::create_directories(dir);

  AnnotationProject project;
  project.folder = folder;
  project.created = utc_timestamp();
  project.correspondences = fs::absolute(correspondences).lexically_normal().string();
  project.seed = options.seed;
  {
    AnnotationStore store = AnnotationStore::open(project.database());
    const torch::Tensor groups = c.groups.contiguous(), distances = c.distances.to(torch::kFloat64).contiguous();
    for (const int64_t k : queue_order(options.seed, c.expression_count())) {
      const int64_t* ids = groups[k].data_ptr<int64_t>();
      const double* d = distances[k].data_ptr<double>();
      store.create_group(c.expressions[k], std::vector<int64_t>(ids, ids + c.group_size),
                         std::vector<double>(d, d + c.group_size), group_seed(options.seed, k));
    }
  }

  YAML::Emitter y;
  y << YAML::BeginMap;
  y << YAML::Key << "format" << YAML::Value << kAnnotationProjectFormat;
  y << YAML::Key << "format_version" << YAML::Value << kAnnotationProjectFormatVersion;
  y << YAML::Key << "software_version" << YAML::Value << RETARGET_VERSION;
  y << YAML::Key << "created" << YAML::Value << project.created;
  y << YAML::Key << "correspondences" << YAML::Value << project.correspondences;
  y << YAML::Key << "seed" << YAML::Value << project.seed;
  y << YAML::Key << "database" << YAML::Value << kDatabase;
  y << YAML::EndMap;
  write_file_atomically((dir / kProjectFile).string(), [&](std::ostream& out) {
    out << "# retarget annotation project (see correspond/annotation_project.h)\n" << y.c_str() << "\n";
  });
  return project;
}

AnnotationProject load_annotation_project(const std::string& folder) {
  const fs::path dir(folder);
  const std::string path = (dir / kProjectFile).string();
  if (!fs::is_regular_file(path))
    throw Error(folder, fs::is_directory(folder) ? "not an annotation project (no project.yaml); make one with "
                                                   "`retarget annotate init`"
                                                 : "annotation project folder not found");
  const ConfigNode m = ConfigNode::load_file(path);
  m.reject_unknown_keys(
      {"format", "format_version", "software_version", "created", "correspondences", "seed", "database"});
  const std::string format = m.child("format").as<std::string>();
  if (format != kAnnotationProjectFormat)
    m.child("format").fail("expected \"" + std::string(kAnnotationProjectFormat) + "\", got \"" + format + "\"");
  const int version = m.child("format_version").as<int>();
  if (version != kAnnotationProjectFormatVersion)
    m.child("format_version")
        .fail(fmt::format("version {} but this build reads version {}", version, kAnnotationProjectFormatVersion));
  AnnotationProject project;
  project.folder = folder;
  m.get("created", project.created);
  m.get_required("correspondences", project.correspondences);
  const int64_t seed = m.child("seed").as<int64_t>();
  project.seed = static_cast<uint64_t>(seed);
  if (!fs::is_regular_file(project.database()))
    throw Error(path, "the project's annotation store " + project.database() + " is missing");
  return project;
}

std::vector<ExpressionRecipe> simulation_recipes(const Dataset& human, const Dataset& avatar) {
  if (human.recipes.empty())
    throw Error(human.folder,
                "the human dataset has no expression recipes (it was built from a face folder), so there is no "
                "expression for a simulated annotator to look at; annotate by hand with `retarget annotate terminal` "
                "or the web tool");
  if (!fs::is_regular_file(human.recipes))
    throw Error(human.folder, "its expression recipes " + human.recipes + " are missing");
  if (avatar.controllers.empty() || !avatar.weights.defined())
    throw Error(avatar.folder, "the avatar dataset has no rig weights");
  return load_expression_recipes(human.recipes);
}

GroundTruth ground_truth_scores(const Correspondences& c, const Dataset& human, const Dataset& avatar,
                                const ControllerCorrespondence& table, const std::string& table_source) {
  const std::vector<ExpressionRecipe> recipes = simulation_recipes(human, avatar);

  std::vector<std::string> blendshapes = blendshape_names(human.source);
  if (blendshapes.empty()) {
    // The face model is out of reach: check the table against what it and the recipes name.
    log::warn("{}: cannot read the face model's blendshape names; the table's human shapes are not checked",
              human.source);
    std::set<std::string> names;
    for (const ExpressionRecipe& r : recipes)
      for (const auto& entry : r.weights) names.insert(entry.first);
    for (const auto& row : table)
      for (const auto& entry : row.second) names.insert(entry.first);
    blendshapes.assign(names.begin(), names.end());
  }
  check_controller_correspondence(table, avatar.controllers, blendshapes, table_source);

  const int64_t controllers = static_cast<int64_t>(avatar.controllers.size());
  GroundTruth truth;
  for (int64_t k = 0; k < c.expression_count(); ++k) {
    const std::string& label = c.expressions[k];
    const ExpressionRecipe* recipe = nullptr;
    for (const ExpressionRecipe& r : recipes)
      if (r.name == label) recipe = &r;
    if (!recipe)
      throw Error(human.recipes,
                  "no recipe for the expression \"" + label + "\" of the correspondences in " + c.folder);
    const std::map<std::string, double> mapped = controller_weights_from_human(table, recipe->weights);
    std::vector<double> target(static_cast<size_t>(controllers), 0.0);
    for (int64_t j = 0; j < controllers; ++j) {
      const auto it = mapped.find(avatar.controllers[j]);
      if (it != mapped.end()) target[j] = it->second;
    }
    truth.controller_weights[label] = target;
    auto& scores = truth.scores[label];
    for (int64_t p = 0; p < c.group_size; ++p) {
      const int64_t sample = c.groups[k][p].item<int64_t>();
      if (sample < 0 || sample >= c.candidate_count())
        throw Error(avatar.folder, fmt::format("has no sample {} (group \"{}\")", sample, label));
      const torch::Tensor candidate = c.candidate_weights(avatar, sample).contiguous();
      const double* cw = candidate.data_ptr<double>();
      double sum = 0;
      for (int64_t j = 0; j < controllers; ++j) sum += (cw[j] - target[j]) * (cw[j] - target[j]);
      scores[sample] = std::sqrt(sum);
    }
  }
  return truth;
}

std::vector<Triplet> load_project_triplets(const std::string& project_or_db, bool include_derived) {
  std::string database;
  if (fs::is_directory(project_or_db)) {
    database = load_annotation_project(project_or_db).database();
  } else if (fs::is_regular_file(project_or_db)) {
    database = project_or_db;
  } else {
    throw Error(project_or_db, "no such annotation project folder or annotations .db file");
  }
  return AnnotationStore::open(database).triplets(include_derived);
}

}  // namespace retarget

// ---- Renders

namespace retarget {

struct AnnotationRenders::Impl {
  AnnotationProject project;
  Correspondences correspondences;
  Dataset avatar;
  std::unique_ptr<Reconstruction> reconstruction;
  RenderOptions options;
  Eigen::AlignedBox3d avatar_frame;
};

namespace {

Eigen::AlignedBox3d enlarged(const Eigen::AlignedBox3d& box, double factor) {
  const Eigen::Vector3d centre = box.center(), half = 0.5 * factor * box.sizes();
  return Eigen::AlignedBox3d(centre - half, centre + half);
}

}  // namespace

AnnotationRenders::AnnotationRenders(const AnnotationProject& project, int size) : impl_(std::make_unique<Impl>()) {
  impl_->project = project;
  impl_->correspondences = load_correspondences(project.correspondences);
  impl_->avatar = load_dataset(impl_->correspondences.avatar_dataset);
  ReconstructionOptions ro;
  ro.weighting = impl_->avatar.dr.weighting;
  impl_->reconstruction = std::make_unique<Reconstruction>(impl_->avatar.rest, ro);
  impl_->options.width = impl_->options.height = size;
  impl_->avatar_frame = enlarged(frame_box(impl_->avatar.rest.vertices), 1.15);
}

AnnotationRenders::~AnnotationRenders() = default;
AnnotationRenders::AnnotationRenders(AnnotationRenders&&) noexcept = default;
AnnotationRenders& AnnotationRenders::operator=(AnnotationRenders&&) noexcept = default;

namespace {

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The PNG at `png`, made by `draw` and written atomically on first use; its bytes go to `bytes`
// when given (the pictures the server sends), else an existing file is not read at all.
template <typename Draw>
void cached_png(const fs::path& png, Draw draw, std::string* bytes = nullptr) {
  if (fs::exists(png)) {
    if (bytes) *bytes = read_bytes(png);
    return;
  }
  const std::string encoded = encode_png(draw(), png.string());
  write_file_atomically(png.string(), [&](std::ostream& out) {
    out.write(encoded.data(), static_cast<std::streamsize>(encoded.size()));
  });
  if (bytes) *bytes = encoded;
}

}  // namespace

Mesh AnnotationRenders::reference(const std::string& label) const {
  return read_mesh((fs::path(impl_->project.correspondences) / "reference" / (label + ".obj")).string());
}

Positions AnnotationRenders::candidate_positions(int64_t sample) const {
  const torch::Tensor features = impl_->correspondences.candidate_features(impl_->avatar, sample).contiguous();
  return impl_->reconstruction->reconstruct(features.data_ptr<float>());
}

std::string AnnotationRenders::anchor(const std::string& label) {
  const fs::path png = fs::path(impl_->project.renders()) / ("human_" + label + ".png");
  cached_png(png, [&] {
    const Mesh mesh = reference(label);
    RenderOptions o = impl_->options;
    o.frame = enlarged(frame_box(mesh.vertices), 1.15);
    return render(mesh, o);
  });
  return png.string();
}

std::string AnnotationRenders::candidate(int64_t sample) {
  const fs::path png = fs::path(impl_->project.renders()) / fmt::format("avatar_{}.png", sample);
  cached_png(png, [&] {
    RenderOptions o = impl_->options;
    o.frame = impl_->avatar_frame;
    return render(impl_->avatar.rest, candidate_positions(sample), o);
  });
  return png.string();
}

fs::path AnnotationRenders::turntable_folder(int frames, double max_yaw_deg) const {
  return fs::path(impl_->project.renders()) /
         fmt::format("turntable-{}x{}-{}deg", frames, impl_->options.width, static_cast<int>(std::lround(max_yaw_deg)));
}

std::string AnnotationRenders::anchor_turntable(const std::string& label, int frames, double max_yaw_deg) {
  std::string bytes;
  cached_png(
      turntable_folder(frames, max_yaw_deg) / ("human_" + label + ".png"),
      [&] {
        const Mesh mesh = reference(label);
        RenderOptions o = impl_->options;
        o.frame = enlarged(frame_box(mesh.vertices), 1.15);
        return render_turntable(mesh, mesh.vertices, frames, max_yaw_deg, o);
      },
      &bytes);
  return bytes;
}

std::string AnnotationRenders::candidate_turntable(int64_t sample, int frames, double max_yaw_deg) {
  std::string bytes;
  cached_png(
      turntable_folder(frames, max_yaw_deg) / fmt::format("avatar_{}.png", sample),
      [&] {
        RenderOptions o = impl_->options;
        o.frame = impl_->avatar_frame;
        return render_turntable(impl_->avatar.rest, candidate_positions(sample), frames, max_yaw_deg, o);
      },
      &bytes);
  return bytes;
}

}  // namespace retarget
