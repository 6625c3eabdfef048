#include "geometry/sparse_cholesky.h"

#include <Eigen/SparseCholesky>
#include <catch2/catch.hpp>

#include "core/random.h"

using namespace retarget;

namespace {
// A random sparse SPD matrix: a path-graph Laplacian plus random couplings and a diagonal shift.
SparseMatrix random_spd(int n, uint64_t seed, double shift) {
  Random random(seed);
  auto pick = [&] { return static_cast<int>(random.below(static_cast<uint64_t>(n))); };
  auto weight = [&] { return random.uniform(0.1, 2.0); };
  std::vector<Eigen::Triplet<double>> t;
  auto couple = [&](int i, int j, double w) {
    t.emplace_back(i, i, w), t.emplace_back(j, j, w), t.emplace_back(i, j, -w), t.emplace_back(j, i, -w);
  };
  for (int i = 0; i + 1 < n; ++i) couple(i, i + 1, weight());
  for (int k = 0; k < 2 * n; ++k) {
    const int i = pick(), j = pick();
    if (i != j) couple(i, j, weight());
  }
  for (int i = 0; i < n; ++i) t.emplace_back(i, i, shift);
  SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}
}  // namespace

TEST_CASE("solves with three right-hand sides match Eigen's solver", "[sparse_cholesky]") {
  const int n = 300;
  const SparseMatrix A = random_spd(n, 1, 0.5);
  const Rhs3 b = Rhs3::Random(n, 3);
  Rhs3 x;
  PinnedCholesky(A, {}).solve(b, Rhs3(0, 3), x);
  Eigen::SimplicialLDLT<SparseMatrix> reference(A);
  const Eigen::MatrixXd expected = reference.solve(Eigen::MatrixXd(b));
  CHECK((x - expected).norm() < 1e-9 * expected.norm());
  CHECK((A * x - b).norm() < 1e-9 * b.norm());
}

TEST_CASE("pinned unknowns take their values and the rest satisfies the free equations", "[sparse_cholesky]") {
  const int n = 200;
  const SparseMatrix A = random_spd(n, 2, 0.0);  // a Laplacian: singular until something is pinned
  const std::vector<int> pinned = {17, 3, 150};
  PinnedCholesky solver(A, pinned);
  const Rhs3 b = Rhs3::Random(n, 3);
  const Rhs3 values = Rhs3::Random(3, 3);
  Rhs3 x;
  solver.solve(b, values, x);
  for (int k = 0; k < 3; ++k) CHECK(x.row(pinned[k]) == values.row(k));
  const Rhs3 residual = A * x - b;
  for (int i = 0; i < n; ++i)
    if (std::find(pinned.begin(), pinned.end(), i) == pinned.end()) CHECK(residual.row(i).norm() < 1e-8);
}

TEST_CASE("refactor reuses the pattern with new values", "[sparse_cholesky]") {
  const int n = 120;
  SparseMatrix A = random_spd(n, 3, 0.0);
  PinnedCholesky solver(A, {0});
  SparseMatrix identity(n, n);
  identity.setIdentity();
  A += 2.0 * identity;
  solver.refactor(A);
  const Rhs3 b = Rhs3::Random(n, 3);
  Rhs3 x;
  solver.solve(b, Rhs3::Zero(1, 3), x);
  CHECK((A * x - b).bottomRows(n - 1).norm() < 1e-9 * b.norm());
}

TEST_CASE("a singular system is reported, not solved into NaN", "[sparse_cholesky]") {
  const SparseMatrix A = random_spd(50, 4, 0.0);  // Laplacian, nothing pinned
  CHECK_THROWS_WITH(PinnedCholesky(A, {}), Catch::Contains("not positive definite"));
}
