#include "render/animation.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "core/atomic_file.h"
#include "core/error.h"

extern char** environ;

namespace retarget {

namespace animation_detail {

namespace fs = std::filesystem;

// A binary file written at a temporary name next to `path`, renamed into place by commit().
class TemporaryFile {
 public:
  explicit TemporaryFile(std::string path) : path_(std::move(path)), temporary_(temporary_path_for(path_)) {
    std::error_code ec;
    const fs::path parent = fs::path(path_).parent_path();
    if (!parent.empty()) fs::create_directories(parent, ec);
    out_.open(temporary_, std::ios::binary | std::ios::trunc);
    if (!out_) throw Error(path_, "cannot create the file (" + temporary_ + ")");
  }
  ~TemporaryFile() {
    if (committed_) return;
    out_.close();
    discard_temporary_file(temporary_);
  }
  void write(const std::string& bytes) {
    out_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out_) throw Error(path_, "write failed (disk full?)");
  }
  std::ofstream& stream() { return out_; }
  void commit() {
    out_.close();
    if (out_.fail()) throw Error(path_, "write failed (disk full?)");
    commit_temporary_file(temporary_, path_);
    committed_ = true;
  }

 private:
  std::string path_, temporary_;
  std::ofstream out_;
  bool committed_ = false;
};

void put_u16_le(std::string& s, int v) {
  s += static_cast<char>(v & 0xff);
  s += static_cast<char>((v >> 8) & 0xff);
}
void put_u16_be(std::string& s, uint32_t v) {
  s += static_cast<char>((v >> 8) & 0xff);
  s += static_cast<char>(v & 0xff);
}
void put_u32_be(std::string& s, uint32_t v) {
  put_u16_be(s, v >> 16);
  put_u16_be(s, v & 0xffff);
}
uint32_t get_u32_be(const std::string& s, size_t at) {
  return (uint32_t(uint8_t(s[at])) << 24) | (uint32_t(uint8_t(s[at + 1])) << 16) | (uint32_t(uint8_t(s[at + 2])) << 8) |
         uint32_t(uint8_t(s[at + 3]));
}

// ---------------------------------------------------------------------------------------------
// APNG: frame 0 is the PNG's default image (IDAT), every frame has an fcTL before its data,
// frames after the first carry their data in fdAT chunks; acTL (frame count) is patched at the end.

uint32_t png_crc(const std::string& type_and_data) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t n = 0; n < 256; ++n) {
      uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  uint32_t c = 0xffffffffu;
  for (char ch : type_and_data) c = table[(c ^ uint8_t(ch)) & 0xff] ^ (c >> 8);
  return c ^ 0xffffffffu;
}

std::string png_chunk(const char* type, const std::string& data) {
  std::string body = std::string(type, 4) + data, chunk;
  put_u32_be(chunk, static_cast<uint32_t>(data.size()));
  chunk += body;
  put_u32_be(chunk, png_crc(body));
  return chunk;
}

struct PngParts {
  std::string ihdr;               // the IHDR chunk, whole
  std::vector<std::string> idat;  // the IDAT chunks' data
};

PngParts png_parts(const std::string& png, const std::string& what) {
  PngParts parts;
  if (png.size() < 8 || png.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0) throw Error(what, "PNG encoding failed");
  for (size_t at = 8; at + 12 <= png.size();) {
    const uint32_t length = get_u32_be(png, at);
    if (at + 12 + length > png.size()) throw Error(what, "PNG encoding failed (a truncated chunk)");
    const std::string type = png.substr(at + 4, 4);
    if (type == "IHDR") parts.ihdr = png.substr(at, 12 + length);
    if (type == "IDAT") parts.idat.push_back(png.substr(at + 8, length));
    at += 12 + length;
  }
  if (parts.ihdr.empty() || parts.idat.empty()) throw Error(what, "PNG encoding failed (no IHDR or IDAT)");
  return parts;
}

// 1 / fps as the fraction fcTL stores (16-bit numerator and denominator).
std::pair<int, int> apng_delay(double fps) {
  if (fps == std::round(fps)) return {1, static_cast<int>(fps)};
  const double den = std::round(fps * 100);
  return {100, static_cast<int>(den)};
}

}  // namespace animation_detail

