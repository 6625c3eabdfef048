// The codes of a VAE's training and test samples on the training codes' two principal axes
// (eval/code_embedding.h), as `retarget eval vae` writes them for `retarget plot`.
#include "eval/code_embedding.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tiny_correspondence.h"
#include "train/vae_run.h"

using namespace retarget;
namespace fs = std::filesystem;

TEST_CASE("code embedding: every test code and the training codes, centred on the training codes' axes",
          "[code_embedding]") {
  const test::TinyCorrespondenceData& d = test::tiny_correspondence_data();
  TrainedVae trained = load_trained_vae(d.run, "best");
  const fs::path dir = test::scratch_dir("code_embedding");
  CodeEmbeddingOptions o;
  o.max_train = 20;
  const CodeEmbedding e = write_code_embedding(*trained.vae, trained.dataset, (dir / "codes.tsv").string(), o);
  CHECK(e.train <= 20);
  CHECK(e.train >= 10);
  CHECK(e.test == static_cast<int64_t>(trained.dataset.test.size()));
  CHECK(e.explained > 0);
  CHECK(e.explained <= 1 + 1e-9);
  std::ifstream in(e.path);
  std::string line;
  std::getline(in, line);
  CHECK(line == "split\tlabel\tpc1\tpc2");
  int train = 0, test = 0;
  double sum1 = 0, sq1 = 0, sq2 = 0;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string split, label;
    double pc1 = 0, pc2 = 0;
    fields >> split >> label >> pc1 >> pc2;
    CHECK(label == "sample");  // an avatar dataset
    if (split == "train") {
      ++train;
      sum1 += pc1, sq1 += pc1 * pc1, sq2 += pc2 * pc2;
    } else {
      CHECK(split == "test");
      ++test;
    }
  }
  CHECK(train == e.train);
  CHECK(test == e.test);
  CHECK(std::abs(sum1 / train) < 1e-4);  // centred on the training codes
  CHECK(sq1 >= sq2);                     // the first axis holds the most variance
}
