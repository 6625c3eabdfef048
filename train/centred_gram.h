// The Gram matrix of some rows of a wide matrix, centred by column, read in column blocks so
// that no [N, D] copy of the rows is ever held: the first pass of the principal starts
// (train/principal_decoder.h, train/principal_encoder.h), whose [N, N] Gram stands in for the
// [D, D] covariance when D (V * 9 features) is far larger than N (rows).
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <functional>

namespace retarget {

constexpr int64_t kColumnBlock = 4096;  // columns read at once

// Columns [begin, end) of the N chosen rows, as float32 [N, end - begin].
using ColumnBlockReader = std::function<torch::Tensor(int64_t begin, int64_t end)>;

struct CentredGram {
  torch::Tensor mean;  // [D] float32: each column's mean over the rows
  torch::Tensor gram;  // [N, N] float64: (X - mean)(X - mean)^T
};

// One pass over columns [0, D) in blocks of kColumnBlock; `rows` is N.
CentredGram centred_gram(int64_t columns, int64_t rows, const ColumnBlockReader& block);

}  // namespace retarget
