#include "geometry/sparse_cholesky.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <string>

#include "core/error.h"

namespace retarget {

struct PinnedCholesky::Impl {
  int n = 0;
  std::vector<int> pinned;
  std::vector<int> free_of;  // n: index among free unknowns, or -1 if pinned
  std::vector<int> free_vars;
  SparseMatrix coupling;  // #free x #pinned block A_fp
  Eigen::SimplicialLLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>> llt;
  // Copy of the factor (CSC, diagonal first in each column) and the fill-reducing order.
  std::vector<int> col_start, row;
  std::vector<double> value;
  std::vector<int> perm;  // perm[i] = position of free unknown i in the factor's order

  void split(const SparseMatrix& A, SparseMatrix& reduced) {
    const int nf = static_cast<int>(free_vars.size());
    std::vector<Eigen::Triplet<double>> ff, fp;
    ff.reserve(A.nonZeros());
    std::vector<int> pinned_slot(n, -1);
    for (int k = 0; k < static_cast<int>(pinned.size()); ++k) pinned_slot[pinned[k]] = k;
    for (int c = 0; c < A.outerSize(); ++c) {
      for (SparseMatrix::InnerIterator it(A, c); it; ++it) {
        const int r = static_cast<int>(it.row());
        if (free_of[r] < 0) continue;
        if (free_of[c] >= 0)
          ff.emplace_back(free_of[r], free_of[c], it.value());
        else
          fp.emplace_back(free_of[r], pinned_slot[c], it.value());
      }
    }
    reduced.resize(nf, nf);
    reduced.setFromTriplets(ff.begin(), ff.end());
    coupling.resize(nf, static_cast<int>(pinned.size()));
    coupling.setFromTriplets(fp.begin(), fp.end());
  }

  void copy_factor() {
    if (llt.info() != Eigen::Success)
      throw Error("sparse Cholesky",
                  "the system matrix is not positive definite after pinning " + std::to_string(pinned.size()) +
                      " unknowns (a disconnected mesh part without a pinned vertex, or NaN weights)");
    const SparseMatrix& L = llt.matrixL().nestedExpression();
    const int nf = static_cast<int>(L.cols());
    col_start.assign(L.outerIndexPtr(), L.outerIndexPtr() + nf + 1);
    row.assign(L.innerIndexPtr(), L.innerIndexPtr() + L.nonZeros());
    value.assign(L.valuePtr(), L.valuePtr() + L.nonZeros());
    const auto& P = llt.permutationP().indices();
    perm.assign(P.data(), P.data() + P.size());
  }
};

PinnedCholesky::PinnedCholesky(const SparseMatrix& A, std::vector<int> pinned) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.n = static_cast<int>(A.rows());
  m.pinned = std::move(pinned);
  m.free_of.assign(m.n, 0);
  for (int p : m.pinned) m.free_of[p] = -1;
  for (int i = 0; i < m.n; ++i) {
    if (m.free_of[i] < 0) continue;
    m.free_of[i] = static_cast<int>(m.free_vars.size());
    m.free_vars.push_back(i);
  }
  SparseMatrix reduced;
  m.split(A, reduced);
  m.llt.analyzePattern(reduced);
  m.llt.factorize(reduced);
  m.copy_factor();
}

PinnedCholesky::~PinnedCholesky() = default;
PinnedCholesky::PinnedCholesky(PinnedCholesky&&) noexcept = default;
PinnedCholesky& PinnedCholesky::operator=(PinnedCholesky&&) noexcept = default;

void PinnedCholesky::refactor(const SparseMatrix& A) {
  SparseMatrix reduced;
  impl_->split(A, reduced);
  impl_->llt.factorize(reduced);
  impl_->copy_factor();
}

void PinnedCholesky::solve(const Rhs3& b, const Rhs3& pinned_values, Rhs3& x) const {
  const Impl& m = *impl_;
  const int nf = static_cast<int>(m.free_vars.size());
  // y = P (b_f - A_fp x_p), in the factor's order.
  Rhs3 y(nf, 3);
  for (int i = 0; i < nf; ++i) y.row(m.perm[i]) = b.row(m.free_vars[i]);
  if (!m.pinned.empty()) {
    for (int c = 0; c < m.coupling.outerSize(); ++c)
      for (SparseMatrix::InnerIterator it(m.coupling, c); it; ++it)
        y.row(m.perm[it.row()]) -= it.value() * pinned_values.row(c);
  }
  double* z = y.data();
  const int* cs = m.col_start.data();
  const int* ri = m.row.data();
  const double* lv = m.value.data();
  // Forward: L z = y, column by column, three right-hand sides at once.
  for (int j = 0; j < nf; ++j) {
    const double inv = 1.0 / lv[cs[j]];
    const double z0 = z[3 * j] * inv, z1 = z[3 * j + 1] * inv, z2 = z[3 * j + 2] * inv;
    z[3 * j] = z0, z[3 * j + 1] = z1, z[3 * j + 2] = z2;
    for (int p = cs[j] + 1; p < cs[j + 1]; ++p) {
      double* zi = z + 3 * ri[p];
      const double l = lv[p];
      zi[0] -= l * z0, zi[1] -= l * z1, zi[2] -= l * z2;
    }
  }
  // Backward: L^T w = z, reading column j of L as row j of L^T.
  for (int j = nf - 1; j >= 0; --j) {
    double s0 = z[3 * j], s1 = z[3 * j + 1], s2 = z[3 * j + 2];
    for (int p = cs[j] + 1; p < cs[j + 1]; ++p) {
      const double* wi = z + 3 * ri[p];
      const double l = lv[p];
      s0 -= l * wi[0], s1 -= l * wi[1], s2 -= l * wi[2];
    }
    const double inv = 1.0 / lv[cs[j]];
    z[3 * j] = s0 * inv, z[3 * j + 1] = s1 * inv, z[3 * j + 2] = s2 * inv;
  }
  x.resize(m.n, 3);
  for (int i = 0; i < nf; ++i) x.row(m.free_vars[i]) = y.row(m.perm[i]);
  for (int k = 0; k < static_cast<int>(m.pinned.size()); ++k) x.row(m.pinned[k]) = pinned_values.row(k);
}

int PinnedCholesky::size() const { return impl_->n; }
const std::vector<int>& PinnedCholesky::pinned() const { return impl_->pinned; }
long PinnedCholesky::factor_nonzeros() const { return static_cast<long>(impl_->value.size()); }

}  // namespace retarget
