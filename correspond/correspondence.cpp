#include "correspond/correspondence.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <numeric>
#include <set>
#include <utility>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/tensor_io.h"
#include "core/timer.h"
#include "geometry/controller_correspondence.h"
#include "geometry/controller_map.h"
#include "geometry/dr_features.h"
#include "geometry/face_model.h"
#include "geometry/landmarks.h"
#include "geometry/mesh_io.h"
#include "geometry/reconstruction.h"
#include "geometry/rig.h"
#include "geometry/rig_weight_fit.h"
#include "geometry/topology_fingerprint.h"
#include "train/vae_run.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

constexpr const char* kManifest = "correspondences.yaml";
constexpr const char* kTensors = "correspondences.pt";
constexpr const char* kReference = "reference";
constexpr const char* kTransferred = "dt";
constexpr const char* kProjected = "dt_rig";

std::string absolute_path(const std::string& path) { return fs::absolute(path).lexically_normal().string(); }

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

template <typename... Args>
void say(const CorrespondenceOptions& options, fmt::format_string<Args...> format, Args&&... args) {
  if (options.progress) *options.progress << fmt::format(format, std::forward<Args>(args)...) << "\n";
}

// An expression name becomes a file name (reference/<name>.obj, dt/<name>.obj).
void check_file_name(const std::string& name, const std::string& where) {
  if (name.empty() || name == "." || name == ".." || name.find_first_of("/\\") != std::string::npos)
    throw Error(where, "the expression name \"" + name + "\" cannot be used as a file name");
}

// Refuses a non-empty folder unless `force`, before any work is done.
void check_output_folder(const std::string& folder, bool force) {
  if (folder.empty()) throw Error("--out", "give a folder for the correspondences");
  if (!fs::exists(folder)) return;
  if (!fs::is_directory(folder)) throw Error(folder, "exists and is not a folder");
  if (!fs::is_empty(folder) && !force)
    throw Error(folder, "exists and is not empty; pass --force to replace the correspondences in it");
}

// Removes what an earlier build wrote (the manifest first, so a half-written folder never has
// one), leaving anything else in the folder alone.
void clear_output_folder(const std::string& folder) {
  const fs::path dir(folder);
  fs::remove(dir / kManifest);
  fs::remove(dir / kTensors);
  fs::remove_all(dir / kReference);
  fs::remove_all(dir / kTransferred);
  fs::remove_all(dir / kProjected);
  fs::create_directories(dir);
}

struct NamedPair {
  std::string name;
  LandmarkPair pair;
};

std::vector<NamedPair> landmark_pairs(const Dataset& human, const Dataset& avatar, const std::string& file) {
  std::vector<NamedPair> out;
  if (file.empty()) {
    for (const auto& [name, vertex] : human.landmarks) {
      const auto it = avatar.landmarks.find(name);
      if (it != avatar.landmarks.end()) out.push_back({name, {vertex, it->second}});
    }
    if (out.size() < 3) {
      std::vector<std::string> h, a;
      for (const auto& entry : human.landmarks) h.push_back(entry.first);
      for (const auto& entry : avatar.landmarks) a.push_back(entry.first);
      throw Error("correspond.landmarks",
                  fmt::format("the human dataset {} and the avatar dataset {} share {} landmark name{} ({}), "
                              "deformation transfer needs at least 3; human landmarks: [{}]; avatar landmarks: "
                              "[{}]; name more landmarks in the rig or face model, or give --landmarks FILE",
                              human.folder, avatar.folder, out.size(), out.size() == 1 ? "" : "s",
                              out.empty() ? "none" : out.front().name, joined(h), joined(a)));
    }
    return out;
  }
  const std::vector<LandmarkPair> pairs = read_landmark_pairs(file);
  if (pairs.size() < 3)
    throw Error(file, fmt::format("{} landmark pair{}, deformation transfer needs at least 3", pairs.size(),
                                  pairs.size() == 1 ? "" : "s"));
  check_landmark_pairs(pairs, human.vertex_count(), human.rest.source, avatar.vertex_count(), avatar.rest.source);
  for (size_t i = 0; i < pairs.size(); ++i) {
    std::string name = fmt::format("pair{}", i);
    for (const auto& [label, vertex] : human.landmarks) {
      const auto it = avatar.landmarks.find(label);
      if (vertex == pairs[i].source && it != avatar.landmarks.end() && it->second == pairs[i].target) name = label;
    }
    out.push_back({name, pairs[i]});
  }
  return out;
}

struct Nearest {
  torch::Tensor groups;     // [K, P] int64
  torch::Tensor distances;  // [K, P] float32
};

// The P rows of data ([N, D] float32) nearest to each query ([K, D] float32) by L2 distance,
// nearest first (ties: lower index first). Squared distances come from |q|^2 + |x|^2 - 2 q.x in
// float64 over chunks of the data; the best P + 8 of each query are then recomputed directly, so
// order and distances are exact up to float64 rounding of the differences themselves.
Nearest nearest_rows(const torch::Tensor& queries, const torch::Tensor& data, int64_t p) {
  const int64_t k = queries.size(0), n = data.size(0), d = data.size(1);
  const torch::Tensor q = queries.to(torch::kFloat64);
  const torch::Tensor q_norm = q.pow(2).sum(1, /*keepdim=*/true);  // [K, 1]
  torch::Tensor squared = torch::empty({k, n}, torch::kFloat64);
  const int64_t chunk = std::max<int64_t>(1, (int64_t{64} << 20) / (d * 8));  // ~64 MB of float64 rows
  for (int64_t begin = 0; begin < n; begin += chunk) {
    const int64_t end = std::min(n, begin + chunk);
    const torch::Tensor x = data.slice(0, begin, end).to(torch::kFloat64);
    squared.slice(1, begin, end).copy_(q_norm + x.pow(2).sum(1).unsqueeze(0) - 2 * q.mm(x.t()));
  }
  const int64_t m = std::min(n, p + 8);
  const torch::Tensor candidates = std::get<1>(squared.topk(m, 1, /*largest=*/false, /*sorted=*/true));  // [K, M]
  Nearest out;
  out.groups = torch::empty({k, p}, torch::kInt64);
  out.distances = torch::empty({k, p}, torch::kFloat32);
  auto groups = out.groups.accessor<int64_t, 2>();
  auto distances = out.distances.accessor<float, 2>();
  for (int64_t i = 0; i < k; ++i) {
    const torch::Tensor index = candidates[i].contiguous();
    const torch::Tensor exact = (data.index_select(0, index).to(torch::kFloat64) - q[i]).pow(2).sum(1).contiguous();
    const int64_t* ids = index.data_ptr<int64_t>();
    const double* values = exact.data_ptr<double>();
    std::vector<std::pair<double, int64_t>> ranked(static_cast<size_t>(m));
    for (int64_t j = 0; j < m; ++j) ranked[j] = {values[j], ids[j]};
    std::sort(ranked.begin(), ranked.end());
    for (int64_t j = 0; j < p; ++j) {
      groups[i][j] = ranked[j].second;
      distances[i][j] = static_cast<float>(std::sqrt(ranked[j].first));
    }
  }
  return out;
}

