// Digests of the files and folders a pipeline stage reads from outside the run folder (recipes,
// rigs, face models, training configs), by content, each computed once per pipeline run.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace retarget {

class InputDigests {
 public:
  // SHA-256 (64 hex digits) of a file's bytes; of a folder, of every file under it (relative
  // path and digest, in sorted order; hidden entries and *.tmp.* temporaries left out); "missing"
  // for a path that does not exist (a stage that needs it fails when it runs, naming it).
  const std::string& of(const std::string& path);

 private:
  std::map<std::string, std::string> cache_;
};

// The fingerprint of a stage: SHA-256 over its key, its commands, its inputs' digests and the
// fingerprints of the stages it reads from, each on its own line.
std::string stage_fingerprint(const std::string& key, const std::vector<std::string>& commands,
                              const std::vector<std::string>& input_digests,
                              const std::vector<std::string>& upstream_fingerprints);

}  // namespace retarget