struct AnimationWriter::Encoder {
  virtual ~Encoder() = default;
  virtual void add(const Image& frame, int index) = 0;
  virtual void finish() = 0;
};

namespace animation_detail {

class ApngEncoder final : public AnimationWriter::Encoder {
 public:
  ApngEncoder(std::string path, double fps) : path_(std::move(path)), fps_(fps), file_(path_) {}

  void add(const Image& frame, int index) override {
    const PngParts parts = png_parts(encode_png(frame, path_), path_);
    std::string out;
    if (index == 0) {
      out += "\x89PNG\r\n\x1a\n";
      out += parts.ihdr;
      acTL_at_ = static_cast<std::streamoff>(out.size());
      out += png_chunk("acTL", actl(0));
    }
    std::string fctl;
    put_u32_be(fctl, sequence_++);
    put_u32_be(fctl, static_cast<uint32_t>(frame.width));
    put_u32_be(fctl, static_cast<uint32_t>(frame.height));
    put_u32_be(fctl, 0);  // x offset
    put_u32_be(fctl, 0);  // y offset
    const auto [num, den] = apng_delay(fps_);
    put_u16_be(fctl, static_cast<uint32_t>(num));
    put_u16_be(fctl, static_cast<uint32_t>(den));
    fctl += '\0';  // dispose: none (every frame covers the whole picture)
    fctl += '\0';  // blend: source
    out += png_chunk("fcTL", fctl);
    for (const std::string& data : parts.idat) {
      if (index == 0) {
        out += png_chunk("IDAT", data);
      } else {
        std::string fdat;
        put_u32_be(fdat, sequence_++);
        out += png_chunk("fdAT", fdat + data);
      }
    }
    file_.write(out);
    frames_ = index + 1;
  }

  void finish() override {
    file_.write(png_chunk("IEND", ""));
    std::ofstream& s = file_.stream();
    s.seekp(acTL_at_);
    const std::string chunk = png_chunk("acTL", actl(static_cast<uint32_t>(frames_)));
    file_.write(chunk);
    file_.commit();
  }

 private:
  static std::string actl(uint32_t frames) {
    std::string data;
    put_u32_be(data, frames);
    put_u32_be(data, 0);  // plays: forever
    return data;
  }

  std::string path_;
  double fps_;
  TemporaryFile file_;
  std::streamoff acTL_at_ = 0;
  uint32_t sequence_ = 0;
  int frames_ = 0;
};

// ---------------------------------------------------------------------------------------------
// GIF: one global palette by median cut over the first frame's colours (5 bits a channel),
// nearest-colour lookup per 15-bit colour, LZW with 8-bit minimum code size.

struct ColourBox {
  std::vector<int> bins;  // 15-bit colours r << 10 | g << 5 | b
  int64_t count = 0;
};

class GifPalette {
 public:
  explicit GifPalette(const Image& image) : nearest_(32768, -1) {
    std::vector<int64_t> count(32768, 0);
    std::vector<std::array<int64_t, 3>> sum(32768, {0, 0, 0});
    const size_t pixels = static_cast<size_t>(image.width) * image.height;
    for (size_t p = 0; p < pixels; ++p) {
      const uint8_t* c = image.rgb.data() + 3 * p;
      const int bin = key(c);
      ++count[bin];
      for (int k = 0; k < 3; ++k) sum[bin][k] += c[k];
    }
    std::vector<ColourBox> boxes(1);
    for (int bin = 0; bin < 32768; ++bin) {
      if (count[bin] == 0) continue;
      boxes[0].bins.push_back(bin);
      boxes[0].count += count[bin];
    }
    auto channel = [](int bin, int k) { return (bin >> (10 - 5 * k)) & 31; };
    while (boxes.size() < 256) {
      // Split the box with the most pixels times its widest range.
      int best = -1, best_channel = 0;
      int64_t best_score = 0;
      for (size_t b = 0; b < boxes.size(); ++b) {
        if (boxes[b].bins.size() < 2) continue;
        for (int k = 0; k < 3; ++k) {
          int lo = 31, hi = 0;
          for (int bin : boxes[b].bins) {
            lo = std::min(lo, channel(bin, k));
            hi = std::max(hi, channel(bin, k));
          }
          const int64_t score = (hi - lo) * boxes[b].count;
          if (hi > lo && score > best_score) {
            best_score = score;
            best = static_cast<int>(b);
            best_channel = k;
          }
        }
      }
      if (best < 0) break;
      ColourBox& box = boxes[best];
      std::sort(box.bins.begin(), box.bins.end(),
                [&](int a, int b) { return channel(a, best_channel) < channel(b, best_channel); });
      // The weighted median, keeping both halves non-empty.
      int64_t seen = 0;
      size_t cut = 1;
      for (; cut < box.bins.size() - 1; ++cut) {
        seen += count[box.bins[cut - 1]];
        if (2 * seen >= box.count) break;
      }
      ColourBox upper;
      upper.bins.assign(box.bins.begin() + static_cast<std::ptrdiff_t>(cut), box.bins.end());
      box.bins.resize(cut);
      box.count = 0;
      for (int bin : box.bins) box.count += count[bin];
      for (int bin : upper.bins) upper.count += count[bin];
      boxes.push_back(std::move(upper));
    }
    for (const ColourBox& box : boxes) {
      std::array<int64_t, 3> s{0, 0, 0};
      for (int bin : box.bins)
        for (int k = 0; k < 3; ++k) s[k] += sum[bin][k];
      std::array<uint8_t, 3> c{};
      for (int k = 0; k < 3; ++k) c[k] = static_cast<uint8_t>(box.count ? (s[k] + box.count / 2) / box.count : 0);
      colours_.push_back(c);
    }
    colours_.resize(256, {0, 0, 0});  // unused entries: black
    used_ = boxes.size();
  }