// Fills columns near..P-1 of each group with samples chosen for variety: farthest-point sampling
// over the unit directions of the samples' rig weights (cosine distance), starting from those of
// the group's first `near` members that are candidates themselves. Candidates are the samples
// that move some controller past half its range (all samples that move at all when fewer than
// needed); ties go to the sample that moves more, then to the lower index. Distances are each pick's raw-DR distance to
// its query.
void spread_groups(Nearest& nearest, const torch::Tensor& queries, const torch::Tensor& data,
                   const torch::Tensor& weights, int64_t near, const std::string& dataset) {
  const int64_t k = nearest.groups.size(0), p = nearest.groups.size(1), n = weights.size(0);
  const torch::Tensor w = weights.to(torch::kFloat64);
  const torch::Tensor norm = w.norm(2, 1);                            // [N]
  const torch::Tensor unit = w / norm.clamp_min(1e-12).unsqueeze(1);  // [N, C]
  const torch::Tensor largest = std::get<0>(w.abs().max(1));          // [N]
  torch::Tensor eligible = largest >= 0.5;
  if (eligible.sum().item<int64_t>() < p - near) eligible = norm > 1e-9;
  if (eligible.sum().item<int64_t>() < p - near)
    throw Error("correspond.spread", fmt::format("{} varied members per group, but only {} samples of the avatar "
                                                 "dataset {} move a controller",
                                                 p - near, eligible.sum().item<int64_t>(), dataset));
  const double* norms = norm.contiguous().data_ptr<double>();
  auto groups = nearest.groups.accessor<int64_t, 2>();
  auto distances = nearest.distances.accessor<float, 2>();
  for (int64_t i = 0; i < k; ++i) {
    // gap[j]: cosine distance of sample j to the nearest chosen direction; -1 once unavailable.
    torch::Tensor gap = torch::full({n}, 2.0, torch::kFloat64);
    gap.masked_fill_(eligible.logical_not(), -1.0);
    // Only the near members that are themselves eligible cover a direction: a nearly neutral
    // sample that moves a controller by 0.02 does not offer what that controller does.
    for (int64_t j = 0; j < near; ++j) {
      const int64_t chosen = groups[i][j];
      if (eligible[chosen].item<bool>()) gap = torch::minimum(gap, 1.0 - unit.mv(unit[chosen]));
      gap[chosen] = -1.0;
    }
    for (int64_t j = near; j < p; ++j) {
      const torch::Tensor g = gap.contiguous();
      const double* values = g.data_ptr<double>();
      int64_t best = -1;
      for (int64_t s = 0; s < n; ++s) {
        if (values[s] < 0) continue;
        if (best < 0 || values[s] > values[best] + 1e-12 ||
            (std::abs(values[s] - values[best]) <= 1e-12 && norms[s] > norms[best]))
          best = s;
      }
      groups[i][j] = best;
      distances[i][j] =
          static_cast<float>((data[best].to(torch::kFloat64) - queries[i].to(torch::kFloat64)).norm().item<double>());
      gap = torch::minimum(gap, 1.0 - unit.mv(unit[best]));
      gap[best] = -1.0;  // cosine distances are >= 0, so -1 stays -1 under the minimum
    }
  }
}

// The avatar dataset's rig, for `purpose`; throws retarget::Error naming `key` with `remedy`
// when it does not load or no longer has the dataset's topology.
Rig dataset_rig(const Dataset& avatar, const std::string& key, const std::string& purpose, const std::string& remedy) {
  Rig rig;
  try {
    rig = load_dataset_rig(avatar);  // the glTF meshes the dataset was built from
  } catch (const Error& e) {
    throw Error(
        key, fmt::format("{} needs the avatar dataset's rig, which does not load ({}); {}", purpose, e.what(), remedy));
  }
  if (topology_fingerprint(rig.neutral) != avatar.fingerprint)
    throw Error(key, fmt::format("the rig {} no longer has the topology of the avatar dataset {}; rebuild the dataset "
                                 "or {}",
                                 avatar.source, avatar.folder, remedy));
  return rig;
}

