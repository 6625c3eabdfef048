#include "export/bundle_export.h"

#include <torch/script.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "core/config.h"
#include "core/error.h"
#include "core/sha256.h"
#include "core/tensor_io.h"
#include "export/vae_export.h"
#include "geometry/mesh_io.h"
#include "geometry/topology_fingerprint.h"
#include "models/graph_operator.h"
#include "tests/export/export_test_support.h"
#include "tests/export/python_torch.h"
#include "tests/test_support.h"

namespace retarget {
namespace {

namespace fs = std::filesystem;

using test::kExportTolerance;
using test::max_difference;
using test::read_text;
using test::write_text;

// A side with a randomly initialised small VAE (eval mode) and a non-trivial normaliser.
BundleSide random_side(Mesh rest, const std::string& name, int64_t latent) {
  BundleSide side;
  const int64_t v = rest.vertex_count();
  side.vae = MeshVae(mesh_graph_operator(rest), MeshVaeOptions(v).channels({9, 16, 8, 1}).hidden(32).latent(latent));
  side.vae->eval();
  side.normaliser_min = torch::randn({v, 9}) * 0.3;
  side.normaliser_max = side.normaliser_min + 0.05 + torch::rand({v, 9});
  side.rest = std::move(rest);
  side.name = name;
  return side;
}

// A curved open patch of 13 x 15 = 195 vertices and 168 quads, a stand-in for a face.
Mesh human_patch() {
  return quad_grid(12, 14, 2.0, 2.4, [](double x, double y) { return 0.3 * std::exp(-(x - 1) * (x - 1) - y * y); });
}

// Human: the patch (latent 6); avatar: a 222-vertex UV sphere in cm (latent 5).
BundleParts random_parts(const std::string& avatar_name = "ball") {
  BundleParts parts;
  parts.human = random_side(human_patch(), "patch", 6);
  parts.human.dr.weighting = EdgeWeighting::uniform;
  parts.human.dr.normal_weight = 2e-4;
  parts.avatar = random_side(uv_sphere(12, 20), avatar_name, 5);
  parts.avatar.units = "cm";
  parts.translation = TranslationMlp(TranslationMlpOptions().latent_in(6).hidden(20).latent_out(5));
  parts.translation->eval();
  parts.created = "2024-05-01T12:00:00Z";
  return parts;
}

torch::Tensor normalise(const BundleSide& s, const torch::Tensor& x) {
  return 1.8 * (x - s.normaliser_min) / (s.normaliser_max - s.normaliser_min) - 0.9;
}
torch::Tensor denormalise(const BundleSide& s, const torch::Tensor& y) {
  return (y + 0.9) / 1.8 * (s.normaliser_max - s.normaliser_min) + s.normaliser_min;
}

// Raw human features a little beyond the training range, as new input can be.
torch::Tensor raw_features(const BundleSide& s, int64_t batch) {
  return s.normaliser_min +
         (s.normaliser_max - s.normaliser_min) * (torch::rand({batch, s.rest.vertex_count(), 9}) * 1.2 - 0.1);
}

// Replaces the first occurrence of `from` in the file by `to`.
// Rewrites the manifest's SHA-256 of every file still in the folder, so that a test can reach the
// checks behind the checksums (load_bundle refuses a changed file before anything else).
void restamp_checksums(const fs::path& folder) {
  const fs::path manifest = folder / "manifest.yaml";
  if (!fs::exists(manifest)) return;
  std::string text = read_text(manifest);
  for (const char* file : {"bundle.pt", "human_rest.obj", "avatar_rest.obj", "rig.pt"}) {
    const std::string key = std::string("\n  ") + file + ": ";
    const size_t at = text.find(key);
    if (at == std::string::npos || !fs::exists(folder / file)) continue;
    text.replace(at + key.size(), 64, sha256_of_file((folder / file).string()));
  }
  write_text(manifest, text);
}

void edit_text(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = read_text(path);
  const size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  write_text(path, text.replace(at, from.size(), to));
}

TEST_CASE("export_bundle: bundle.pt equals the in-framework composition", "[bundle_export]") {
  torch::manual_seed(21);
  BundleParts parts = random_parts();
  const fs::path dir = test::scratch_dir("bundle_export_equal");
  export_bundle(parts, dir.string());
  for (const char* file : {"manifest.yaml", "bundle.pt", "human_rest.obj", "avatar_rest.obj"}) {
    CHECK(fs::is_regular_file(dir / file));
  }
  for (const auto& entry : fs::directory_iterator(dir)) {
    CHECK(entry.path().filename().string().find(".tmp") == std::string::npos);  // nothing left over
  }

  const LoadedBundle bundle = load_bundle(dir.string());
  torch::jit::Module module = bundle.module;
  CHECK_FALSE(module.is_training());
  const torch::Tensor x = raw_features(parts.human, 5);
  const torch::Tensor z = torch::randn({4, 6}), w = torch::randn({3, 5});
  torch::NoGradGuard no_grad;
  // MeshVae encode mean -> TranslationMlp -> MeshVae decode, with the project's normalisation.
  const torch::Tensor code = parts.human.vae->encode(normalise(parts.human, x)).mean;
  const torch::Tensor translated = parts.translation->forward(code);
  const torch::Tensor expected = denormalise(parts.avatar, parts.avatar.vae->decode(translated));

  const torch::Tensor y = module.forward({x}).toTensor();
  CHECK(y.sizes() == torch::IntArrayRef({5, 222, 9}));
  CHECK(max_difference(y, expected) <= kExportTolerance);
  CHECK(max_difference(module.get_method("encode_human")({x}).toTensor(), code) <= kExportTolerance);
  CHECK(max_difference(module.get_method("translate")({z}).toTensor(), parts.translation->forward(z)) <=
        kExportTolerance);
  CHECK(max_difference(module.get_method("decode_avatar")({w}).toTensor(),
                       denormalise(parts.avatar, parts.avatar.vae->decode(w))) <= kExportTolerance);
  CHECK(max_difference(module.get_method("human_normalise")({x}).toTensor(), normalise(parts.human, x)) <=
        kExportTolerance);
  // A second and third call (the executor optimises after profiling runs) give the same.
  CHECK(max_difference(module.forward({x}).toTensor(), y) == 0.0);
  CHECK(max_difference(module.forward({x}).toTensor(), y) == 0.0);
  {
    c10::InferenceMode inference;
    CHECK(max_difference(module.forward({x}).toTensor(), y) == 0.0);
  }
  // Wrong shapes are caught with a message in the user's terms.
  CHECK_THROWS_WITH(module.forward({torch::zeros({2, 222, 9})}),
                    Catch::Contains("expected x of shape [B, 195, 9]") && Catch::Contains("got [2, 222, 9]"));
  CHECK_THROWS_WITH(module.get_method("translate")({torch::zeros({2, 5})}),
                    Catch::Contains("expected z of shape [B, 6]"));

  // The rest meshes come back as they went in.
  CHECK(bundle.human_rest.vertices == parts.human.rest.vertices);
  CHECK(bundle.avatar_rest.vertices == parts.avatar.rest.vertices);
  CHECK(bundle.avatar_rest.faces.indices == parts.avatar.rest.faces.indices);
  CHECK(bundle.avatar_rest.faces.offsets == parts.avatar.rest.faces.offsets);
}

TEST_CASE("export_bundle: manifest.yaml, attributes and metadata.json describe the bundle", "[bundle_export]") {
  torch::manual_seed(22);
  BundleParts parts = random_parts();
  const fs::path dir = test::scratch_dir("bundle_export_metadata");
  export_bundle(parts, dir.string());

  const BundleMetadata m = load_bundle(dir.string()).metadata;
  CHECK(m.format == "retarget-bundle");
  CHECK(m.format_version == kBundleFormatVersion);
  CHECK(m.software_version == RETARGET_VERSION);
  CHECK(m.created == "2024-05-01T12:00:00Z");
  CHECK(m.features == 9);
  CHECK(m.human.name == "patch");
  CHECK(m.human.vertices == 195);
  CHECK(m.human.faces == 168);
  CHECK(m.human.fingerprint == topology_fingerprint(parts.human.rest));
  CHECK(m.human.latent == 6);
  CHECK(m.human.units.empty());
  CHECK(m.human.dr.weighting == EdgeWeighting::uniform);
  CHECK(m.human.dr.normal_term);
  CHECK(m.human.dr.normal_weight == 2e-4);
  CHECK(m.avatar.name == "ball");
  CHECK(m.avatar.vertices == 222);
  CHECK(m.avatar.faces == parts.avatar.rest.faces.size());
  CHECK(m.avatar.fingerprint == topology_fingerprint(parts.avatar.rest));
  CHECK(m.avatar.latent == 5);
  CHECK(m.avatar.units == "cm");
  CHECK(m.avatar.dr.weighting == EdgeWeighting::cotangent);
  CHECK(m.avatar.dr.normal_weight == 1e-4);
  CHECK(m.translation_hidden == 20);

  // The manifest is plain YAML a person can read.
  const ConfigNode manifest = ConfigNode::load_file((dir / "manifest.yaml").string());
  CHECK(manifest.child("format").as<std::string>() == "retarget-bundle");
  CHECK(manifest.child("avatar").child("vertices").as<int>() == 222);
  CHECK(manifest.child("human").child("dr").child("weighting").as<std::string>() == "uniform");
  CHECK(manifest.child("files").child("module").as<std::string>() == "bundle.pt");
  // parse_bundle_manifest reads the text as load_bundle does (the fuzzer's entry point).
  const std::string text = read_text(dir / "manifest.yaml");
  CHECK(parse_bundle_manifest(text, "manifest.yaml") == m);
  CHECK_THROWS_WITH(parse_bundle_manifest(text + "extra: 1\n", "m.yaml"),
                    Catch::Contains("m.yaml:") && Catch::Contains("extra") && Catch::Contains("unknown key"));
  CHECK_THROWS_WITH(parse_bundle_manifest("format: retarget-bundle\nformat_version: [1]\n", "m.yaml"),
                    Catch::Contains("m.yaml:2: format_version") && Catch::Contains("expected an integer"));

  torch::jit::ExtraFilesMap extra{{"metadata.json", ""}};
  torch::jit::Module module = torch::jit::load((dir / "bundle.pt").string(), torch::kCPU, extra);
  CHECK(parse_bundle_metadata_json(extra["metadata.json"], "bundle.pt") == m);
  const nlohmann::json json = nlohmann::json::parse(extra["metadata.json"]);
  CHECK(json.at("format") == "retarget-bundle");
  CHECK(json.at("avatar").at("units") == "cm");
  CHECK(json.at("human").at("latent") == 6);
  CHECK(module.attr("format").toStringRef() == "retarget-bundle");
  CHECK(module.attr("human_vertices").toInt() == 195);
  CHECK(module.attr("avatar_vertices").toInt() == 222);
  CHECK(module.attr("human_latent").toInt() == 6);
  CHECK(module.attr("avatar_latent").toInt() == 5);
  CHECK(module.attr("avatar_name").toStringRef() == "ball");
  CHECK(module.attr("avatar_fingerprint").toStringRef() == m.avatar.fingerprint);
  CHECK(module.attr("human_dr_weighting").toStringRef() == "uniform");
  CHECK(module.attr("human_dr_normal_weight").toDouble() == 2e-4);
  CHECK(module.attr("avatar_units").toStringRef() == "cm");
  CHECK(torch::equal(module.attr("avatar_normaliser_max").toTensor(), parts.avatar.normaliser_max));

  // Re-exporting replaces the bundle.
  BundleParts renamed = random_parts("ball2");
  export_bundle(renamed, dir.string());
  CHECK(load_bundle(dir.string()).metadata.avatar.name == "ball2");
}

TEST_CASE("load_bundle: missing, broken and mismatched files are named", "[bundle_export]") {
  torch::manual_seed(23);
  const fs::path dir = test::scratch_dir("bundle_export_bad_files");
  const fs::path good = dir / "good", bad = dir / "bad", other = dir / "other";
  export_bundle(random_parts(), good.string());
  export_bundle(random_parts("other"), other.string());
  auto fresh_copy = [&] {
    fs::remove_all(bad);
    fs::copy(good, bad);
  };
  auto load_bad = [&] {
    restamp_checksums(bad);
    return load_bundle(bad.string());
  };

  CHECK_THROWS_WITH(load_bundle((dir / "nowhere").string()), Catch::Contains("nowhere") &&
                                                                 Catch::Contains("no such folder") &&
                                                                 Catch::Contains("manifest.yaml"));
  for (const char* file : {"manifest.yaml", "bundle.pt", "human_rest.obj", "avatar_rest.obj"}) {
    INFO(file);
    fresh_copy();
    fs::remove(bad / file);
    CHECK_THROWS_WITH(load_bad(), Catch::Contains(file) && Catch::Contains("missing file"));
  }

  // The manifest: garbage, another format, a newer version, a missing key.
  fresh_copy();
  write_text(bad / "manifest.yaml", "[unclosed\n");
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("manifest.yaml"));
  write_text(bad / "manifest.yaml", "just some text\n");
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("manifest.yaml") && Catch::Contains("not a retarget bundle manifest"));
  fresh_copy();
  edit_text(bad / "manifest.yaml", "format: retarget-bundle", "format: retarget-dataset");
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("manifest.yaml") && Catch::Contains("not a retarget bundle manifest"));
  fresh_copy();
  edit_text(bad / "manifest.yaml", "format_version: " + std::to_string(kBundleFormatVersion), "format_version: 7");
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("manifest.yaml") && Catch::Contains("newer retarget"));
  fresh_copy();
  edit_text(bad / "manifest.yaml", "latent: 5", "latnet: 5");
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("manifest.yaml") && Catch::Contains("avatar.latnet"));
  fresh_copy();
  edit_text(bad / "manifest.yaml", "vertices: 222", "vertices: lots");
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("manifest.yaml") && Catch::Contains("avatar.vertices"));

  // bundle.pt: truncated, garbage, foreign, from another export.
  fresh_copy();
  const std::string bytes = read_text(good / "bundle.pt");
  write_text(bad / "bundle.pt", bytes.substr(0, bytes.size() / 2));
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("bundle.pt") && Catch::Contains("cannot be read as a TorchScript"));
  write_text(bad / "bundle.pt", "not a model at all\n");
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("bundle.pt") && Catch::Contains("cannot be read as a TorchScript"));
  torch::jit::Module foreign = make_script_module("__torch__.Foreign");
  foreign.define("def forward(self, x: Tensor) -> Tensor:\n    return x\n");
  foreign.save((bad / "bundle.pt").string());
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("bundle.pt") && Catch::Contains("not a retarget bundle"));
  fs::copy_file(other / "bundle.pt", bad / "bundle.pt", fs::copy_options::overwrite_existing);
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("bundle.pt") && Catch::Contains("different exports") &&
                                    Catch::Contains("avatar.name") && Catch::Contains("\"other\"") &&
                                    Catch::Contains("\"ball\""));

  // Rest meshes: another vertex count, the sides swapped, the same count on another topology.
  fresh_copy();
  write_mesh((bad / "avatar_rest.obj").string(), uv_sphere(5, 6));
  CHECK_THROWS_WITH(load_bad(),
                    Catch::Contains("avatar_rest.obj") && Catch::Contains("26 vertices") && Catch::Contains("222"));
  fresh_copy();
  fs::copy_file(good / "avatar_rest.obj", bad / "human_rest.obj", fs::copy_options::overwrite_existing);
  CHECK_THROWS_WITH(load_bad(),
                    Catch::Contains("human_rest.obj") && Catch::Contains("222 vertices") && Catch::Contains("195"));
  fresh_copy();
  Mesh flipped = read_mesh((good / "human_rest.obj").string());  // same counts, one face reversed
  std::reverse(flipped.faces.indices.begin(), flipped.faces.indices.begin() + 4);
  triangulate(flipped);
  write_mesh((bad / "human_rest.obj").string(), flipped);
  CHECK_THROWS_WITH(load_bad(), Catch::Contains("human_rest.obj") && Catch::Contains("fingerprint") &&
                                    Catch::Contains("does not belong"));
}

