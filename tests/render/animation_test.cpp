#include "render/animation.h"

#include <stb/stb_image.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "scratch.h"

namespace retarget::test {

namespace animation_test {

// Frame k of a little film: a width x height picture in colours that are multiples of 8 (so a
// 256-colour palette holds them exactly), a square moving right by k pixels a frame.
Image film_frame(int width, int height, int k) {
  Image image(width, height, Eigen::Vector3f(0.97f, 0.97f, 0.97f));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      uint8_t* p = image.pixel(x, y);
      p[0] = static_cast<uint8_t>(8 * (x % 32));
      p[1] = static_cast<uint8_t>(8 * (y % 32));
      p[2] = 128;
      if (x >= k && x < k + 8 && y >= 4 && y < 12) p[0] = p[1] = p[2] = 16;
    }
  return image;
}

std::vector<Image> film(int width, int height, int frames) {
  std::vector<Image> out;
  for (int k = 0; k < frames; ++k) out.push_back(film_frame(width, height, k));
  return out;
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

uint32_t be32(const std::string& s, size_t at) {
  return (uint32_t(uint8_t(s[at])) << 24) | (uint32_t(uint8_t(s[at + 1])) << 16) | (uint32_t(uint8_t(s[at + 2])) << 8) |
         uint32_t(uint8_t(s[at + 3]));
}
int be16(const std::string& s, size_t at) { return (uint8_t(s[at]) << 8) | uint8_t(s[at + 1]); }
int le16(const std::string& s, size_t at) { return uint8_t(s[at]) | (uint8_t(s[at + 1]) << 8); }

struct PngChunk {
  std::string type, data;
};

std::vector<PngChunk> png_chunks(const std::string& png) {
  REQUIRE(png.size() >= 8);
  REQUIRE(png.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0);
  std::vector<PngChunk> chunks;
  for (size_t at = 8; at < png.size();) {
    REQUIRE(at + 12 <= png.size());
    const uint32_t length = be32(png, at);
    REQUIRE(at + 12 + length <= png.size());
    chunks.push_back({png.substr(at + 4, 4), png.substr(at + 8, length)});
    at += 12 + length;
  }
  return chunks;
}

std::string png_chunk_bytes(const std::string& type, const std::string& data);

// A plain PNG of one APNG frame: the IHDR and that frame's image data, for stb to decode.
std::string frame_png(const std::vector<PngChunk>& chunks, int frame);

Image decode_png(const std::string& png) {
  int w = 0, h = 0, c = 0;
  stbi_uc* pixels =
      stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(png.data()), static_cast<int>(png.size()), &w, &h, &c, 3);
  REQUIRE(pixels != nullptr);
  Image image;
  image.width = w;
  image.height = h;
  image.rgb.assign(pixels, pixels + 3 * static_cast<size_t>(w) * h);
  stbi_image_free(pixels);
  return image;
}

// What a GIF's blocks say: the screen size, the frames' sizes and delays (centiseconds).
struct GifStructure {
  int width = 0, height = 0;
  bool loops = false;
  std::vector<std::array<int, 2>> frame_sizes;
  std::vector<int> delays;
  bool trailer = false;
};

GifStructure gif_structure(const std::string& gif) {
  GifStructure g;
  REQUIRE(gif.size() > 13);
  REQUIRE(gif.substr(0, 6) == "GIF89a");
  g.width = le16(gif, 6);
  g.height = le16(gif, 8);
  const uint8_t packed = uint8_t(gif[10]);
  size_t at = 13;
  if (packed & 0x80) at += 3 * (size_t(1) << ((packed & 7) + 1));
  auto skip_sub_blocks = [&] {
    while (true) {
      REQUIRE(at < gif.size());
      const uint8_t n = uint8_t(gif[at++]);
      if (n == 0) break;
      at += n;
    }
  };
  while (at < gif.size()) {
    const uint8_t block = uint8_t(gif[at++]);
    if (block == 0x3b) {
      g.trailer = true;
      break;
    }
    if (block == 0x21) {
      const uint8_t label = uint8_t(gif[at++]);
      if (label == 0xf9) g.delays.push_back(le16(gif, at + 2));
      if (label == 0xff && gif.compare(at + 1, 11, "NETSCAPE2.0") == 0) g.loops = true;
      skip_sub_blocks();
      continue;
    }
    REQUIRE(block == 0x2c);
    g.frame_sizes.push_back({le16(gif, at + 4), le16(gif, at + 6)});
    const uint8_t local = uint8_t(gif[at + 8]);
    at += 9;
    if (local & 0x80) at += 3 * (size_t(1) << ((local & 7) + 1));
    ++at;  // LZW minimum code size
    skip_sub_blocks();
  }
  return g;
}

}  // namespace animation_test

