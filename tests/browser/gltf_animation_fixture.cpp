// Writes the tiny animation of tests/tiny_animation.h for the glTF checks in node
// (gltf_validator_test.mjs, gltf_three_browser_test.mjs):
//   gltf_animation_fixture FOLDER [FPS]   (FPS default 24)
//     FOLDER/anim.glb, FOLDER/anim.gltf   the animation (infer/gltf_animation.h), in metres
//     FOLDER/rig/                         the same rig as a folder (rig.yaml, cm)
//     FOLDER/weights.csv                  its weights as retarget-infer --weights writes them
//     FOLDER/expected.json                {fps, controllers, times, weights: [F][C]}
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/atomic_file.h"
#include "core/error.h"
#include "geometry/rig.h"
#include "infer/gltf_animation.h"
#include "tiny_animation.h"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  using namespace retarget;
  if (argc != 2 && argc != 3) {
    std::cerr << "usage: gltf_animation_fixture FOLDER [FPS]\n";
    return 2;
  }
  try {
    const fs::path folder = fs::absolute(argv[1]);
    fs::remove_all(folder);
    fs::create_directories(folder);
    const GltfAnimationInput in = test::tiny_animation(9);
    GltfAnimationOptions options;
    options.fps = argc == 3 ? std::stod(argv[2]) : 24;
    for (const char* name : {"anim.glb", "anim.gltf"}) write_gltf_animation(in, options, (folder / name).string());

    Rig rig;
    rig.name = "tiny";
    rig.units = in.units;
    rig.neutral = in.neutral;
    for (size_t c = 0; c < in.controllers.size(); ++c) rig.controllers.push_back({in.controllers[c], in.offsets[c]});
    write_rig_folder((folder / "rig").string(), rig);

    nlohmann::json expected = {{"fps", options.fps}, {"controllers", in.controllers}};
    write_file_atomically((folder / "weights.csv").string(), [&](std::ostream& out) {
      out << "frame";
      for (const std::string& name : in.controllers) out << ',' << name;
      out << ",residual_mm\n";
      for (size_t f = 0; f < in.weights.size(); ++f) {
        out << fmt::format("take_{:04d}", f);
        std::vector<double> row;
        for (Eigen::Index k = 0; k < in.weights[f].size(); ++k) {
          out << fmt::format(",{}", in.weights[f](k));
          row.push_back(in.weights[f](k));
        }
        out << ",0.0\n";
        expected["times"].push_back(static_cast<double>(f) / options.fps);
        expected["weights"].push_back(row);
      }
    });
    write_file_atomically((folder / "expected.json").string(),
                          [&](std::ostream& out) { out << expected.dump(1) << "\n"; });
    std::cout << folder.string() << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "gltf_animation_fixture: " << e.what() << "\n";
    return 1;
  }
}