  uint8_t index(const uint8_t* c) {
    const int bin = key(c);
    int& i = nearest_[bin];
    if (i < 0) {
      // The bin's centre against the used palette entries.
      const int r = ((bin >> 10) & 31) * 8 + 4, g = ((bin >> 5) & 31) * 8 + 4, b = (bin & 31) * 8 + 4;
      int best = 0, best_d = 1 << 30;
      for (size_t p = 0; p < used_; ++p) {
        const int dr = r - colours_[p][0], dg = g - colours_[p][1], db = b - colours_[p][2];
        const int d = 3 * dr * dr + 4 * dg * dg + 2 * db * db;
        if (d < best_d) best_d = d, best = static_cast<int>(p);
      }
      i = best;
    }
    return static_cast<uint8_t>(i);
  }

  std::string table() const {
    std::string t;
    for (const auto& c : colours_)
      for (uint8_t v : c) t += static_cast<char>(v);
    return t;
  }

 private:
  static int key(const uint8_t* c) { return ((c[0] >> 3) << 10) | ((c[1] >> 3) << 5) | (c[2] >> 3); }
  std::vector<std::array<uint8_t, 3>> colours_;
  std::vector<int> nearest_;
  size_t used_ = 0;
};

// Codes of variable width, least significant bit first, in sub-blocks of at most 255 bytes.
class GifBits {
 public:
  void put(int code, int size) {
    bits_ |= static_cast<uint32_t>(code) << count_;
    count_ += size;
    while (count_ >= 8) {
      byte(static_cast<uint8_t>(bits_ & 0xff));
      bits_ >>= 8;
      count_ -= 8;
    }
  }
  std::string finish() {
    if (count_ > 0) byte(static_cast<uint8_t>(bits_ & 0xff));
    bits_ = 0;
    count_ = 0;
    flush_block();
    out_ += '\0';  // block terminator
    return std::move(out_);
  }