std::string animation_test::png_chunk_bytes(const std::string& type, const std::string& data) {
  // CRC-32 as PNG defines it.
  uint32_t crc = 0xffffffffu;
  for (char ch : type + data) {
    crc ^= uint8_t(ch);
    for (int k = 0; k < 8; ++k) crc = (crc & 1) ? 0xedb88320u ^ (crc >> 1) : crc >> 1;
  }
  crc ^= 0xffffffffu;
  std::string out;
  for (uint32_t v : {static_cast<uint32_t>(data.size())})
    for (int s = 24; s >= 0; s -= 8) out += static_cast<char>((v >> s) & 0xff);
  out += type + data;
  for (int s = 24; s >= 0; s -= 8) out += static_cast<char>((crc >> s) & 0xff);
  return out;
}

std::string animation_test::frame_png(const std::vector<PngChunk>& chunks, int frame) {
  std::string png = "\x89PNG\r\n\x1a\n";
  png += png_chunk_bytes("IHDR", chunks.at(0).data);
  int seen = -1;
  for (const PngChunk& c : chunks) {
    if (c.type == "fcTL") ++seen;
    if (seen != frame) continue;
    if (c.type == "IDAT") png += png_chunk_bytes("IDAT", c.data);
    if (c.type == "fdAT") png += png_chunk_bytes("IDAT", c.data.substr(4));
  }
  return png + png_chunk_bytes("IEND", "");
}

TEST_CASE("APNG: acTL, one fcTL per frame at 1/fps, every frame decodes to its picture", "[animation]") {
  using namespace animation_test;
  const std::string path = (scratch_dir("animation_apng") / "film.png").string();
  const std::vector<Image> frames = film(40, 24, 5);
  AnimationOptions options;
  options.fps = 25;
  write_animation(path, frames, options);

  const std::string bytes = file_bytes(path);
  const std::vector<PngChunk> chunks = png_chunks(bytes);
  REQUIRE(chunks.front().type == "IHDR");
  CHECK(chunks.back().type == "IEND");
  REQUIRE(chunks[1].type == "acTL");
  CHECK(be32(chunks[1].data, 0) == 5);  // frames
  CHECK(be32(chunks[1].data, 4) == 0);  // plays forever
  // Every chunk's CRC is right (the patched acTL too): rebuilding each chunk gives the file back.
  std::string rebuilt = "\x89PNG\r\n\x1a\n";
  for (const PngChunk& c : chunks) rebuilt += png_chunk_bytes(c.type, c.data);
  CHECK(rebuilt == bytes);

  int fctl = 0, idat = 0;
  uint32_t sequence = 0;
  for (const PngChunk& c : chunks) {
    if (c.type == "fcTL") {
      ++fctl;
      CHECK(be32(c.data, 0) == sequence++);
      CHECK(be32(c.data, 4) == 40);
      CHECK(be32(c.data, 8) == 24);
      CHECK(be16(c.data, 20) == 1);   // delay numerator
      CHECK(be16(c.data, 22) == 25);  // / denominator: 1/25 s
    } else if (c.type == "fdAT") {
      CHECK(fctl >= 2);
      CHECK(be32(c.data, 0) == sequence++);
    } else if (c.type == "IDAT") {
      CHECK(fctl == 1);
      ++idat;
    }
  }
  CHECK(fctl == 5);
  CHECK(idat >= 1);

  // The file itself is a valid PNG (its default image is frame 0), and every frame is lossless.
  const Image first = decode_png(bytes);
  CHECK(first.width == 40);
  CHECK(first.height == 24);
  CHECK(first.rgb == frames[0].rgb);
  for (int k = 1; k < 5; ++k) CHECK(decode_png(frame_png(chunks, k)).rgb == frames[k].rgb);
}