TEST_CASE("load_bundle: a file changed after export is refused by its checksum, naming it", "[bundle_export]") {
  torch::manual_seed(29);
  const fs::path dir = test::scratch_dir("bundle_export_checksums");
  const fs::path good = dir / "good", bad = dir / "bad";
  export_bundle(random_parts(), good.string());
  const std::string manifest = read_text(good / "manifest.yaml");
  for (const char* file : {"bundle.pt", "human_rest.obj", "avatar_rest.obj"})
    CHECK_THAT(manifest, Catch::Contains(std::string(file) + ": " + sha256_of_file((good / file).string())));
  auto fresh_copy = [&] {
    fs::remove_all(bad);
    fs::copy(good, bad);
  };

  // 50 bytes flipped inside bundle.pt's tensors: LibTorch loads and runs such a file without a
  // word (its zip entries are not verified); the checksum, computed while it loads, refuses it.
  fresh_copy();
  std::string bytes = read_text(bad / "bundle.pt");
  const size_t middle = bytes.size() / 2;
  for (size_t i = 0; i < 50; ++i) bytes[middle + i] = static_cast<char>(~bytes[middle + i]);
  write_text(bad / "bundle.pt", bytes);
  CHECK_THROWS_WITH(load_bundle(bad.string()), Catch::Contains("bundle.pt: its SHA-256 is") &&
                                                   Catch::Contains("manifest.yaml says") &&
                                                   Catch::Contains("damaged or changed after export"));
  // Cut in half, it cannot be loaded at all: the checksum still says what is wrong, not the loader.
  fresh_copy();
  write_text(bad / "bundle.pt", bytes.substr(0, middle));
  CHECK_THROWS_WITH(load_bundle(bad.string()),
                    Catch::Contains("bundle.pt: its SHA-256 is") && Catch::Contains("damaged or changed after export"));
  fresh_copy();
  edit_text(bad / "avatar_rest.obj", "v ", "v  ");
  CHECK_THROWS_WITH(load_bundle(bad.string()), Catch::Contains("avatar_rest.obj: its SHA-256 is"));

  // A manifest of format 2 without a file's checksum, a malformed one, an unknown file.
  fresh_copy();
  const std::string digest = sha256_of_file((good / "human_rest.obj").string());
  edit_text(bad / "manifest.yaml", "  human_rest.obj: " + digest + "\n", "");
  CHECK_THROWS_WITH(load_bundle(bad.string()), Catch::Contains("manifest.yaml") && Catch::Contains("sha256") &&
                                                   Catch::Contains("no SHA-256 of human_rest.obj"));
  fresh_copy();
  edit_text(bad / "manifest.yaml", digest, "12345");
  CHECK_THROWS_WITH(load_bundle(bad.string()),
                    Catch::Contains("sha256.human_rest.obj") && Catch::Contains("expected 64 lowercase hex digits"));
  fresh_copy();
  edit_text(bad / "manifest.yaml", "  human_rest.obj: ", "  notes.txt: ");
  CHECK_THROWS_WITH(load_bundle(bad.string()), Catch::Contains("'notes.txt' is not one of the bundle's files"));
  fresh_copy();
  CHECK_NOTHROW(load_bundle(bad.string()));
}