void write_manifest(const Correspondences& c, int64_t avatar_vertices, int64_t avatar_samples, int64_t latent,
                    const std::vector<NamedPair>& pairs, const DeformationTransferOptions& transfer,
                    const DeformationTransfer::Report& report, double transfer_seconds) {
  YAML::Emitter y;
  y.SetDoublePrecision(10);
  y << YAML::BeginMap;
  y << YAML::Key << "format" << YAML::Value << kCorrespondenceFormat;
  y << YAML::Key << "format_version" << YAML::Value << kCorrespondenceFormatVersion;
  y << YAML::Key << "software_version" << YAML::Value << RETARGET_VERSION;
  y << YAML::Key << "created" << YAML::Value << c.created;
  y << YAML::Key << "group_size" << YAML::Value << c.group_size;
  y << YAML::Key << "latent" << YAML::Value << latent;
  y << YAML::Key << "human" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "folder" << YAML::Value << c.human_dataset;
  y << YAML::Key << "name" << YAML::Value << c.human_name;
  y << YAML::Key << "fingerprint" << YAML::Value << c.human_fingerprint << YAML::EndMap;
  y << YAML::Key << "avatar" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "folder" << YAML::Value << c.avatar_dataset;
  y << YAML::Key << "name" << YAML::Value << c.avatar_name;
  y << YAML::Key << "fingerprint" << YAML::Value << c.avatar_fingerprint;
  y << YAML::Key << "vertex_count" << YAML::Value << avatar_vertices;
  y << YAML::Key << "sample_count" << YAML::Value << avatar_samples << YAML::EndMap;
  y << YAML::Key << "avatar_vae" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "folder" << YAML::Value << c.avatar_vae_run;
  y << YAML::Key << "checkpoint" << YAML::Value << c.avatar_vae_checkpoint << YAML::EndMap;
  y << YAML::Key << "landmarks" << YAML::Value << YAML::BeginMap;
  for (const NamedPair& p : pairs)
    y << YAML::Key << p.name << YAML::Value << YAML::Flow << YAML::BeginSeq << p.pair.source << p.pair.target
      << YAML::EndSeq;
  y << YAML::EndMap;
  y << YAML::Key << "expressions" << YAML::Value << YAML::Flow << c.expressions;
  y << YAML::Key << "initial" << YAML::Value << c.initial;
  if (!c.around.empty()) y << YAML::Key << "around" << YAML::Value << c.around;
  if (!c.start_table.empty()) y << YAML::Key << "start_table" << YAML::Value << c.start_table;
  y << YAML::Key << "spread" << YAML::Value << c.spread;
  if (c.proposals.count > 0) {
    y << YAML::Key << "proposals" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "count" << YAML::Value << c.proposals.count;
    y << YAML::Key << "sigma" << YAML::Value << c.proposals.sigma;
    y << YAML::Key << "controllers" << YAML::Value << c.proposals.controllers;
    y << YAML::Key << "seed" << YAML::Value << c.proposals.seed << YAML::EndMap;
  }
  if (c.informative) {
    y << YAML::Key << "informative" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "evidence" << YAML::Value << YAML::BeginSeq;
    for (const std::string& e : c.evidence) y << e;
    y << YAML::EndSeq << YAML::Key << "comparisons" << YAML::Value << c.evidence_comparisons << YAML::EndMap;
  }
  y << YAML::Key << "deformation_transfer" << YAML::Value << YAML::BeginMap;
  const char* prealignment = transfer.prealignment == DeformationTransferOptions::Prealignment::none ? "none"
                             : transfer.prealignment == DeformationTransferOptions::Prealignment::translation_scale
                                 ? "translation_scale"
                                 : "similarity";
  y << YAML::Key << "prealignment" << YAML::Value << prealignment;
  y << YAML::Key << "translation_anchor" << YAML::Value
    << (transfer.translation_anchor == DeformationTransferOptions::TranslationAnchor::follow_source ? "follow_source"
                                                                                                    : "keep_centroid");
  y << YAML::Key << "fit_mean_distance" << YAML::Value << report.mean_distance;
  y << YAML::Key << "fit_max_distance" << YAML::Value << report.max_distance;
  y << YAML::Key << "prealignment_scale" << YAML::Value << report.prealignment_scale;
  y << YAML::Key << "match_distance" << YAML::Value << report.match_distance;
  y << YAML::Key << "triangle_pairs" << YAML::Value << report.triangle_pairs;
  y << YAML::Key << "fallback_target_triangles" << YAML::Value << report.fallback_target_triangles;
  y << YAML::Key << "identity_target_triangles" << YAML::Value << report.identity_target_triangles;
  y << YAML::Key << "seconds" << YAML::Value << transfer_seconds << YAML::EndMap;
  y << YAML::Key << "files" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "tensors" << YAML::Value << kTensors;
  y << YAML::Key << "reference" << YAML::Value << std::string(kReference) + "/<expression>.obj";
  y << YAML::Key << "dt" << YAML::Value << std::string(kTransferred) + "/<expression>.obj";
  if (c.initial == "rig") y << YAML::Key << "dt_rig" << YAML::Value << std::string(kProjected) + "/<expression>.obj";
  y << YAML::EndMap;
  y << YAML::EndMap;
  if (!y.good()) throw Error(c.folder, "cannot write the manifest: " + y.GetLastError());
  write_file_atomically((fs::path(c.folder) / kManifest).string(), [&](std::ostream& out) {
    out << "# retarget correspondences (see correspond/correspondence.h); correspondences.pt loads with torch.load\n"
        << y.c_str() << "\n";
  });
}

}  // namespace

void CorrespondenceOptions::validate() const {
  if (group_size < 2)
    throw Error("correspond.group_size", fmt::format("expected at least 2 candidates per group, got {}", group_size));
  std::set<std::string> seen;
  for (const std::string& name : expressions) {
    if (name.empty()) throw Error("correspond.expressions", "an expression name is empty");
    if (!seen.insert(name).second)
      throw Error("correspond.expressions", "the expression \"" + name + "\" is named twice");
  }
  if (checkpoint != "best" && checkpoint != "last")
    throw Error("correspond.checkpoint", "expected 'best' or 'last', got '" + checkpoint + "'");
  if (initial != "rig" && initial != "dt" && initial != "champions" && initial != "table")
    throw Error("correspond.initial", "expected 'rig', 'dt', 'champions' or 'table', got '" + initial + "'");
  if ((initial == "table") != !start_table.empty())
    throw Error("correspond.start_table", initial == "table"
                                              ? "initial 'table' needs the controller table to start from"
                                              : "a table to start from needs initial 'table'");
  if ((initial == "champions") != !around.empty())
    throw Error("correspond.around", initial == "champions"
                                         ? "initial 'champions' needs the annotation project to take them from"
                                         : "an annotation project to start from needs initial 'champions'");
  if (spread < 0 || spread >= group_size)
    throw Error("correspond.spread",
                fmt::format("expected 0 to {} (fewer than the group size), got {}", group_size - 1, spread));
  proposals.validate("correspond.proposals");
  if (spread + proposals.count > group_size || (spread > 0 && spread + proposals.count >= group_size))
    throw Error("correspond.proposals",
                fmt::format("{} proposals and {} varied members do not fit groups of {}{}", proposals.count, spread,
                            group_size, spread > 0 ? " with a dataset member to start the variety from" : ""));
  if (proposals.count > 0 && initial == "dt")
    throw Error("correspond.proposals", "proposals move a start on the rig: give initial 'rig' or 'champions'");
  if (!(projection_ridge >= 0) || !std::isfinite(projection_ridge))
    throw Error("correspond.projection_ridge", "expected a finite number >= 0");
  if (!evidence.empty() && !informative)
    throw Error("correspond.evidence", "earlier rounds inform the belief search only: give informative");
  if (informative) {
    if (initial != "table")
      throw Error("correspond.informative", "the belief search starts from a controller table: give start_table");
    if (group_size != 2 || spread != 0 || proposals.count != 0)
      throw Error("correspond.informative",
                  fmt::format("the belief search asks one comparison per group: groups of 2 with no spread or "
                              "proposals, got groups of {} with {} varied and {} proposed",
                              group_size, spread, proposals.count));
  }
  if ((initial == "champions" || informative) && !round_starts)
    throw Error("correspond.round_starts",
                "a round that earlier rounds decide needs the rule for its starts (pipeline/round_starts.h)");
  transfer.validate();
}