TEST_CASE("APNG: a frame rate that is not whole keeps its delay exactly; .apng works too", "[animation]") {
  using namespace animation_test;
  const std::string path = (scratch_dir("animation_apng_fps") / "film.apng").string();
  AnimationOptions options;
  options.fps = 12.5;
  write_animation(path, film(16, 16, 2), options);
  const std::vector<PngChunk> chunks = png_chunks(file_bytes(path));
  for (const PngChunk& c : chunks)
    if (c.type == "fcTL") CHECK(double(be16(c.data, 20)) / be16(c.data, 22) == Approx(1 / 12.5));
}

TEST_CASE("GIF: frames, sizes and delays in the blocks; stb decodes every frame", "[animation]") {
  using namespace animation_test;
  const std::string path = (scratch_dir("animation_gif") / "film.gif").string();
  const std::vector<Image> frames = film(48, 20, 7);
  AnimationWriter writer(path);  // 30 fps
  for (const Image& f : frames) writer.add(f);
  CHECK(writer.frames() == 7);
  CHECK(writer.format() == AnimationFormat::gif);
  CHECK_FALSE(std::filesystem::exists(path));  // only finish() puts it in place
  writer.finish();

  const std::string bytes = file_bytes(path);
  const GifStructure g = gif_structure(bytes);
  CHECK(g.width == 48);
  CHECK(g.height == 20);
  CHECK(g.loops);
  CHECK(g.trailer);
  REQUIRE(g.frame_sizes.size() == 7);
  for (const auto& size : g.frame_sizes) CHECK(size == std::array<int, 2>{48, 20});
  REQUIRE(g.delays.size() == 7);
  int total = 0;
  for (int d : g.delays) {
    CHECK((d == 3 || d == 4));
    total += d;
  }
  CHECK(total == 23);  // 7 frames at 30 fps: 0.233 s

  int* delays = nullptr;
  int w = 0, h = 0, z = 0, c = 0;
  stbi_uc* pixels = stbi_load_gif_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                                              static_cast<int>(bytes.size()), &delays, &w, &h, &z, &c, 3);
  REQUIRE(pixels != nullptr);
  CHECK(w == 48);
  CHECK(h == 20);
  CHECK(z == 7);
  // The film has fewer than 256 colours: the palette holds them all, the frames come back exact.
  for (int k = 0; k < z; ++k) {
    const std::vector<uint8_t> frame(pixels + 3 * size_t(k) * w * h, pixels + 3 * size_t(k + 1) * w * h);
    CHECK(frame == frames[k].rgb);
  }
  stbi_image_free(pixels);
  std::free(delays);
}