TEST_CASE("export_bundle rejects inconsistent parts with a message", "[bundle_export]") {
  torch::manual_seed(24);
  const fs::path dir = test::scratch_dir("bundle_export_rejects");
  auto export_with = [&](const BundleParts& parts) { export_bundle(parts, dir.string()); };

  BundleParts parts = random_parts();
  parts.avatar.rest = uv_sphere(5, 6);
  CHECK_THROWS_WITH(export_with(parts),
                    Catch::Contains("bundle.avatar.vae") && Catch::Contains("222") && Catch::Contains("26"));
  parts = random_parts();
  parts.translation = TranslationMlp(TranslationMlpOptions().latent_in(6).latent_out(25));
  CHECK_THROWS_WITH(export_with(parts), Catch::Contains("bundle.translation") && Catch::Contains("6 -> 25") &&
                                            Catch::Contains("avatar VAE's 5"));
  parts = random_parts();
  parts.translation = TranslationMlp(nullptr);
  CHECK_THROWS_WITH(export_with(parts), Catch::Contains("bundle.translation"));
  parts = random_parts();
  parts.human.normaliser_max = parts.human.normaliser_max.narrow(0, 0, 10);
  CHECK_THROWS_WITH(export_with(parts), Catch::Contains("bundle.human.normaliser") && Catch::Contains("[195, 9]"));
  parts = random_parts();
  parts.avatar.normaliser_max[3][2] = parts.avatar.normaliser_min[3][2];
  CHECK_THROWS_WITH(export_with(parts),
                    Catch::Contains("bundle.avatar.normaliser") && Catch::Contains("vertex 3, channel 2"));
  parts = random_parts();
  parts.human.name.clear();
  CHECK_THROWS_WITH(export_with(parts), Catch::Contains("bundle.human.name"));
  parts = random_parts();
  parts.avatar.dr.normal_weight = -1;
  CHECK_THROWS_WITH(export_with(parts), Catch::Contains("bundle.avatar.dr"));
  parts = random_parts();
  parts.human.vae = MeshVae(mesh_graph_operator(parts.human.rest), MeshVaeOptions(195).channels({3, 8, 1}).latent(6));
  CHECK_THROWS_WITH(export_with(parts), Catch::Contains("bundle.human.vae") && Catch::Contains("DR features"));
  CHECK(fs::is_empty(dir));  // nothing written
}

