// Animations out of pictures: a sequence of equally sized RGB images (render/render.h's Image)
// written as one file that plays them at a fixed frame rate. Used by `retarget-infer --animation`
// (the human | avatar pictures of a sequence).
//
// Formats, chosen by the file's extension:
//   .gif          animated GIF89a, written here (no dependency): one 256-colour palette for the
//                 whole animation (median cut over the first frame, which fixes the lighting and
//                 background), LZW, looping forever. Delays are in 1/100 s, rounded so that the
//                 total time is right (30 fps: 3, 3, 4, 3, 3, 4, ... centiseconds).
//   .png, .apng   animated PNG (APNG), written here: every frame a PNG through stb_image_write,
//                 its image data moved into fcTL/fdAT chunks; lossless, looping forever; viewers
//                 without APNG support show the first frame.
//   .mp4          H.264 (libx264; MPEG-4 part 2 when this ffmpeg lacks libx264), yuv420p, through
//                 the `ffmpeg` program (Debian package ffmpeg): raw RGB frames piped to it.
// Frames are streamed: each is encoded (or piped) as it is added, nothing but the current frame
// is held. The file is written to a temporary name next to the target and renamed into place by
// finish() (core/atomic_file.h), so a failed or abandoned animation leaves no partial file.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "render/render.h"

namespace retarget {

enum class AnimationFormat { gif, apng, mp4 };

// The format of `path` by its extension (.gif, .png or .apng, .mp4; any case). Throws
// retarget::Error naming `where` (an option such as "--animation") for any other extension.
AnimationFormat animation_format(const std::string& path, const std::string& where = "animation");
const char* animation_format_name(AnimationFormat format);  // "GIF", "APNG", "MP4"

struct AnimationOptions {
  double fps = 30;  // frames per second, in [0.1, 240]
  // The ffmpeg program for .mp4: a name looked up on PATH, or a path.
  std::string ffmpeg = "ffmpeg";

  void validate() const;  // throws retarget::Error naming the option ("animation.fps", ...)
};

// Writes one animation, frame by frame:
//   AnimationWriter writer("out/take.gif", options);
//   for (...) writer.add(picture);  // all the size of the first
//   writer.finish();                // the file appears now
// Destroying a writer that was not finished discards what was written (and stops ffmpeg).
class AnimationWriter {
 public:
  // Checks the options and the extension; for .mp4 also that ffmpeg can be found (throws
  // retarget::Error naming the package to install). Nothing is written before the first add().
  AnimationWriter(std::string path, AnimationOptions options = {});
  ~AnimationWriter();
  AnimationWriter(const AnimationWriter&) = delete;
  AnimationWriter& operator=(const AnimationWriter&) = delete;

  // frame: width x height RGB, the same size for every frame (at most 16384 x 16384; GIF: 65535).
  // Throws retarget::Error naming the file for another size, an empty image or a write error
  // (ffmpeg's own message for .mp4).
  void add(const Image& frame);
  // Completes the file and renames it into place. Throws retarget::Error naming the file for no
  // frames or a failed write / encode.
  void finish();

  int frames() const;  // added so far
  AnimationFormat format() const;
  const std::string& path() const;

  struct Encoder;  // one per format, in animation.cpp

 private:
  std::string path_;
  AnimationOptions options_;
  AnimationFormat format_;
  std::unique_ptr<Encoder> encoder_;
  int frames_ = 0, width_ = 0, height_ = 0;
  bool finished_ = false;
};

// All of `frames` (>= 1, equal sizes) as one animation: AnimationWriter in one call.
void write_animation(const std::string& path, const std::vector<Image>& frames, const AnimationOptions& options = {});

// The ffmpeg program `name` (a name on PATH or a path) as an absolute path, or "" when missing.
std::string find_program(const std::string& name);

}  // namespace retarget