TEST_CASE("GIF: a picture of many colours (long LZW codes, table resets) decodes close to its input", "[animation]") {
  using namespace animation_test;
  const std::string path = (scratch_dir("animation_gif_many") / "noise.gif").string();
  std::vector<Image> frames;
  uint32_t state = 12345;
  for (int k = 0; k < 3; ++k) {
    Image image(300, 200, Eigen::Vector3f(0, 0, 0));
    for (size_t i = 0; i < image.rgb.size(); ++i) {
      state = state * 1664525u + 1013904223u;
      // Smooth gradients with a little noise: more than 256 colours, like shaded renders.
      const size_t p = i / 3;
      const int x = static_cast<int>(p % 300), y = static_cast<int>(p / 300);
      const int base = (i % 3 == 0 ? x * 255 / 299 : i % 3 == 1 ? y * 255 / 199 : (x + y + 40 * k) % 256);
      image.rgb[i] = static_cast<uint8_t>(std::clamp(base + static_cast<int>(state >> 29) - 4, 0, 255));
    }
    frames.push_back(image);
  }
  AnimationOptions options;
  options.fps = 10;
  write_animation(path, frames, options);
  const std::string bytes = file_bytes(path);
  const GifStructure g = gif_structure(bytes);
  CHECK(g.frame_sizes.size() == 3);
  CHECK(g.delays == std::vector<int>{10, 10, 10});
  int* delays = nullptr;
  int w = 0, h = 0, z = 0, c = 0;
  stbi_uc* pixels = stbi_load_gif_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                                              static_cast<int>(bytes.size()), &delays, &w, &h, &z, &c, 3);
  REQUIRE(pixels != nullptr);
  REQUIRE(z == 3);
  CHECK(delays[0] == 100);  // stb reports milliseconds
  double error = 0;
  for (int k = 0; k < 3; ++k)
    for (size_t i = 0; i < frames[k].rgb.size(); ++i)
      error += std::abs(int(pixels[k * frames[k].rgb.size() + i]) - int(frames[k].rgb[i]));
  error /= 3.0 * frames[0].rgb.size();
  // Mean absolute error per channel, of 255: gradients through the whole colour cube in 256 colours,
  // with noise; renders (greys and one albedo) come out far closer.
  CHECK(error < 20);
  stbi_image_free(pixels);
  std::free(delays);
}

// ffprobe's count of decoded frames and the size of the first video stream: "frames,width,height".
std::string ffprobe_frames(const std::string& path) {
  const std::string out = path + ".probe.txt";
  const std::string command =
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=nb_read_frames,width,height -of csv=p=0 '" +
      path + "' > '" + out + "' 2>&1";
  const int rc = std::system(command.c_str());
  std::string text = animation_test::file_bytes(out);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  INFO(text);
  REQUIRE(rc == 0);
  return text;
}

TEST_CASE("MP4 through ffmpeg: ffprobe counts the frames at their size", "[animation][ffmpeg]") {
  // scripts/setup.sh installs ffmpeg (with ffprobe): missing, this fails rather than skips.
  INFO("ffmpeg and ffprobe come from Debian's ffmpeg package: apt-get install ffmpeg (scripts/setup.sh)");
  REQUIRE_FALSE(find_program("ffmpeg").empty());
  REQUIRE_FALSE(find_program("ffprobe").empty());
  using namespace animation_test;
  const std::filesystem::path dir = scratch_dir("animation_mp4");
  const std::string path = (dir / "film.mp4").string();
  AnimationOptions options;
  options.fps = 10;
  write_animation(path, film(64, 48, 12), options);
  // width,height,frames in ffprobe's field order.
  CHECK(ffprobe_frames(path) == "64,48,12");
  // Odd sides are padded to even ones (yuv420p); no temporaries or logs are left behind.
  const std::string odd = (dir / "odd.mp4").string();
  write_animation(odd, film(33, 21, 3), options);
  CHECK(ffprobe_frames(odd) == "34,22,3");
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.path().extension() == ".mp4")
      ++files;
    else
      CHECK(entry.path().string().find(".probe.txt") != std::string::npos);
  CHECK(files == 2);
}

// An executable shell script at `path`.
void write_script(const std::filesystem::path& path, const std::string& body) {
  std::ofstream(path) << "#!/bin/sh\n" << body;
  std::filesystem::permissions(path, std::filesystem::perms::owner_all);
}