TEST_CASE("export_bundle: Python's torch.jit.load runs bundle.pt", "[bundle_export][python]") {
  const std::string python = test::python_with_torch();
  torch::manual_seed(25);
  BundleParts parts = random_parts();
  const fs::path dir = test::scratch_dir("bundle_export_python");
  export_bundle(parts, (dir / "bundle").string());
  const torch::Tensor x = raw_features(parts.human, 3);
  {
    torch::NoGradGuard no_grad;
    const torch::Tensor code = parts.human.vae->encode(normalise(parts.human, x)).mean;
    const torch::Tensor y = denormalise(parts.avatar, parts.avatar.vae->decode(parts.translation->forward(code)));
    save_tensors((dir / "data.pt").string(), {{"x", x}, {"y", y}});
  }
  write_text(dir / "check.py", R"(import json, sys, torch
folder, data = sys.argv[1], torch.load(sys.argv[2])
extra = {"metadata.json": ""}
bundle = torch.jit.load(folder + "/bundle.pt", _extra_files=extra)
bundle.eval()
metadata = json.loads(extra["metadata.json"])
with torch.no_grad():
    error = (bundle(data["x"]) - data["y"]).abs().max().item()
attributes = (bundle.human_vertices, bundle.avatar_vertices, bundle.avatar_name, metadata["avatar"]["latent"])
print("error", error, "attributes", attributes)
sys.exit(0 if error <= 1e-5 and attributes == (195, 222, "ball", 5) else 1)
)");
  const fs::path log = dir / "check.log";
  const std::string command = python + " '" + (dir / "check.py").string() + "' '" + (dir / "bundle").string() + "' '" +
                              (dir / "data.pt").string() + "' >'" + log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  INFO(read_text(log));
  CHECK(status == 0);
}

