// retarget-infer --animation: the frames' human | avatar pictures as one animation.
#include <stb/stb_image.h>
#include <sys/wait.h>

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/log.h"
#include "infer/infer_run.h"
#include "render/animation.h"
#include "tests/infer/infer_test_support.h"

namespace retarget::test {

namespace animation_run_test {

namespace fs = std::filesystem;

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

uint32_t be32_at(const std::string& s, size_t at) {
  return (uint32_t(uint8_t(s[at])) << 24) | (uint32_t(uint8_t(s[at + 1])) << 16) | (uint32_t(uint8_t(s[at + 2])) << 8) |
         uint32_t(uint8_t(s[at + 3]));
}

// An APNG's frame count (acTL) and its fcTL chunks.
struct ApngCounts {
  int actl_frames = -1, fctl = 0;
};

ApngCounts apng_counts(const std::string& png) {
  ApngCounts c;
  REQUIRE(png.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0);
  for (size_t at = 8; at + 12 <= png.size();) {
    const uint32_t length = be32_at(png, at);
    const std::string type = png.substr(at + 4, 4);
    if (type == "acTL") c.actl_frames = static_cast<int>(be32_at(png, at + 8));
    if (type == "fcTL") ++c.fctl;
    at += 12 + length;
  }
  return c;
}

// A tiny rig bundle and frames 1..5 of a take, with one unreadable file among them.
struct AnimationScene {
  fs::path dir;
  std::string bundle;
  std::vector<std::string> frames;
  explicit AnimationScene(const std::string& name)
      : dir(scratch_dir(name)), bundle(tiny_rig_bundle(dir / "bundle")), frames(write_frames(dir / "take", {1, 2, 3})) {
    std::ofstream(dir / "take" / "frame_4.obj") << "not a mesh\n";
    for (const std::string& f : write_frames(dir / "take", {5, 6})) frames.push_back(f);
  }
  InferOptions options(const std::string& animation) const {
    InferOptions o;
    o.bundle = bundle;
    o.inputs = {(dir / "take").string()};
    o.out = (dir / "out").string();
    o.animation = animation.empty() ? "" : (dir / animation).string();
    o.batch = 2;  // frames across batches
    o.progress = nullptr;
    return o;
  }
};

struct QuietAnimationLog {
  log::Level previous = log::level();
  QuietAnimationLog() { log::set_level(log::Level::off); }
  ~QuietAnimationLog() { log::set_level(previous); }
};

}  // namespace animation_run_test

TEST_CASE("run_inference --animation: one frame per input written, as APNG, GIF and MP4", "[infer_run][animation]") {
  using namespace animation_run_test;
  const QuietAnimationLog quiet;
  const AnimationScene scene("infer_animation");

  SECTION("APNG: acTL and fcTL count the frames; the first is a PNG of the side-by-side picture") {
    InferOptions options = scene.options("take.png");
    options.fps = 12;
    const InferSummary summary = run_inference(options);
    CHECK(summary.done == 5);
    CHECK(summary.failed() == 1);  // frame_4.obj
    CHECK(summary.animation == options.animation);
    CHECK(summary.animation_frames == 5);
    CHECK(summary.seconds.render > 0);
    CHECK_THAT(format_summary(summary),
               Catch::Contains("animation: " + options.animation + " (5 frames, APNG at 12 fps)"));
    const std::string png = bytes_of(options.animation);
    const ApngCounts counts = apng_counts(png);
    CHECK(counts.actl_frames == 5);
    CHECK(counts.fctl == 5);
    int w = 0, h = 0, c = 0;
    stbi_uc* pixels = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(png.data()), static_cast<int>(png.size()),
                                            &w, &h, &c, 3);
    REQUIRE(pixels != nullptr);
    CHECK(w == 2 * 384);   // human | avatar, 384 pixels each
    CHECK(h == 384 + 32);  // and the caption band
    stbi_image_free(pixels);
    // No per-frame pictures without --render: the animation is its own option.
    CHECK_FALSE(fs::exists(scene.dir / "out" / "frame_1.png"));
  }