int64_t Correspondences::expression_index(const std::string& expression) const {
  const auto it = std::find(expressions.begin(), expressions.end(), expression);
  if (it == expressions.end())
    throw Error(folder, "no correspondence for the expression \"" + expression + "\"; it has: " + joined(expressions));
  return it - expressions.begin();
}

Correspondences build_correspondences(const std::string& human_dataset, const std::string& avatar_dataset,
                                      const std::string& avatar_vae_run, const std::string& out_folder,
                                      const CorrespondenceOptions& options) {
  return build_correspondences(human_dataset, avatar_dataset, avatar_vae_run, out_folder, options, nullptr);
}

namespace {

// What a build reads: the human dataset, the avatar VAE and its dataset, the expressions chosen
// and the landmark pairs.
struct BuildInputs {
  Dataset human;
  TrainedVae trained;
  Dataset avatar;                  // the VAE's own dataset when it is the one given
  std::vector<int64_t> selected;   // [K] indices into human.expressions
  std::vector<std::string> names;  // [K] their names
  std::vector<NamedPair> pairs;
};

BuildInputs load_build_inputs(const std::string& human_dataset, const std::string& avatar_dataset,
                              const std::string& avatar_vae_run, const CorrespondenceOptions& options) {
  BuildInputs in;
  in.human = load_dataset(human_dataset);
  const Dataset& human = in.human;
  if (human.kind != DatasetKind::human)
    throw Error(human_dataset, "is an avatar dataset; --human needs a human dataset (retarget dataset --face-model)");
  in.trained = load_trained_vae(avatar_vae_run, options.checkpoint);
  // The run's own dataset is usually the avatar dataset itself: read it once.
  std::error_code same_error;
  const bool same_folder = fs::equivalent(in.trained.dataset.folder, avatar_dataset, same_error);
  in.avatar = same_folder ? in.trained.dataset : load_dataset(avatar_dataset);
  const Dataset& avatar = in.avatar;
  if (avatar.kind != DatasetKind::avatar)
    throw Error(avatar_dataset, "is a human dataset; --avatar needs an avatar dataset (retarget dataset --rig)");
  if (in.trained.dataset.fingerprint != avatar.fingerprint)
    throw Error(
        avatar_vae_run,
        fmt::format("the avatar VAE was trained on {} (topology fingerprint {}), but the avatar dataset {} has "
                    "the topology {}; give the VAE run trained on this avatar",
                    in.trained.dataset.folder, in.trained.dataset.fingerprint, avatar_dataset, avatar.fingerprint));
  // The encoder only knows the normalisation it was trained with.
  const Normaliser& normaliser = in.trained.dataset.normaliser;
  if (!same_folder &&
      !(torch::equal(normaliser.min, avatar.normaliser.min) && torch::equal(normaliser.max, avatar.normaliser.max)))
    say(options, "note: {} and the VAE's dataset {} normalise differently; codes use the VAE's normaliser",
        avatar_dataset, in.trained.dataset.folder);
  if (avatar.sample_count() < options.group_size)
    throw Error("correspond.group_size", fmt::format("{} candidates per group, but the avatar dataset {} has only {} "
                                                     "samples",
                                                     options.group_size, avatar_dataset, avatar.sample_count()));
  if (!human.targets.defined() || human.targets.size(0) != static_cast<int64_t>(human.expressions.size()))
    throw Error(human_dataset, "has no identity-averaged targets for its expressions");

  if (options.expressions.empty()) {
    for (size_t e = 0; e < human.expressions.size(); ++e) in.selected.push_back(static_cast<int64_t>(e));
    in.names = human.expressions;
  } else {
    for (const std::string& name : options.expressions) {
      const auto it = std::find(human.expressions.begin(), human.expressions.end(), name);
      if (it == human.expressions.end())
        throw Error("correspond.expressions", "unknown expression \"" + name + "\"; the human dataset " +
                                                  human_dataset + " has: " + joined(human.expressions));
      in.selected.push_back(it - human.expressions.begin());
      in.names.push_back(name);
    }
  }
  for (const std::string& name : in.names) check_file_name(name, human_dataset);
  in.pairs = landmark_pairs(human, avatar, options.landmarks_file);
  return in;
}

// DR features [M, Va, 9] float32 of avatar meshes.
torch::Tensor avatar_features(const DrFeatures& dr, int64_t vertices, const std::vector<Positions>& meshes) {
  torch::Tensor f = torch::empty({static_cast<int64_t>(meshes.size()), vertices, kDrWidth}, torch::kFloat32);
  std::vector<const Positions*> pointers;
  for (const Positions& p : meshes) pointers.push_back(&p);
  dr.compute_batch(pointers, f.data_ptr<float>());
  return f;
}

// The reference meshes (the identity-averaged expressions on the mean face) and their
// deformation transfer onto the avatar's neutral.
struct Transferred {
  std::vector<Positions> references;    // [K] human meshes
  std::vector<LandmarkPair> landmarks;  // the pairs the transfer used
  DeformationTransfer::Report report;
  std::vector<Positions> meshes;  // [K] avatar meshes
  torch::Tensor features;         // [K, Va, 9] float32, their DR features
};

Transferred transfer_references(const BuildInputs& in, const CorrespondenceOptions& options, const DrFeatures& dr,
                                CorrespondenceReport& r, Stopwatch& clock) {
  const Dataset& human = in.human;
  Transferred t;
  const torch::Tensor targets =
      human.targets.index_select(0, torch::tensor(in.selected, torch::kInt64)).to(torch::kFloat32).contiguous();
  ReconstructionOptions reconstruction_options;
  reconstruction_options.weighting = human.dr.weighting;
  const Reconstruction reconstruction(human.rest, reconstruction_options);
  t.references = reconstruction.reconstruct_batch(targets.data_ptr<float>(), static_cast<int>(in.selected.size()));
  r.reconstruction_seconds = clock.restart();

  for (const NamedPair& p : in.pairs) t.landmarks.push_back(p.pair);
  // The transfer's source rest is the identity-averaged neutral when the set has one: the
  // references share its identity, so DT carries only their expression onto the avatar (from
  // the mean face they would also carry the small difference between the mean face and the
  // training people's average, over every vertex).
  const auto neutral = std::find(human.expressions.begin(), human.expressions.end(), "neutral");
  Positions source_rest = human.rest.vertices;
  if (neutral != human.expressions.end()) {
    const torch::Tensor n = human.targets[neutral - human.expressions.begin()].to(torch::kFloat32).contiguous();
    source_rest = reconstruction.reconstruct_batch(n.data_ptr<float>(), 1).front();
  }
  const DeformationTransfer transfer(with_positions(human.rest, source_rest), in.avatar.rest, t.landmarks,
                                     options.transfer);
  t.report = transfer.report();
  t.meshes = transfer.transfer(t.references);
  t.features = avatar_features(dr, in.avatar.vertex_count(), t.meshes);
  return t;
}

// Where y0 and the groups start: the DT results, their projections onto the rig, or the
// champions of an earlier round.
struct Start {
  Rig rig;                           // loaded when projecting or proposing
  std::vector<Positions> projected;  // [K] with initial: rig
  torch::Tensor weights;             // [K, C] float64; undefined for initial: dt
  torch::Tensor features;            // [K, Va, 9] float32
  torch::Tensor pairs;               // [K, 2, C] float64: informative only, the belief search's pairs
  int evidence_comparisons = 0;      // informative only: the comparisons the belief observed
};

// Per named expression, the rig weights the controller table (or controller map: the rig head
// of earlier rounds) gives its recipe, [K, C] float64, inside each controller's range.
torch::Tensor table_starts(const BuildInputs& in, const Rig& rig, const std::string& table_path) {
  if (in.human.recipes.empty())
    throw Error("correspond.start_table", in.human.folder + " has no expression recipes to read through the table");
  const std::vector<ExpressionRecipe> recipes = load_expression_recipes(in.human.recipes);
  std::function<Eigen::VectorXd(const std::map<std::string, double>&)> read;
  if (is_controller_map_file(table_path)) {
    const auto map = std::make_shared<const ControllerMap>(load_controller_map(table_path));
    read = [map, &rig, table_path](const std::map<std::string, double>& w) { return map->on_rig(w, rig, table_path); };
  } else {
    const auto table = std::make_shared<const ControllerCorrespondence>(load_controller_correspondence(table_path));
    read = [table, &rig](const std::map<std::string, double>& w) { return rig_weights_from_human(*table, rig, w); };
  }
  torch::Tensor weights =
      torch::empty({static_cast<int64_t>(in.names.size()), rig.controller_count()}, torch::kFloat64);
  for (size_t i = 0; i < in.names.size(); ++i) {
    const Eigen::VectorXd w = read(recipe_weights(recipes, in.names[i], in.human.recipes));
    for (int c = 0; c < rig.controller_count(); ++c) weights[static_cast<int64_t>(i)][c] = w(c);
  }
  return weights;
}

Start start_points(const BuildInputs& in, const Transferred& dt, const CorrespondenceOptions& options,
                   const DrFeatures& dr, const std::string& avatar_dataset) {
  const Dataset& avatar = in.avatar;
  Start start;
  start.features = dt.features;
  if (options.initial == "rig" || options.initial == "table")
    start.rig =
        dataset_rig(avatar, "correspond.initial", "starting on the rig", "give --initial dt to use the raw transfer");
  else if (options.proposals.count > 0)
    start.rig = dataset_rig(avatar, "correspond.proposals", "proposing expressions", "give no proposals");
  const Rig& rig = start.rig;
  const auto k = static_cast<int64_t>(in.names.size());
  if (options.initial == "rig") {
    RigWeightFitOptions fit_options;
    fit_options.ridge = options.projection_ridge;
    const RigWeightFit fit(rig, fit_options);
    start.weights = torch::empty({k, rig.controller_count()}, torch::kFloat64);
    for (int64_t i = 0; i < k; ++i) {
      const Eigen::VectorXd w = fit.fit(dt.meshes[i]);
      for (int c = 0; c < rig.controller_count(); ++c) start.weights[i][c] = w(c);
      start.projected.push_back(rig.evaluate(w));
    }
    start.features = avatar_features(dr, avatar.vertex_count(), start.projected);
  } else if (options.initial == "table") {
    if (options.informative) {
      RoundStarts decided = options.round_starts({in.names, in.human, avatar, rig});
      start.weights = std::move(decided.weights);
      start.pairs = std::move(decided.pairs);
      start.evidence_comparisons = decided.evidence_comparisons;
    } else {
      start.weights = table_starts(in, rig, options.start_table);
    }
    std::vector<Positions> meshes;  // not written to dt_rig/: they are no projection of the transfer
    for (int64_t i = 0; i < k; ++i) {
      const torch::Tensor w = start.weights[i].contiguous();
      meshes.push_back(rig.evaluate(Eigen::Map<const Eigen::VectorXd>(w.data_ptr<double>(), w.numel())));
    }
    start.features = avatar_features(dr, avatar.vertex_count(), meshes);
  } else if (options.initial == "champions") {
    if (!avatar.weights.defined())
      throw Error(avatar_dataset, "has no rig weights; starting from champions needs them");
    RoundStarts decided = options.round_starts({in.names, in.human, avatar, rig});
    start.weights = std::move(decided.weights);
    start.features = std::move(decided.features);
    start.evidence_comparisons = decided.evidence_comparisons;
  }
  return start;
}

// Each group's members: the exact nearest avatar samples in raw DR space, then the spread
// members, then the proposals (new rig expressions around the start, ids n + i * m + j).
struct Groups {
  Nearest nearest;                  // [K, group_size] ids and distances
  torch::Tensor proposal_weights;   // [K, M, C] float64 (M = proposals.count > 0)
  torch::Tensor proposal_features;  // [K, M, Va, 9] float32
};

Groups find_groups(const BuildInputs& in, const Start& start, const CorrespondenceOptions& options,
                   const DrFeatures& dr, const std::string& avatar_dataset) {
  const Dataset& avatar = in.avatar;
  const auto k = static_cast<int64_t>(in.names.size());
  const int64_t n = avatar.sample_count(), width = static_cast<int64_t>(avatar.vertex_count()) * kDrWidth;
  const int64_t m = options.proposals.count;
  const int64_t near = options.group_size - options.spread - m;
  const torch::Tensor queries = start.features.reshape({k, width});
  Groups g;
  g.nearest = nearest_rows(queries, avatar.features.reshape({n, width}), near);
  if (options.spread > 0) {
    if (!avatar.weights.defined())
      throw Error("correspond.spread", avatar_dataset + " has no rig weights to choose varied members by");
    Nearest full;
    full.groups = torch::cat({g.nearest.groups, torch::zeros({k, options.spread}, torch::kInt64)}, 1);
    full.distances = torch::cat({g.nearest.distances, torch::zeros({k, options.spread}, torch::kFloat32)}, 1);
    spread_groups(full, queries, avatar.features.reshape({n, width}), avatar.weights, near, avatar_dataset);
    g.nearest = std::move(full);
  }
  if (m > 0) {
    g.proposal_weights =
        start.pairs.defined() ? start.pairs : propose_rig_weights(start.rig, start.weights, options.proposals);
    std::vector<Positions> meshes;
    meshes.reserve(static_cast<size_t>(k * m));
    for (int64_t i = 0; i < k; ++i)
      for (int64_t j = 0; j < m; ++j) {
        const torch::Tensor w = g.proposal_weights[i][j].contiguous();
        meshes.push_back(start.rig.evaluate(Eigen::Map<const Eigen::VectorXd>(w.data_ptr<double>(), w.numel())));
      }
    g.proposal_features =
        avatar_features(dr, avatar.vertex_count(), meshes).reshape({k, m, avatar.vertex_count(), kDrWidth});
    const torch::Tensor ids = n + torch::arange(k * m, torch::kInt64).reshape({k, m});
    const torch::Tensor gaps = (g.proposal_features.reshape({k, m, width}).to(torch::kFloat64) -
                                start.features.reshape({k, 1, width}).to(torch::kFloat64))
                                   .norm(2, 2)
                                   .to(torch::kFloat32);
    g.nearest.groups = torch::cat({g.nearest.groups, ids}, 1).contiguous();
    g.nearest.distances = torch::cat({g.nearest.distances, gaps}, 1).contiguous();
  }
  return g;
}

// The encoder means of every group member, [K, group_size, latent]: each dataset sample
// encoded once, then the proposals.
torch::Tensor group_member_codes(BuildInputs& in, const Groups& g, const CorrespondenceOptions& options,
                                 int64_t latent) {
  const auto k = static_cast<int64_t>(in.names.size());
  const int64_t m = options.proposals.count;
  const int64_t dataset_members = options.group_size - m;
  torch::Tensor codes;
  if (dataset_members > 0) {
    const torch::Tensor members = g.nearest.groups.slice(1, 0, dataset_members);
    const auto [unique_ids, inverse] = torch::_unique(members.flatten(), /*sorted=*/true, /*return_inverse=*/true);
    const torch::Tensor unique_codes =
        encoder_means(in.trained, in.avatar.features.index_select(0, unique_ids), /*clamp_to_range=*/true);
    codes = unique_codes.index_select(0, inverse).reshape({k, dataset_members, latent});
  }
  if (m > 0) {
    const torch::Tensor proposed =
        encoder_means(in.trained, g.proposal_features.reshape({k * m, in.avatar.vertex_count(), kDrWidth}),
                      /*clamp_to_range=*/true)
            .reshape({k, m, latent});
    codes = codes.defined() ? torch::cat({codes, proposed}, 1) : proposed;
  }
  return codes.contiguous();
}

// Meshes and tensors first, the manifest last.
void write_correspondences(const Correspondences& c, const BuildInputs& in, const Transferred& dt, const Start& start) {
  clear_output_folder(c.folder);
  const fs::path dir(c.folder);
  for (size_t i = 0; i < in.names.size(); ++i) {
    write_mesh((dir / kReference / (in.names[i] + ".obj")).string(), with_positions(in.human.rest, dt.references[i]));
    write_mesh((dir / kTransferred / (in.names[i] + ".obj")).string(), with_positions(in.avatar.rest, dt.meshes[i]));
    if (!start.projected.empty())
      write_mesh((dir / kProjected / (in.names[i] + ".obj")).string(),
                 with_positions(in.avatar.rest, start.projected[i]));
  }
  TensorMap tensors = {{"y0", c.y0},
                       {"dt_features", c.dt_features},
                       {"groups", c.groups},
                       {"distances", c.distances},
                       {"group_codes", c.group_codes}};
  if (c.initial_weights.defined()) {
    tensors.emplace("initial_weights", c.initial_weights);
    tensors.emplace("initial_features", c.initial_features);
  }
  if (c.proposals.count > 0) {
    tensors.emplace("proposal_weights", c.proposal_weights);
    tensors.emplace("proposal_features", c.proposal_features);
  }
  save_tensors((dir / kTensors).string(), tensors);
}

}  // namespace