 private:
  void byte(uint8_t b) {
    block_ += static_cast<char>(b);
    if (block_.size() == 255) flush_block();
  }
  void flush_block() {
    if (block_.empty()) return;
    out_ += static_cast<char>(block_.size());
    out_ += block_;
    block_.clear();
  }
  uint32_t bits_ = 0;
  int count_ = 0;
  std::string block_, out_;
};

// LZW of 8-bit indices (minimum code size 8): the image data after the image descriptor.
std::string gif_lzw(const std::vector<uint8_t>& indices) {
  constexpr int kClear = 256, kEnd = 257, kMaxCode = 4095;
  // Open addressing: key (prefix << 8 | byte) + 1 -> code; 8192 slots for at most 3838 entries.
  constexpr int kSlots = 8192;
  std::vector<int32_t> keys(kSlots, 0);
  std::vector<int16_t> codes(kSlots, 0);
  auto slot_of = [&](int32_t key) {
    uint32_t h = (static_cast<uint32_t>(key) * 2654435761u) >> 19;  // 13 bits
    while (keys[h] != 0 && keys[h] != key) h = (h + 1) & (kSlots - 1);
    return h;
  };
  std::string out(1, '\x08');  // minimum code size
  GifBits bits;
  int size = 9, last = kEnd;
  bits.put(kClear, size);
  int prefix = indices.empty() ? 0 : indices[0];
  for (size_t p = 1; p < indices.size(); ++p) {
    const int c = indices[p];
    const int32_t key = ((prefix << 8) | c) + 1;
    const uint32_t slot = slot_of(key);
    if (keys[slot] == key) {
      prefix = codes[slot];
      continue;
    }
    bits.put(prefix, size);
    ++last;
    keys[slot] = key;
    codes[slot] = static_cast<int16_t>(last);
    if (last >= (1 << size) && size < 12) ++size;
    if (last == kMaxCode) {
      bits.put(kClear, size);
      std::fill(keys.begin(), keys.end(), 0);
      size = 9;
      last = kEnd;
    }
    prefix = c;
  }
  bits.put(prefix, size);
  // The decoder adds an entry for the code just read: follow it before the end code.
  ++last;
  if (last >= (1 << size) && size < 12) ++size;
  bits.put(kEnd, size);
  return out + bits.finish();
}

// Centiseconds of frame `index` at `fps`, rounded so that the running total stays right.
int gif_delay(int index, double fps) {
  return static_cast<int>(std::lround((index + 1) * 100.0 / fps) - std::lround(index * 100.0 / fps));
}

class GifEncoder final : public AnimationWriter::Encoder {
 public:
  GifEncoder(std::string path, double fps) : path_(std::move(path)), fps_(fps), file_(path_) {}

  void add(const Image& frame, int index) override {
    if (frame.width > 65535 || frame.height > 65535)
      throw Error(path_, fmt::format("GIF pictures are at most 65535 x 65535, got {} x {}", frame.width, frame.height));
    std::string out;
    if (index == 0) {
      palette_ = std::make_unique<GifPalette>(frame);
      out += "GIF89a";
      put_u16_le(out, frame.width);
      put_u16_le(out, frame.height);
      out += '\xf7';  // a global table of 256 colours, 8 bits a channel
      out += '\0';    // background colour
      out += '\0';    // square pixels
      out += palette_->table();
      out += std::string("\x21\xff\x0bNETSCAPE2.0\x03\x01\x00\x00\x00", 19);  // loop forever
    }
    out += "\x21\xf9\x04";
    out += '\x04';  // disposal: leave the frame in place (the next covers it)
    put_u16_le(out, gif_delay(index, fps_));
    out += '\0';  // transparent colour (none: the flag is off)
    out += '\0';
    out += '\x2c';
    put_u16_le(out, 0);
    put_u16_le(out, 0);
    put_u16_le(out, frame.width);
    put_u16_le(out, frame.height);
    out += '\0';  // no local colour table, not interlaced
    std::vector<uint8_t> indices(static_cast<size_t>(frame.width) * frame.height);
    for (size_t p = 0; p < indices.size(); ++p) indices[p] = palette_->index(frame.rgb.data() + 3 * p);
    out += gif_lzw(indices);
    file_.write(out);
  }

  void finish() override {
    file_.write(";");  // trailer
    file_.commit();
  }

 private:
  std::string path_;
  double fps_;
  TemporaryFile file_;
  std::unique_ptr<GifPalette> palette_;
};

// ---------------------------------------------------------------------------------------------
// MP4: raw RGB frames piped into ffmpeg, which writes the temporary file; its messages go to a
// log file next to it (a pipe nobody reads could fill and stall it).

// Runs `argv` with stdin from `stdin_fd` (-1: /dev/null) and stdout and stderr into `log`.
pid_t spawn(const std::vector<std::string>& argv, int stdin_fd, const std::string& log, const std::string& what) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (stdin_fd >= 0)
    posix_spawn_file_actions_adddup2(&actions, stdin_fd, 0);
  else
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw Error(what, fmt::format("cannot run {}: {}", argv[0], std::strerror(rc)));
  return pid;
}