  SECTION("GIF: every frame decodes, at the picture's size") {
    const InferOptions options = scene.options("take.gif");
    const InferSummary summary = run_inference(options);
    CHECK(summary.animation_frames == 5);
    const std::string gif = bytes_of(options.animation);
    int* delays = nullptr;
    int w = 0, h = 0, z = 0, c = 0;
    stbi_uc* pixels = stbi_load_gif_from_memory(reinterpret_cast<const stbi_uc*>(gif.data()),
                                                static_cast<int>(gif.size()), &delays, &w, &h, &z, &c, 3);
    REQUIRE(pixels != nullptr);
    CHECK(z == 5);
    CHECK(w == 768);
    CHECK(h == 416);
    stbi_image_free(pixels);
    std::free(delays);
  }

  SECTION("MP4 through ffmpeg (scripts/setup.sh installs it): ffprobe counts the frames") {
    INFO("ffmpeg and ffprobe come from Debian's ffmpeg package: apt-get install ffmpeg (scripts/setup.sh)");
    REQUIRE_FALSE(find_program("ffprobe").empty());
    const InferOptions options = scene.options("take.mp4");
    const InferSummary summary = run_inference(options);
    CHECK(summary.animation_frames == 5);
    const std::string probe = (scene.dir / "probe.txt").string();
    const std::string command =
        "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
        "stream=nb_read_frames,width,height -of csv=p=0 '" +
        options.animation + "' > '" + probe + "' 2>&1";
    const int rc = std::system(command.c_str());
    std::string text = bytes_of(probe);
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    INFO(text);
    REQUIRE(rc == 0);
    CHECK(text == "768,416,5");
  }
}

TEST_CASE("run_inference --animation: a bad file name or frame rate stops before any work", "[infer_run][animation]") {
  using namespace animation_run_test;
  const fs::path dir = scratch_dir("infer_animation_bad");
  const std::vector<std::string> inputs = write_frames(dir / "in", {1});
  InferOptions options;
  options.bundle = (dir / "no_bundle").string();  // never loaded: the options fail first
  options.inputs = inputs;
  options.out = (dir / "out").string();
  options.progress = nullptr;
  options.animation = (dir / "take.avi").string();
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("--animation") && Catch::Contains(".mp4, .gif"));
  options.animation = (dir / "take.gif").string();
  options.fps = 1000;
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("--fps") && Catch::Contains("0.1 to 240"));
  CHECK_FALSE(fs::exists(dir / "out"));
  CHECK_FALSE(fs::exists(dir / "take.gif"));
}

TEST_CASE("retarget-infer --animation --fps: the summary names the file", "[infer_run][animation][cli]") {
  using namespace animation_run_test;
  const QuietAnimationLog quiet;
  const fs::path dir = scratch_dir("infer_animation_cli");
  const std::string bundle = tiny_bundle(dir / "bundle");
  write_frames(dir / "in", {1, 2});
  const std::string gif = (dir / "take.gif").string(), log = (dir / "log.txt").string();
  const std::string command = std::string("'") + RETARGET_INFER_EXE + "' --bundle '" + bundle + "' '" +
                              (dir / "in").string() + "' --out '" + (dir / "out").string() + "' --animation '" + gif +
                              "' --fps 8 > '" + log + "' 2>&1";
  const int rc = std::system(command.c_str());
  const std::string text = bytes_of(log);
  INFO(text);
  CHECK(WIFEXITED(rc));
  CHECK(WEXITSTATUS(rc) == 0);
  CHECK_THAT(text, Catch::Contains("animation: " + gif + " (2 frames, GIF at 8 fps)"));
  CHECK(fs::file_size(gif) > 1000);
}

}  // namespace retarget::test