TEST_CASE("export_bundle: the avatar's still vertices travel in the manifest and metadata.json", "[bundle_export]") {
  torch::manual_seed(24);
  BundleParts parts = random_parts();
  parts.avatar.still_vertices = {0, 5, 7, 221};
  const fs::path dir = test::scratch_dir("bundle_export_still");
  export_bundle(parts, dir.string());
  const BundleMetadata m = load_bundle(dir.string()).metadata;
  CHECK(m.avatar.still_vertices == std::vector<int64_t>{0, 5, 7, 221});
  CHECK(m.human.still_vertices.empty());
  torch::jit::ExtraFilesMap extra{{"metadata.json", ""}};
  torch::jit::load((dir / "bundle.pt").string(), torch::kCPU, extra);
  CHECK(parse_bundle_metadata_json(extra["metadata.json"], "bundle.pt") == m);

  // A manifest whose list is out of range or out of order is refused, naming the key.
  const fs::path manifest = dir / "manifest.yaml";
  std::ifstream in(manifest);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  const size_t at = text.find("still_vertices: [0, 5, 7, 221]");
  REQUIRE(at != std::string::npos);
  std::string bad = text;
  bad.replace(at, 30, "still_vertices: [0, 5, 7, 222]");
  std::ofstream(manifest) << bad;
  CHECK_THROWS_WITH(load_bundle(dir.string()), Catch::Contains("still_vertices") && Catch::Contains("0..221"));
  bad = text;
  bad.replace(at, 30, "still_vertices: [0, 7, 5, 221]");
  std::ofstream(manifest) << bad;
  CHECK_THROWS_WITH(load_bundle(dir.string()), Catch::Contains("still_vertices") && Catch::Contains("ascending"));
}

