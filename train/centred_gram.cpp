#include "train/centred_gram.h"

#include <algorithm>

namespace retarget {

CentredGram centred_gram(int64_t columns, int64_t rows, const ColumnBlockReader& block) {
  CentredGram g{torch::empty({columns}, torch::kFloat32), torch::zeros({rows, rows}, torch::kFloat64)};
  for (int64_t begin = 0; begin < columns; begin += kColumnBlock) {
    const int64_t end = std::min(columns, begin + kColumnBlock);
    torch::Tensor x = block(begin, end);
    const torch::Tensor m = x.mean(0);
    g.mean.slice(0, begin, end).copy_(m);
    x.sub_(m);
    g.gram += x.mm(x.t()).to(torch::kFloat64);
  }
  return g;
}

}  // namespace retarget