// The exit status of `pid` (-1: killed by a signal).
int wait_for(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The last lines of ffmpeg's messages, for an error.
std::string tail_of(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.pop_back();
  if (text.size() > 600) text = "..." + text.substr(text.size() - 600);
  return text.empty() ? "(no message)" : text;
}

// Writes all of `data` into the pipe; false when the reader is gone (EPIPE, without dying of SIGPIPE).
bool write_all(int fd, const uint8_t* data, size_t size) {
  sigset_t pipe_signal, old;
  sigemptyset(&pipe_signal);
  sigaddset(&pipe_signal, SIGPIPE);
  pthread_sigmask(SIG_BLOCK, &pipe_signal, &old);
  bool ok = true;
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      ok = false;
      break;
    }
    data += n;
    size -= static_cast<size_t>(n);
  }
  if (!ok) {
    // Take the pending SIGPIPE before the old mask comes back.
    const timespec zero{0, 0};
    sigtimedwait(&pipe_signal, nullptr, &zero);
  }
  pthread_sigmask(SIG_SETMASK, &old, nullptr);
  return ok;
}

class FfmpegEncoder final : public AnimationWriter::Encoder {
 public:
  FfmpegEncoder(std::string path, double fps, std::string ffmpeg)
      : path_(std::move(path)), fps_(fps), ffmpeg_(std::move(ffmpeg)) {}

  ~FfmpegEncoder() override {
    if (pid_ > 0) {
      ::close(pipe_);
      kill(pid_, SIGTERM);
      wait_for(pid_);
    }
    if (!temporary_.empty()) {
      discard_temporary_file(temporary_);
      discard_temporary_file(log_);
    }
  }

  void add(const Image& frame, int index) override {
    if (index == 0) start(frame.width, frame.height);
    if (!write_all(pipe_, frame.rgb.data(), frame.rgb.size())) {
      ::close(pipe_);
      const int status = wait_for(pid_);
      pid_ = -1;
      throw Error(path_, fmt::format("ffmpeg stopped at frame {} (exit status {}): {}", index, status,
                                     tail_of(read_text(log_))));
    }
  }

  void finish() override {
    ::close(pipe_);
    const int status = wait_for(pid_);
    pid_ = -1;
    if (status != 0)
      throw Error(path_, fmt::format("ffmpeg failed (exit status {}): {}", status, tail_of(read_text(log_))));
    commit_temporary_file(temporary_, path_);
    discard_temporary_file(log_);
    temporary_.clear();
  }

 private:
  void start(int width, int height) {
    {
      std::error_code ec;
      const fs::path parent = fs::path(path_).parent_path();
      if (!parent.empty()) fs::create_directories(parent, ec);
    }
    temporary_ = temporary_path_for(path_);
    log_ = temporary_ + ".log";
    // libx264 when this ffmpeg has it, else its built-in MPEG-4 part 2.
    spawn_and_wait({ffmpeg_, "-hide_banner", "-encoders"});
    const bool x264 = read_text(log_).find(" libx264 ") != std::string::npos;
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) throw Error(path_, std::string("cannot make a pipe: ") + std::strerror(errno));
    std::vector<std::string> args{ffmpeg_, "-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt",
                                  "rgb24", "-s", fmt::format("{}x{}", width, height), "-r", fmt::format("{}", fps_),
                                  "-i", "-",
                                  // yuv420p needs even sides: pad odd ones with a row / column.
                                  "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", x264 ? "libx264" : "mpeg4"};
    if (!x264) args.insert(args.end(), {"-q:v", "3"});
    args.insert(args.end(), {"-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4", temporary_});
    try {
      pid_ = spawn(args, fds[0], log_, path_);
    } catch (...) {
      ::close(fds[0]);
      ::close(fds[1]);
      throw;
    }
    ::close(fds[0]);
    pipe_ = fds[1];
  }

  void spawn_and_wait(const std::vector<std::string>& args) { wait_for(spawn(args, -1, log_, path_)); }

  std::string path_;
  double fps_;
  std::string ffmpeg_, temporary_, log_;
  pid_t pid_ = -1;
  int pipe_ = -1;
};

}  // namespace animation_detail