// A rig over the avatar's rest mesh: three controllers of random offsets in three ranges.
BundleRig random_rig(const Mesh& avatar_rest) {
  BundleRig part;
  part.rig.name = "ball";
  part.rig.source = "ball/rig.yaml";
  part.rig.neutral = avatar_rest;
  const std::vector<std::tuple<std::string, double, double>> controllers{
      {"jawOpen", 0, 1}, {"brow raise, left", -1, 1}, {"\"squash\"", 0, 2.5}};
  for (const auto& [name, min, max] : controllers) {
    Controller c;
    c.name = name;
    c.min = min;
    c.max = max;
    c.offset = 0.1 * Positions::Random(avatar_rest.vertex_count(), 3);
    c.offset.row(0).setZero();
    part.rig.controllers.push_back(std::move(c));
  }
  part.millimetres_per_unit = 12.5;
  return part;
}

TEST_CASE("export_bundle: the avatar's rig round-trips through rig.pt and the manifest", "[bundle_export]") {
  torch::manual_seed(31);
  BundleParts parts = random_parts();
  parts.rig = random_rig(parts.avatar.rest);
  const fs::path dir = test::scratch_dir("bundle_export_rig");
  export_bundle(parts, dir.string());
  CHECK(fs::is_regular_file(dir / "rig.pt"));
  const std::string manifest = read_text(dir / "manifest.yaml");
  CHECK_THAT(manifest,
             Catch::Contains("rig: rig.pt") && Catch::Contains("rig.pt: " + sha256_of_file((dir / "rig.pt").string())));

  const LoadedBundle bundle = load_bundle(dir.string());
  REQUIRE(bundle.metadata.rig.has_value());
  const BundleRigMetadata& m = *bundle.metadata.rig;
  CHECK(bundle.metadata.format_version == 3);
  CHECK(m.millimetres_per_unit == 12.5);
  REQUIRE(m.controllers.size() == 3);
  REQUIRE(bundle.rig.has_value());
  const Rig& rig = *bundle.rig;
  CHECK(rig.source == (dir / "rig.pt").string());
  CHECK(rig.units == "cm");
  CHECK(rig.neutral.vertices == bundle.avatar_rest.vertices);
  REQUIRE(rig.controller_count() == 3);
  for (int k = 0; k < 3; ++k) {
    const Controller& in = parts.rig->rig.controllers[k];
    INFO(in.name);
    CHECK(m.controllers[k].name == in.name);
    CHECK(m.controllers[k].min == in.min);
    CHECK(m.controllers[k].max == in.max);
    CHECK(rig.controllers[k].name == in.name);
    CHECK(rig.controllers[k].min == in.min);
    CHECK(rig.controllers[k].max == in.max);
    CHECK((rig.controllers[k].offset - in.offset).cwiseAbs().maxCoeff() < 1e-7);  // float32
  }
  // rig.pt is a plain dict of tensors; metadata.json inside bundle.pt says the same as the manifest.
  const TensorMap tensors = load_tensors((dir / "rig.pt").string());
  CHECK(tensors.at("offsets").sizes() == torch::IntArrayRef({3, 222, 3}));
  CHECK(tensors.at("offsets").scalar_type() == torch::kFloat32);
  torch::jit::ExtraFilesMap extra{{"metadata.json", ""}};
  torch::jit::load((dir / "bundle.pt").string(), torch::kCPU, extra);
  CHECK(parse_bundle_metadata_json(extra["metadata.json"], "bundle.pt") == bundle.metadata);
  CHECK(parse_bundle_manifest(manifest, "manifest.yaml") == bundle.metadata);
  BundleMetadata without = bundle.metadata;
  without.rig.reset();
  CHECK(without != bundle.metadata);

  // Re-exporting without a rig removes rig.pt and the manifest's rig.
  export_bundle(random_parts(), dir.string());
  CHECK_FALSE(fs::exists(dir / "rig.pt"));
  const LoadedBundle plain = load_bundle(dir.string());
  CHECK_FALSE(plain.metadata.rig.has_value());
  CHECK_FALSE(plain.rig.has_value());
}