Correspondences build_correspondences(const std::string& human_dataset, const std::string& avatar_dataset,
                                      const std::string& avatar_vae_run, const std::string& out_folder,
                                      const CorrespondenceOptions& given, CorrespondenceReport* report) {
  given.validate();
  CorrespondenceOptions options = given;
  if (options.informative) options.proposals.count = 2;  // the belief search's pair
  check_output_folder(out_folder, options.force);
  const Stopwatch total;
  Stopwatch clock;
  CorrespondenceReport r;

  BuildInputs in = load_build_inputs(human_dataset, avatar_dataset, avatar_vae_run, options);
  const Dataset& avatar = in.avatar;
  r.landmark_pairs = static_cast<int>(in.pairs.size());
  r.load_seconds = clock.restart();
  const auto k = static_cast<int64_t>(in.selected.size());
  say(options, "correspond: {} expressions, {} landmark pairs, {} avatar samples; inputs read in {:.2f} s", k,
      in.pairs.size(), avatar.sample_count(), r.load_seconds);

  const DrFeatures dr(avatar.rest, avatar.dr);
  const Transferred dt = transfer_references(in, options, dr, r, clock);
  r.transfer = dt.report;
  const Start start = start_points(in, dt, options, dr, avatar_dataset);
  r.transfer_seconds = clock.restart();
  say(options,
      "correspond: deformation transfer fit mean {:.4g}, max {:.4g} (avatar units), {} triangle pairs; {:.2f} s",
      r.transfer.mean_distance, r.transfer.max_distance, r.transfer.triangle_pairs, r.transfer_seconds);

  const Groups groups = find_groups(in, start, options, dr, avatar_dataset);
  r.search_seconds = clock.restart();

  const torch::Tensor y0 = encoder_means(in.trained, start.features, /*clamp_to_range=*/true);
  const int64_t latent = y0.size(1);
  const torch::Tensor group_codes = group_member_codes(in, groups, options, latent);
  r.encode_seconds = clock.restart();

  Correspondences c;
  c.folder = out_folder;
  c.created = utc_timestamp();
  c.group_size = options.group_size;
  c.human_dataset = absolute_path(human_dataset);
  c.human_name = in.human.name;
  c.human_fingerprint = in.human.fingerprint;
  c.avatar_dataset = absolute_path(avatar_dataset);
  c.avatar_name = avatar.name;
  c.avatar_fingerprint = avatar.fingerprint;
  c.avatar_vae_run = absolute_path(avatar_vae_run);
  c.avatar_vae_checkpoint = options.checkpoint;
  c.expressions = in.names;
  c.landmarks = dt.landmarks;
  c.initial = options.initial;
  c.around = options.around.empty() ? "" : absolute_path(options.around);
  c.start_table = options.start_table.empty() ? "" : absolute_path(options.start_table);
  c.spread = options.spread;
  c.avatar_samples = avatar.sample_count();
  c.proposals = options.proposals;
  c.informative = options.informative;
  for (const std::string& e : options.evidence) c.evidence.push_back(absolute_path(e));
  c.evidence_comparisons = start.evidence_comparisons;
  c.proposal_weights = groups.proposal_weights;
  c.proposal_features = groups.proposal_features;
  c.y0 = y0;
  c.dt_features = dt.features;
  c.groups = groups.nearest.groups;
  c.distances = groups.nearest.distances;
  c.group_codes = group_codes;
  if (start.weights.defined()) {
    c.initial_weights = start.weights;
    c.initial_features = start.features;
  }
  write_correspondences(c, in, dt, start);
  write_manifest(c, avatar.vertex_count(), avatar.sample_count(), latent, in.pairs, options.transfer, r.transfer,
                 r.transfer_seconds);
  r.write_seconds = clock.restart();
  r.seconds = total.seconds();
  say(options, "correspond: {} groups of {} written to {} in {:.2f} s", k, options.group_size, out_folder, r.seconds);
  if (report) *report = r;
  return c;
}