AnimationFormat animation_format(const std::string& path, const std::string& where) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".gif") return AnimationFormat::gif;
  if (ext == ".png" || ext == ".apng") return AnimationFormat::apng;
  if (ext == ".mp4") return AnimationFormat::mp4;
  throw Error(where, "expected a .mp4, .gif, .png or .apng file name, got \"" + path + "\"");
}

const char* animation_format_name(AnimationFormat format) {
  switch (format) {
    case AnimationFormat::gif:
      return "GIF";
    case AnimationFormat::apng:
      return "APNG";
    case AnimationFormat::mp4:
      return "MP4";
  }
  return "?";
}

void AnimationOptions::validate() const {
  if (!(fps >= 0.1 && fps <= 240)) throw Error("animation.fps", fmt::format("expected 0.1 to 240, got {}", fps));
  if (ffmpeg.empty()) throw Error("animation.ffmpeg", "expected a program name or path");
}

std::string find_program(const std::string& name) {
  if (name.empty()) return "";
  auto runnable = [](const std::filesystem::path& p) {
    std::error_code ec;
    return std::filesystem::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
  };
  if (name.find('/') != std::string::npos) return runnable(name) ? std::filesystem::absolute(name).string() : "";
  const char* path = std::getenv("PATH");
  std::stringstream folders(path ? path : "/usr/local/bin:/usr/bin:/bin");
  for (std::string folder; std::getline(folders, folder, ':');) {
    if (folder.empty()) folder = ".";
    const std::filesystem::path candidate = std::filesystem::path(folder) / name;
    if (runnable(candidate)) return candidate.string();
  }
  return "";
}

AnimationWriter::AnimationWriter(std::string path, AnimationOptions options)
    : path_(std::move(path)), options_(std::move(options)), format_(animation_format(path_)) {
  options_.validate();
  if (format_ == AnimationFormat::mp4) {
    const std::string ffmpeg = find_program(options_.ffmpeg);
    if (ffmpeg.empty())
      throw Error(path_, "writing an MP4 needs the ffmpeg program, and \"" + options_.ffmpeg +
                             "\" was not found on PATH; install Debian's ffmpeg package (apt-get install ffmpeg; "
                             "scripts/setup.sh does), or write a .gif or .png animation, which need no ffmpeg");
    options_.ffmpeg = ffmpeg;
  }
}

AnimationWriter::~AnimationWriter() = default;

void AnimationWriter::add(const Image& frame) {
  if (finished_) throw Error(path_, "the animation is already finished");
  if (frame.width < 1 || frame.height < 1 || frame.width > 16384 || frame.height > 16384 ||
      frame.rgb.size() != 3 * static_cast<size_t>(frame.width) * frame.height)
    throw Error(path_, fmt::format("frame {}: cannot write a {} x {} picture with {} bytes", frames_, frame.width,
                                   frame.height, frame.rgb.size()));
  if (frames_ == 0) {
    width_ = frame.width;
    height_ = frame.height;
    switch (format_) {
      case AnimationFormat::gif:
        encoder_ = std::make_unique<animation_detail::GifEncoder>(path_, options_.fps);
        break;
      case AnimationFormat::apng:
        encoder_ = std::make_unique<animation_detail::ApngEncoder>(path_, options_.fps);
        break;
      case AnimationFormat::mp4:
        encoder_ = std::make_unique<animation_detail::FfmpegEncoder>(path_, options_.fps, options_.ffmpeg);
        break;
    }
  } else if (frame.width != width_ || frame.height != height_) {
    throw Error(path_, fmt::format("frame {} is {} x {} but the animation's frames are {} x {}", frames_, frame.width,
                                   frame.height, width_, height_));
  }
  encoder_->add(frame, frames_);
  ++frames_;
}

void AnimationWriter::finish() {
  if (finished_) return;
  if (frames_ == 0) throw Error(path_, "no frames to write");
  encoder_->finish();
  finished_ = true;
}

int AnimationWriter::frames() const { return frames_; }
AnimationFormat AnimationWriter::format() const { return format_; }
const std::string& AnimationWriter::path() const { return path_; }

void write_animation(const std::string& path, const std::vector<Image>& frames, const AnimationOptions& options) {
  AnimationWriter writer(path, options);
  for (const Image& frame : frames) writer.add(frame);
  writer.finish();
}

}  // namespace retarget