TEST_CASE("load_bundle: a damaged, missing or mismatched rig.pt is refused, naming it", "[bundle_export]") {
  torch::manual_seed(32);
  BundleParts parts = random_parts();
  parts.rig = random_rig(parts.avatar.rest);
  const fs::path dir = test::scratch_dir("bundle_export_rig_bad");
  const fs::path good = dir / "good", bad = dir / "bad";
  export_bundle(parts, good.string());
  auto fresh_copy = [&] {
    fs::remove_all(bad);
    fs::copy(good, bad);
  };

  fresh_copy();
  std::string bytes = read_text(bad / "rig.pt");
  for (size_t i = 0; i < 20; ++i) bytes[bytes.size() / 2 + i] = static_cast<char>(~bytes[bytes.size() / 2 + i]);
  write_text(bad / "rig.pt", bytes);
  CHECK_THROWS_WITH(load_bundle(bad.string()),
                    Catch::Contains("rig.pt: its SHA-256 is") && Catch::Contains("damaged or changed after export"));
  fresh_copy();
  fs::remove(bad / "rig.pt");
  CHECK_THROWS_WITH(load_bundle(bad.string()), Catch::Contains("rig.pt") && Catch::Contains("missing file"));

  // Offsets of another shape (restamped, so that the check behind the checksum is reached).
  fresh_copy();
  save_tensors((bad / "rig.pt").string(), {{"offsets", torch::zeros({2, 222, 3})}});
  restamp_checksums(bad);
  CHECK_THROWS_WITH(load_bundle(bad.string()), Catch::Contains("rig.pt") && Catch::Contains("[3, 222, 3]"));
  save_tensors((bad / "rig.pt").string(), {{"weights", torch::zeros({3, 222, 3})}});
  restamp_checksums(bad);
  CHECK_THROWS_WITH(load_bundle(bad.string()), Catch::Contains("rig.pt") && Catch::Contains("offsets"));

  // The manifest's rig: a bad range, a repeated name, a rig file without a rig.
  CHECK_THROWS_WITH(
      parse_bundle_manifest(
          read_text(good / "manifest.yaml")
              .replace(read_text(good / "manifest.yaml").find("range: [0, 2.5]"), 15, "range: [3, 2.5]"),
          "m.yaml"),
      Catch::Contains("m.yaml:") && Catch::Contains("rig.controllers[2].range") && Catch::Contains("min < max"));
  std::string text = read_text(good / "manifest.yaml");
  text.replace(text.find("name: \"jawOpen\""), 15, "name: \"brow raise, left\"");
  CHECK_THROWS_WITH(parse_bundle_manifest(text, "m.yaml"),
                    Catch::Contains("rig.controllers[1].name") && Catch::Contains("controllers[0] too"));
  export_bundle(random_parts(), bad.string());
  edit_text(bad / "manifest.yaml", "avatar_rest: avatar_rest.obj", "avatar_rest: avatar_rest.obj\n  rig: rig.pt");
  CHECK_THROWS_WITH(load_bundle(bad.string()), Catch::Contains("files.rig") && Catch::Contains("no rig"));
}

