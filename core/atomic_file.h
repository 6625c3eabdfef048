// Files are written atomically: a reader (or a crash) sees the old file or the new one,
// never half of one.
#pragma once

#include <cstdint>
#include <functional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace retarget {

// Writes `path` by calling write(stream) on a temporary file in the same folder, flushing
// it to disk, then renaming it over `path`. Creates missing parent folders. Throws
// retarget::Error naming the path if the folder cannot be created, the stream fails, or the
// rename fails; the temporary file is removed on failure.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

// For writers that need a file name (third-party libraries): a unique temporary path next
// to `path`, then commit_temporary_file() renames it into place (fsync first). On failure
// call discard_temporary_file().
std::string temporary_path_for(const std::string& path);
void commit_temporary_file(const std::string& temporary, const std::string& path);
void discard_temporary_file(const std::string& temporary) noexcept;

// Files written as one group: while a FlushGroup lives, write_file_atomically on the thread that
// made it writes each file to its temporary and leaves the flush and the rename to commit(): one
// syncfs of each file system the files are on, then every temporary renamed into place, in the
// order written. For many small files at once (retarget-infer's batches of meshes): one flush
// instead of one per file. A reader or a crash still sees each file whole or not at all.
// Temporaries not committed are removed when the group ends.
class FlushGroup {
 public:
  FlushGroup();
  ~FlushGroup();
  FlushGroup(const FlushGroup&) = delete;
  FlushGroup& operator=(const FlushGroup&) = delete;

  // Flushes, then renames, every file written since the last commit. Returns the files that could
  // not be moved into place, each path with the message write_file_atomically would have thrown
  // (their temporaries are removed); empty when every file is in place.
  std::vector<std::pair<std::string, std::string>> commit();

 private:
  friend void write_file_atomically(const std::string&, const std::function<void(std::ostream&)>&);
  std::vector<std::pair<std::string, std::string>> pending_;  // temporary, path
  FlushGroup* outer_;                                         // the thread's group before this one
};

// What remove_stale_temporaries found and removed.
struct StaleTemporaries {
  int files = 0;
  uintmax_t bytes = 0;
};

// Removes the temporaries (`<name>.tmp.<pid>.<n>`, as temporary_path_for makes them) directly in
// `folder` whose writing process no longer runs: what a kill during a write leaves behind (a
// killed checkpoint write: checkpoints/last.pt.tmp.<pid>.<n>, 147 MB). Temporaries of live
// processes (another writer at work) are kept. A missing folder has none. Logs what it removed
// (info). Never throws; files that cannot be removed are skipped.
StaleTemporaries remove_stale_temporaries(const std::string& folder) noexcept;

}  // namespace retarget
