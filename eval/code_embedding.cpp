#include "eval/code_embedding.h"

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"

namespace retarget {

void CodeEmbeddingOptions::validate() const {
  require_positive(static_cast<double>(max_train), "codes.max_train");
  require_positive(static_cast<double>(batch), "codes.batch");
}

namespace {

// Encoder means [rows, latent] float64 of the dataset's `rows`.
torch::Tensor encode_rows(MeshVaeImpl& vae, const Dataset& d, const std::vector<int64_t>& rows, int64_t batch) {
  std::vector<torch::Tensor> codes;
  for (size_t begin = 0; begin < rows.size(); begin += static_cast<size_t>(batch)) {
    const size_t end = std::min(rows.size(), begin + static_cast<size_t>(batch));
    const torch::Tensor idx = torch::tensor(std::vector<int64_t>(rows.begin() + static_cast<std::ptrdiff_t>(begin),
                                                                 rows.begin() + static_cast<std::ptrdiff_t>(end)),
                                            torch::kInt64);
    const torch::Tensor x = d.normaliser.normalise(d.features.index_select(0, idx)).to(torch::kFloat32);
    codes.push_back(vae.forward(x, false).mean.to(torch::kFloat64));
  }
  return torch::cat(codes);
}

std::string label_of(const Dataset& d, int64_t row) {
  if (d.kind != DatasetKind::human || !d.expression.defined()) return "sample";
  const int64_t e = d.expression[row].item<int64_t>();
  return e >= 0 && e < static_cast<int64_t>(d.expressions.size()) ? d.expressions[static_cast<size_t>(e)]
                                                                  : std::to_string(e);
}

}  // namespace

CodeEmbedding write_code_embedding(MeshVaeImpl& vae, const Dataset& d, const std::string& path,
                                   const CodeEmbeddingOptions& options) {
  options.validate();
  if (d.train.empty()) throw Error(d.folder, "has no training samples to embed");
  if (vae.options.vertices() != d.vertex_count())
    throw Error(d.folder, fmt::format("the VAE is for {} vertices, the dataset's mesh has {}", vae.options.vertices(),
                                      d.vertex_count()));
  std::vector<int64_t> train;
  const auto n = static_cast<int64_t>(d.train.size());
  const int64_t step = (n + options.max_train - 1) / options.max_train;
  for (int64_t i = 0; i < n; i += step) train.push_back(d.train[static_cast<size_t>(i)]);
  torch::NoGradGuard no_grad;
  vae.eval();
  const torch::Tensor train_codes = encode_rows(vae, d, train, options.batch);
  const torch::Tensor test_codes = d.test.empty() ? torch::empty({0, train_codes.size(1)}, torch::kFloat64)
                                                  : encode_rows(vae, d, d.test, options.batch);
  const torch::Tensor mean = train_codes.mean(0);
  const torch::Tensor centred = train_codes - mean;
  const auto [u, s, vh] = torch::linalg::svd(centred, /*full_matrices=*/false, c10::nullopt);
  const torch::Tensor axes = vh.narrow(0, 0, std::min<int64_t>(2, vh.size(0))).t();  // [latent, 2]
  const torch::Tensor variance = s.pow(2);
  CodeEmbedding result;
  result.train = static_cast<int64_t>(train.size());
  result.test = static_cast<int64_t>(d.test.size());
  result.explained = variance.sum().item<double>() > 0
                         ? (variance.narrow(0, 0, axes.size(1)).sum() / variance.sum()).item<double>()
                         : 0.0;
  result.path = path;
  std::string text = "split\tlabel\tpc1\tpc2\n";
  auto lines = [&](const char* split, const torch::Tensor& codes, const std::vector<int64_t>& rows) {
    if (codes.size(0) == 0) return;
    const torch::Tensor projected = (codes - mean).mm(axes).contiguous();
    const auto p = projected.accessor<double, 2>();
    for (int64_t i = 0; i < projected.size(0); ++i)
      text += fmt::format("{}\t{}\t{:.6g}\t{:.6g}\n", split, label_of(d, rows[static_cast<size_t>(i)]), p[i][0],
                          projected.size(1) > 1 ? p[i][1] : 0.0);
  };
  lines("train", train_codes, train);
  lines("test", test_codes, d.test);
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
  return result;
}

}  // namespace retarget