TEST_CASE("load_bundle: a format 2 bundle (no rig) still loads", "[bundle_export]") {
  torch::manual_seed(33);
  const fs::path dir = test::scratch_dir("bundle_export_v2");
  export_bundle(random_parts(), dir.string());
  // Written as format 2 was: the same files, format_version 2 in the manifest and metadata.json.
  torch::jit::ExtraFilesMap extra{{"metadata.json", ""}};
  torch::jit::Module module = torch::jit::load((dir / "bundle.pt").string(), torch::kCPU, extra);
  nlohmann::json metadata = nlohmann::json::parse(extra["metadata.json"]);
  REQUIRE_FALSE(metadata.contains("rig"));
  metadata["format_version"] = 2;
  module.save((dir / "bundle.pt").string(), {{"metadata.json", metadata.dump(2)}});
  edit_text(dir / "manifest.yaml", "format_version: 3", "format_version: 2");
  restamp_checksums(dir);
  REQUIRE(read_text(dir / "manifest.yaml").find("rig") == std::string::npos);

  const LoadedBundle bundle = load_bundle(dir.string());
  CHECK(bundle.metadata.format_version == 2);
  CHECK_FALSE(bundle.metadata.rig.has_value());
  CHECK_FALSE(bundle.rig.has_value());
}

TEST_CASE("export_bundle rejects a rig that does not fit the avatar, naming it", "[bundle_export]") {
  torch::manual_seed(34);
  const fs::path dir = test::scratch_dir("bundle_export_rig_rejected");
  BundleParts parts = random_parts();
  auto export_with = [&](const BundleRig& rig) {
    BundleParts p = parts;
    p.rig = rig;
    export_bundle(p, dir.string());
  };
  const BundleRig good = random_rig(parts.avatar.rest);
  BundleRig r = good;
  r.rig.neutral = uv_sphere(5, 6);
  CHECK_THROWS_WITH(export_with(r),
                    Catch::Contains("bundle.rig") && Catch::Contains("26 vertices") && Catch::Contains("222"));
  r = good;
  r.rig.neutral.vertices.array() += 0.5;
  CHECK_THROWS_WITH(export_with(r), Catch::Contains("bundle.rig") && Catch::Contains("not the avatar's rest mesh"));
  r = good;
  r.rig.controllers[2].name = "jawOpen";
  CHECK_THROWS_WITH(export_with(r),
                    Catch::Contains("bundle.rig.controllers[2].name") && Catch::Contains("names controllers[0] too"));
  r = good;
  r.rig.controllers[1].max = -1;
  CHECK_THROWS_WITH(export_with(r), Catch::Contains("bundle.rig.controllers[1].range"));
  r = good;
  r.rig.controllers[0].offset(3, 1) = NAN;
  CHECK_THROWS_WITH(export_with(r), Catch::Contains("bundle.rig.controllers[0]") && Catch::Contains("finite"));
  r = good;
  r.rig.controllers.clear();
  CHECK_THROWS_WITH(export_with(r), Catch::Contains("bundle.rig.controllers") && Catch::Contains("at least one"));
  r = good;
  r.millimetres_per_unit = -2;
  CHECK_THROWS_WITH(export_with(r), Catch::Contains("bundle.rig.millimetres_per_unit"));
  CHECK_FALSE(fs::exists(dir / "manifest.yaml"));  // nothing was written
}

}  // namespace
}  // namespace retarget
