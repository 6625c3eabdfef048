#include "core/sha256.h"

#include <openssl/evp.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <memory>
#include <vector>

#include "core/error.h"

namespace retarget {

namespace {

struct ContextDeleter {
  void operator()(EVP_MD_CTX* context) const { EVP_MD_CTX_free(context); }
};

class Digest {
 public:
  explicit Digest(const std::string& where) : where_(where), context_(EVP_MD_CTX_new()) {
    if (!context_ || EVP_DigestInit_ex(context_.get(), EVP_sha256(), nullptr) != 1)
      throw Error(where_, "cannot start a SHA-256 digest (OpenSSL)");
  }
  void update(const char* data, size_t size) {
    if (size > 0 && EVP_DigestUpdate(context_.get(), data, size) != 1)
      throw Error(where_, "SHA-256 digest failed (OpenSSL)");
  }
  std::string hex() {
    std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
    unsigned int size = 0;
    if (EVP_DigestFinal_ex(context_.get(), digest.data(), &size) != 1)
      throw Error(where_, "SHA-256 digest failed (OpenSSL)");
    static const char* const kHex = "0123456789abcdef";
    std::string out;
    out.reserve(2 * size);
    for (unsigned int i = 0; i < size; ++i) {
      out.push_back(kHex[digest[i] >> 4]);
      out.push_back(kHex[digest[i] & 15]);
    }
    return out;
  }

 private:
  std::string where_;
  std::unique_ptr<EVP_MD_CTX, ContextDeleter> context_;
};

}  // namespace

std::string sha256_of_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, std::string("cannot open for its checksum: ") + std::strerror(errno));
  Digest digest(path);
  std::vector<char> block(1 << 20);
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    digest.update(block.data(), static_cast<size_t>(in.gcount()));
  }
  if (in.bad()) throw Error(path, "read error while computing its checksum");
  return digest.hex();
}

std::string sha256_of_bytes(const std::string& bytes) {
  Digest digest("sha256");
  digest.update(bytes.data(), bytes.size());
  return digest.hex();
}

}  // namespace retarget
