// Sparse symmetric positive (semi-)definite solves, factorised once and reused:
// the workhorse behind reconstruction and deformation transfer.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

namespace retarget {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
// n x 3 right-hand sides / solutions, row-major so one row is one unknown's (x, y, z).
using Rhs3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Solves A x = b for n x 3 right-hand sides with some unknowns pinned to given values.
// A is n x n, symmetric (both triangles stored), positive definite once the pinned
// unknowns are removed (a Laplacian needs one pinned vertex per connected component).
// The factor is computed once (AMD ordering, simplicial LLT) and each solve runs one
// forward and one backward sweep over the factor for all three columns together,
// instead of Eigen's one sweep per column.
class PinnedCholesky {
 public:
  // pinned: indices in [0, n), any order, no duplicates. Throws retarget::Error if
  // the reduced matrix is not positive definite (names the failing solve).
  PinnedCholesky(const SparseMatrix& A, std::vector<int> pinned);
  ~PinnedCholesky();
  PinnedCholesky(PinnedCholesky&&) noexcept;
  PinnedCholesky& operator=(PinnedCholesky&&) noexcept;

  // New numeric values on the SAME sparsity pattern as the constructor's A:
  // reuses the symbolic analysis.
  void refactor(const SparseMatrix& A);

  // b: n x 3; pinned_values: #pinned x 3 in the order given to the constructor.
  // out x: n x 3 with the pinned rows set to pinned_values. Thread-safe (const).
  void solve(const Rhs3& b, const Rhs3& pinned_values, Rhs3& x) const;

  int size() const;
  const std::vector<int>& pinned() const;
  // Non-zeros of the triangular factor, for benchmarks and logs.
  long factor_nonzeros() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace retarget
