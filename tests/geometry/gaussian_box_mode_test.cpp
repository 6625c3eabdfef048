#include "geometry/gaussian_box_mode.h"

#include <catch2/catch.hpp>

#include "core/error.h"

using Catch::Contains;
using namespace retarget;

namespace {

// A 3-d Gaussian: x0 well known (sd 0.05) at 0.8, x1 poorly known (sd 0.5) at 0.3, x2 well known
// (sd 0.1) at 1.2, past the box's top, and correlated with x1 (x1 on x2: slope -1).
struct Example {
  Eigen::VectorXd mean = Eigen::Vector3d(0.8, 0.3, 1.2);
  Eigen::MatrixXd covariance;
  Eigen::VectorXd lower = Eigen::VectorXd::Zero(3), upper = Eigen::VectorXd::Ones(3);
  Example() {
    covariance = Eigen::MatrixXd::Zero(3, 3);
    covariance.diagonal() << 0.05 * 0.05, 0.5 * 0.5, 0.1 * 0.1;
    covariance(1, 2) = covariance(2, 1) = -0.2 * 0.5 * 0.1;
  }
};

double objective(const Example& e, const Eigen::VectorXd& x, const Eigen::VectorXd& centre, double pull) {
  const Eigen::VectorXd d = x - e.mean;
  return 0.5 * d.dot(e.covariance.ldlt().solve(d)) + pull * (x - centre).cwiseAbs().sum();
}

}  // namespace

TEST_CASE("box mode: inside the box, with the correlations kept", "[box]") {
  const Example e;
  const Eigen::VectorXd x = gaussian_box_mode(e.mean, e.covariance, e.lower, e.upper);
  CHECK(x(2) == Approx(1.0));  // x2 leans past its top: on it
  CHECK(x(0) == Approx(0.8));  // independent of the others: where it was
  // x1 moves as its correlation with x2 says (x2 = 1 instead of 1.2): up by 0.2.
  CHECK(x(1) == Approx(0.5).margin(1e-9));
  CHECK((x.array() >= 0).all());
  CHECK((x.array() <= 1).all());
}

TEST_CASE("sparse box mode: a weakly known value stays at the centre, a well known one moves", "[box]") {
  const Example e;
  const Eigen::VectorXd centre = Eigen::VectorXd::Zero(3);
  const double pull = 4.0;
  const Eigen::VectorXd x =
      sparse_box_mode(e.mean, e.covariance, centre, Eigen::VectorXd::Constant(3, pull), e.lower, e.upper);
  CHECK(x(1) == 0.0);                                            // sd 0.5: the pull outweighs it, exactly
  CHECK(x(0) == Approx(0.8 - pull * 0.05 * 0.05).margin(1e-9));  // sd 0.05: shrunk by pull * variance
  CHECK(x(2) == Approx(1.0));
  // The optimum: no small move of any coordinate inside the box lowers the objective.
  const double best = objective(e, x, centre, pull);
  for (Eigen::Index j = 0; j < 3; ++j)
    for (const double step : {-1e-4, 1e-4}) {
      Eigen::VectorXd y = x;
      y(j) = std::clamp(y(j) + step, 0.0, 1.0);
      CHECK(objective(e, y, centre, pull) >= best - 1e-12);
    }
  // No pull: the plain box mode.
  const Eigen::VectorXd plain =
      sparse_box_mode(e.mean, e.covariance, centre, Eigen::VectorXd::Zero(3), e.lower, e.upper);
  CHECK((plain - gaussian_box_mode(e.mean, e.covariance, e.lower, e.upper)).norm() < 1e-12);
}

TEST_CASE("sparse box mode: sizes are checked", "[box]") {
  const Example e;
  CHECK_THROWS_WITH(
      sparse_box_mode(e.mean, e.covariance, Eigen::VectorXd::Zero(2), Eigen::VectorXd::Zero(3), e.lower, e.upper),
      Contains("a centre of 2"));
  CHECK_THROWS_WITH(gaussian_box_mode(e.mean, e.covariance, e.lower, Eigen::VectorXd::Ones(4)),
                    Contains("ranges of 3 and 4"));
}