// ---- Reading

namespace {

const torch::Tensor& expect_tensor(const TensorMap& tensors, const std::string& name, const std::string& file,
                                   torch::ScalarType dtype, const std::vector<int64_t>& shape) {
  const torch::Tensor& t = tensor_named(tensors, name, file);
  if (t.scalar_type() != dtype || t.sizes() != c10::IntArrayRef(shape))
    throw Error(file, "tensor \"" + name + "\" is " + std::string(c10::toString(t.scalar_type())) + " " +
                          c10::str(t.sizes()) + " but " + kManifest + " calls for " + c10::toString(dtype) + " " +
                          c10::str(c10::IntArrayRef(shape)));
  return t;
}

}  // namespace

Correspondences load_correspondences(const std::string& folder) {
  const fs::path dir(folder);
  const std::string manifest_path = (dir / kManifest).string();
  if (!fs::is_regular_file(manifest_path))
    throw Error(folder, fs::is_directory(folder)
                            ? "not a correspondence folder (no correspondences.yaml); build one with "
                              "`retarget correspond`"
                            : "correspondence folder not found");
  const ConfigNode m = ConfigNode::load_file(manifest_path);
  m.reject_unknown_keys({"format", "format_version", "software_version", "created", "group_size", "latent", "human",
                         "avatar", "avatar_vae", "landmarks", "expressions", "initial", "around", "start_table",
                         "spread", "proposals", "informative", "deformation_transfer", "files"});
  const std::string format = m.child("format").as<std::string>();
  if (format != kCorrespondenceFormat)
    m.child("format").fail("expected \"" + std::string(kCorrespondenceFormat) + "\", got \"" + format + "\"");
  const int version = m.child("format_version").as<int>();
  if (version != kCorrespondenceFormatVersion)
    m.child("format_version")
        .fail(fmt::format("format version {} but this build reads version {}; rebuild with `retarget correspond`",
                          version, kCorrespondenceFormatVersion));
  Correspondences c;
  c.folder = folder;
  m.get("created", c.created);
  m.get_required("group_size", c.group_size);
  if (c.group_size < 2) m.child("group_size").fail("expected at least 2");
  const int64_t latent = m.child("latent").as<int64_t>();
  if (latent < 1) m.child("latent").fail("expected a positive latent size");
  const ConfigNode human = m.child("human");
  human.get_required("folder", c.human_dataset);
  human.get_required("name", c.human_name);
  human.get_required("fingerprint", c.human_fingerprint);
  const ConfigNode avatar = m.child("avatar");
  avatar.get_required("folder", c.avatar_dataset);
  avatar.get_required("name", c.avatar_name);
  avatar.get_required("fingerprint", c.avatar_fingerprint);
  const int64_t vertices = avatar.child("vertex_count").as<int64_t>();
  const int64_t samples = avatar.child("sample_count").as<int64_t>();
  if (samples < 1) avatar.child("sample_count").fail("expected a positive sample count");
  c.avatar_samples = samples;
  const ConfigNode run = m.child("avatar_vae");
  run.get_required("folder", c.avatar_vae_run);
  run.get_required("checkpoint", c.avatar_vae_checkpoint);
  m.get("initial", c.initial);
  if (c.initial != "rig" && c.initial != "dt" && c.initial != "champions" && c.initial != "table")
    m.child("initial").fail("expected 'rig', 'dt', 'champions' or 'table', got '" + c.initial + "'");
  m.get("around", c.around);
  m.get("start_table", c.start_table);
  if (c.initial == "champions" && c.around.empty())
    m.fail("initial 'champions' without the annotation project they came from ('around')");
  m.get("spread", c.spread);
  if (c.spread < 0) m.child("spread").fail("expected 0 or more");
  if (m.has("proposals")) {
    const ConfigNode proposals = m.child("proposals");
    proposals.reject_unknown_keys({"count", "sigma", "controllers", "seed"});
    proposals.get_required("count", c.proposals.count);
    proposals.get("sigma", c.proposals.sigma);
    proposals.get("controllers", c.proposals.controllers);
    int64_t seed = static_cast<int64_t>(c.proposals.seed);
    proposals.get("seed", seed);
    if (seed < 0) proposals.child("seed").fail("expected a seed of 0 or more");
    c.proposals.seed = static_cast<uint64_t>(seed);
    try {
      c.proposals.validate("proposals");
    } catch (const Error& e) {
      proposals.fail(e.what());
    }
    if (c.initial == "dt" && c.proposals.count > 0)
      proposals.fail("proposals need a start on the rig, but 'initial' is 'dt'");
  }
  if (m.has("informative")) {
    const ConfigNode informative = m.child("informative");
    informative.reject_unknown_keys({"evidence", "comparisons"});
    c.informative = true;
    informative.get("evidence", c.evidence);
    informative.get("comparisons", c.evidence_comparisons);
    if (c.proposals.count != 2) informative.fail("the belief search's pairs need 'proposals' with a count of 2");
  }
  c.expressions = m.child("expressions").as<std::vector<std::string>>();
  if (c.expressions.empty()) m.child("expressions").fail("no expressions");
  const ConfigNode marks = m.child("landmarks");
  if (!marks.is_map()) marks.fail("expected a map of name: [human vertex, avatar vertex]");
  for (const auto& entry : marks.yaml()) {
    const ConfigNode pair = marks.child(entry.first.as<std::string>());
    const std::vector<int64_t> v = pair.as<std::vector<int64_t>>();
    if (v.size() != 2 || v[0] < 0 || v[1] < 0 || v[1] >= vertices)
      pair.fail(fmt::format("expected [human vertex, avatar vertex] with the avatar vertex in 0..{}", vertices - 1));
    c.landmarks.push_back({static_cast<int>(v[0]), static_cast<int>(v[1])});
  }
  if (c.landmarks.size() < 3) marks.fail("deformation transfer needs at least 3 landmark pairs");
  std::set<std::string> unique(c.expressions.begin(), c.expressions.end());
  if (unique.size() != c.expressions.size()) m.child("expressions").fail("an expression is listed twice");

  const std::string tensors_path = (dir / kTensors).string();
  const TensorMap t = load_tensors(tensors_path);
  const int64_t k = c.expression_count(), p = c.group_size;
  c.y0 = expect_tensor(t, "y0", tensors_path, torch::kFloat32, {k, latent});
  c.dt_features = expect_tensor(t, "dt_features", tensors_path, torch::kFloat32, {k, vertices, kDrWidth});
  c.groups = expect_tensor(t, "groups", tensors_path, torch::kInt64, {k, p});
  c.distances = expect_tensor(t, "distances", tensors_path, torch::kFloat32, {k, p});
  c.group_codes = expect_tensor(t, "group_codes", tensors_path, torch::kFloat32, {k, p, latent});
  if (c.initial != "dt") {
    const torch::Tensor& w = tensor_named(t, "initial_weights", tensors_path);
    if (w.dim() != 2 || w.size(0) != k || w.scalar_type() != torch::kFloat64)
      throw Error(tensors_path, "tensor \"initial_weights\" is not float64 [" + std::to_string(k) + ", C]");
    c.initial_weights = w;
    c.initial_features = expect_tensor(t, "initial_features", tensors_path, torch::kFloat32, {k, vertices, kDrWidth});
  }
  const int64_t proposals = c.proposals.count;
  if (proposals > 0) {
    const int64_t controllers = c.initial_weights.size(1);
    c.proposal_weights =
        expect_tensor(t, "proposal_weights", tensors_path, torch::kFloat64, {k, proposals, controllers});
    c.proposal_features =
        expect_tensor(t, "proposal_features", tensors_path, torch::kFloat32, {k, proposals, vertices, kDrWidth});
  }
  if (c.groups.numel() > 0 &&
      (c.groups.min().item<int64_t>() < 0 || c.groups.max().item<int64_t>() >= c.candidate_count()))
    throw Error(tensors_path, fmt::format("tensor \"groups\" holds sample indices outside 0..{} (the avatar dataset's "
                                          "{} samples and {} proposals)",
                                          c.candidate_count() - 1, samples, c.candidate_count() - samples));
  if (!torch::isfinite(c.distances).all().item<bool>() || !torch::isfinite(c.y0).all().item<bool>() ||
      !torch::isfinite(c.group_codes).all().item<bool>() ||
      (proposals > 0 && !(torch::isfinite(c.proposal_weights).all().item<bool>() &&
                          torch::isfinite(c.proposal_features).all().item<bool>())))
    throw Error(tensors_path, "holds NaN or infinite values");
  return c;
}

