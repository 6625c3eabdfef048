// `retarget eval vae` on an avatar dataset of a glTF file whose chosen mesh is not the loader's
// default: the rig is reloaded with the meshes the dataset recorded (data/dataset.h).
#include <catch2/catch.hpp>
#include <filesystem>

#include "data/dataset.h"
#include "eval/vae_evaluation.h"
#include "gltf_avatar_file.h"
#include "test_support.h"
#include "train/vae_run.h"

using namespace retarget;

TEST_CASE("eval vae reloads a glTF avatar's rig with the mesh the dataset was built from", "[vae_evaluation][gltf]") {
  const std::filesystem::path dir = test::scratch_dir("vae_evaluation_gltf");
  const std::string gltf = test::write_test_gltf_avatar(dir / "avatar.gltf");
  AvatarDatasetOptions options;
  options.mesh_name = "Face";  // Body, with more morph targets, is what a plain load_rig(gltf) reads
  options.samples = 12;
  options.test_fraction = 0.25;
  options.progress = nullptr;
  build_avatar_dataset(gltf, (dir / "data").string(), options);
  const Dataset d = load_dataset((dir / "data").string());

  MeshVaeOptions model(d.vertex_count());
  model.channels({9, 4, 1}).hidden(8).latent(2).order(2);
  torch::manual_seed(1);
  MeshVae vae = build_mesh_vae(d.rest, model);
  const VaeEvaluation r = evaluate_vae(*vae, d);
  CHECK(r.ground_truth == "rig meshes");
  CHECK(r.footprint == "rig controllers");
  CHECK(r.unit == "mm");

  // Without the record the file's default mesh is read, which is not this avatar.
  Dataset unrecorded = d;
  unrecorded.gltf_meshes.clear();
  const VaeEvaluation fallback = evaluate_vae(*vae, unrecorded);
  CHECK(fallback.ground_truth != "rig meshes");
  CHECK(fallback.footprint == "ground-truth meshes");
}
