#include "data/dataset_preview.h"

#include <catch2/catch.hpp>

#include "core/error.h"
#include "geometry/rig.h"
#include "test_support.h"

using namespace retarget;

namespace {
// A sphere rig whose controllers push one cap outwards each: samples differ visibly.
std::string sphere_rig(const std::filesystem::path& dir) {
  Rig rig;
  rig.name = "ball";
  rig.neutral = test::uv_sphere(12, 16);
  for (int k = 0; k < 3; ++k) {
    Positions offset = Positions::Zero(rig.neutral.vertex_count(), 3);
    for (int v = 0; v < offset.rows(); ++v) {
      const double along = rig.neutral.vertices(v, k);
      if (along > 0.3) offset.row(v) = 0.5 * (along - 0.3) * rig.neutral.vertices.row(v);
    }
    rig.controllers.push_back({"push" + std::to_string(k), offset});
  }
  write_rig_folder((dir / "rig").string(), rig);
  return (dir / "rig").string();
}
}  // namespace

TEST_CASE("an avatar dataset preview rebuilds samples from their features into a captioned grid", "[dataset_preview]") {
  const auto dir = test::scratch_dir("dataset_preview");
  AvatarDatasetOptions options;
  options.samples = 10;
  options.progress = nullptr;
  options.require_eyes = false;  // a ball has none, and a preview needs no millimetres
  build_avatar_dataset(sphere_rig(dir), (dir / "ds").string(), options);
  const Dataset dataset = load_dataset((dir / "ds").string());

  DatasetPreviewOptions preview;
  preview.count = 4;
  preview.size = 64;
  preview.both_views = false;
  const Image image = dataset_preview(dataset, preview);
  // 4 cells in 4 columns, one view each, under a title band, with a caption band per row.
  CHECK(image.width == 4 * 64);
  CHECK(image.height > 64);
  // The middle of every cell shows the ball, not the background.
  const int top = image.height - 64 - text_band_height(2);
  for (int c = 0; c < 4; ++c) {
    const auto* p = image.rgb.data() + 3 * ((top + 32) * image.width + c * 64 + 32);
    const auto* corner = image.rgb.data() + 3 * ((top + 1) * image.width + c * 64 + 1);
    CHECK((p[0] != corner[0] || p[1] != corner[1] || p[2] != corner[2]));
  }
  preview.count = 0;
  CHECK_THROWS_WITH(dataset_preview(dataset, preview), Catch::Contains("preview.count"));
}