void check_correspondences(const Correspondences& c, const Dataset& human, const Dataset& avatar) {
  if (human.fingerprint != c.human_fingerprint || human.name != c.human_name)
    throw Error(human.folder,
                fmt::format("the human dataset \"{}\" (topology {}) is not the one the correspondences in "
                            "{} were built from: \"{}\" (topology {})",
                            human.name, human.fingerprint, c.folder, c.human_name, c.human_fingerprint));
  if (avatar.fingerprint != c.avatar_fingerprint || avatar.name != c.avatar_name)
    throw Error(avatar.folder,
                fmt::format("the avatar dataset \"{}\" (topology {}) is not the one the correspondences in {} were "
                            "built from: \"{}\" (topology {})",
                            avatar.name, avatar.fingerprint, c.folder, c.avatar_name, c.avatar_fingerprint));
  if (c.proposals.count > 0 && avatar.sample_count() != c.avatar_samples)
    throw Error(avatar.folder, fmt::format("has {} samples, but the correspondences in {} were built on {} (their "
                                           "proposals are numbered after them)",
                                           avatar.sample_count(), c.folder, c.avatar_samples));
  if (c.proposals.count == 0 && c.groups.defined() && c.groups.numel() > 0 &&
      c.groups.max().item<int64_t>() >= avatar.sample_count())
    throw Error(avatar.folder, fmt::format("has {} samples, but the correspondences in {} use sample {}",
                                           avatar.sample_count(), c.folder, c.groups.max().item<int64_t>()));
}

