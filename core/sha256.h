// SHA-256 digests of files (OpenSSL's libcrypto), for the checksums bundles carry of their files.
#pragma once

#include <string>

namespace retarget {

// The SHA-256 of the file's bytes as 64 lowercase hex digits. Reads the file in 1 MiB blocks
// (no copy of the whole file in memory). Throws retarget::Error naming the path when it cannot
// be opened or read.
std::string sha256_of_file(const std::string& path);

// The SHA-256 of `bytes`, as above.
std::string sha256_of_bytes(const std::string& bytes);

}  // namespace retarget