TEST_CASE("MP4: without libx264 MPEG-4 part 2; ffmpeg's own message when it fails", "[animation][ffmpeg]") {
  INFO("ffmpeg and ffprobe come from Debian's ffmpeg package: apt-get install ffmpeg (scripts/setup.sh)");
  const std::string ffmpeg = find_program("ffmpeg");
  REQUIRE_FALSE(ffmpeg.empty());
  REQUIRE_FALSE(find_program("ffprobe").empty());
  using namespace animation_test;
  const std::filesystem::path dir = scratch_dir("animation_mp4_fallback");
  // An ffmpeg whose encoder list lacks libx264.
  write_script(dir / "ffmpeg_no_x264", "case \" $* \" in *\" -encoders \"*) '" + ffmpeg +
                                           "' \"$@\" | grep -v libx264;; *) exec '" + ffmpeg + "' \"$@\";; esac\n");
  AnimationOptions options;
  options.ffmpeg = (dir / "ffmpeg_no_x264").string();
  const std::string path = (dir / "out" / "film.mp4").string();
  write_animation(path, film(32, 16, 4), options);
  CHECK(ffprobe_frames(path) == "32,16,4");
  const std::string codec = (dir / "codec.txt").string();
  REQUIRE(std::system(("ffprobe -v error -select_streams v:0 -show_entries stream=codec_name -of csv=p=0 '" + path +
                       "' > '" + codec + "'")
                          .c_str()) == 0);
  CHECK(file_bytes(codec) == "mpeg4\n");

  // An ffmpeg that fails: its message in the error, no file and no temporaries left.
  write_script(dir / "ffmpeg_broken", "cat > /dev/null; echo 'Unknown encoder: nothing here' >&2; exit 1\n");
  options.ffmpeg = (dir / "ffmpeg_broken").string();
  const std::filesystem::path broken_dir = dir / "broken";
  CHECK_THROWS_WITH(write_animation((broken_dir / "film.mp4").string(), film(32, 16, 3), options),
                    Catch::Contains("film.mp4") && Catch::Contains("ffmpeg failed (exit status 1)") &&
                        Catch::Contains("Unknown encoder: nothing here"));
  CHECK(std::filesystem::is_empty(broken_dir));

  // One that quits without reading: frames larger than the pipe's buffer meet a closed pipe, which
  // is an error (EPIPE), not the death of this process (SIGPIPE).
  write_script(dir / "ffmpeg_quits", "echo 'gone' >&2; exit 2\n");
  options.ffmpeg = (dir / "ffmpeg_quits").string();
  CHECK_THROWS_WITH(write_animation((broken_dir / "big.mp4").string(), film(256, 256, 4), options),
                    Catch::Contains("big.mp4") && Catch::Contains("exit status 2") && Catch::Contains("gone"));
  CHECK(std::filesystem::is_empty(broken_dir));
}

TEST_CASE("animations: errors name the file or the option, and leave no file behind", "[animation]") {
  using namespace animation_test;
  const std::filesystem::path dir = scratch_dir("animation_errors");
  CHECK_THROWS_WITH(animation_format("take.avi", "--animation"),
                    Catch::Contains("--animation") && Catch::Contains(".mp4, .gif, .png or .apng"));
  CHECK(animation_format("A.GIF") == AnimationFormat::gif);
  CHECK(animation_format("a.png") == AnimationFormat::apng);
  CHECK(animation_format("a.mp4") == AnimationFormat::mp4);

  AnimationOptions fast;
  fast.fps = 0;
  CHECK_THROWS_WITH(fast.validate(), Catch::Contains("animation.fps"));
  CHECK_THROWS_WITH(AnimationWriter((dir / "a.gif").string(), fast), Catch::Contains("animation.fps"));

  AnimationOptions missing;
  missing.ffmpeg = "retarget-no-such-ffmpeg";
  CHECK_THROWS_WITH(AnimationWriter((dir / "a.mp4").string(), missing), Catch::Contains("a.mp4") &&
                                                                            Catch::Contains("ffmpeg package") &&
                                                                            Catch::Contains("apt-get install ffmpeg"));

  {
    AnimationWriter writer((dir / "sizes.gif").string());
    writer.add(film_frame(20, 10, 0));
    CHECK_THROWS_WITH(writer.add(film_frame(21, 10, 1)), Catch::Contains("sizes.gif") &&
                                                             Catch::Contains("frame 1 is 21 x 10") &&
                                                             Catch::Contains("20 x 10"));
    CHECK_THROWS_WITH(writer.add(Image()), Catch::Contains("cannot write a 0 x 0"));
  }  // not finished: discarded
  {
    AnimationWriter writer((dir / "none.png").string());
    CHECK_THROWS_WITH(writer.finish(), Catch::Contains("none.png") && Catch::Contains("no frames"));
  }
  CHECK(std::filesystem::is_empty(dir));  // neither files nor temporaries
}

}  // namespace retarget::test