namespace {

// Where a candidate id points: dataset sample `sample`, or proposal `j` of expression `k`.
struct CandidateSlot {
  int64_t sample = -1, k = -1, j = -1;
};

CandidateSlot candidate_slot(const Correspondences& c, const Dataset& avatar, int64_t id) {
  if (id >= 0 && id < c.avatar_samples && id < avatar.sample_count()) return {id, -1, -1};
  const int64_t m = c.proposals.count;
  if (m > 0 && id >= c.avatar_samples && id < c.candidate_count())
    return {-1, (id - c.avatar_samples) / m, (id - c.avatar_samples) % m};
  throw Error(c.folder, fmt::format("has no candidate {} (the avatar dataset's {} samples and {} proposals)", id,
                                    c.avatar_samples, c.candidate_count() - c.avatar_samples));
}

}  // namespace

torch::Tensor Correspondences::candidate_features(const Dataset& avatar, int64_t id) const {
  const CandidateSlot slot = candidate_slot(*this, avatar, id);
  if (slot.sample >= 0) return avatar.features[slot.sample].to(torch::kFloat32);
  return proposal_features[slot.k][slot.j];
}

torch::Tensor Correspondences::candidate_weights(const Dataset& avatar, int64_t id) const {
  const CandidateSlot slot = candidate_slot(*this, avatar, id);
  if (slot.sample < 0) return proposal_weights[slot.k][slot.j];
  if (!avatar.weights.defined()) throw Error(avatar.folder, "has no rig weights");
  return avatar.weights[slot.sample].to(torch::kFloat64);
}

}  // namespace retarget
