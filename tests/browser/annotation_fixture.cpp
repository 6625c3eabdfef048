// Writes a tiny annotation project for the browser tests (tests/browser/annotate_browser_test.mjs):
// the tiny human and avatar data of the correspondence tests, correspondences with groups of 4
// avatar samples, and a project over them: 4 groups x 3 comparisons = 12 comparisons.
//   annotation_fixture FOLDER      -> FOLDER/project (the project), FOLDER/data, FOLDER/correspondences
#include <filesystem>
#include <iostream>

#include "core/error.h"
#include "correspond/annotation_project.h"
#include "correspond/correspondence.h"
#include "tiny_correspondence.h"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc != 2) {
    std::cerr << "usage: annotation_fixture FOLDER\n";
    return 2;
  }
  try {
    const fs::path folder = fs::absolute(argv[1]);
    fs::remove_all(folder);
    const retarget::test::TinyCorrespondenceData data = retarget::test::build_tiny_correspondence_data(folder / "data");
    retarget::CorrespondenceOptions c;
    c.group_size = 4;
    c.progress = nullptr;
    retarget::build_correspondences(data.human, data.avatar, data.run, (folder / "correspondences").string(), c);
    retarget::init_annotation_project((folder / "correspondences").string(), (folder / "project").string());
    std::cout << (folder / "project").string() << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "annotation_fixture: " << e.what() << "\n";
    return 1;
  }
}
