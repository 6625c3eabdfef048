#include "pipeline/round_answers.h"

#include <fmt/format.h>

#include <chrono>
#include <iostream>
#include <thread>

#include "annotate/annotation_store.h"
#include "correspond/annotation_project.h"

namespace retarget {

void wait_for_round_answers(const std::string& folder, double poll_seconds) {
  const AnnotationProject project = load_annotation_project(folder);
  int shown = -1;
  for (bool first = true;; first = false) {
    const StoreProgress progress = AnnotationStore::open(project.database()).progress();
    if (first && !progress.finished())
      std::cout << fmt::format(
                       "waiting for people to answer {} comparisons; serve them with\n"
                       "  retarget annotate serve {}\n"
                       "(the pipeline goes on by itself once every comparison is decided)\n",
                       progress.total() - progress.done(), folder)
                << std::flush;
    if (progress.done() != shown) {
      shown = progress.done();
      std::cout << fmt::format("{} of {} comparisons decided\n", progress.done(), progress.total()) << std::flush;
    }
    if (progress.finished()) return;
    std::this_thread::sleep_for(std::chrono::duration<double>(poll_seconds));
  }
}

}  // namespace retarget
