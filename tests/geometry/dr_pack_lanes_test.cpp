#include "geometry/dr_pack_lanes.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/error.h"
#include "geometry/dr_features.h"
#include "geometry/rotation.h"

using namespace retarget;

namespace {

// Gradients of every kind the features meet: rotations from none to near pi, mild and strong
// stretches (the scaled Newton steps), reflections and rank-deficient T (the eigen path), zero.
std::vector<Eigen::Matrix3d> gradients_of_every_kind() {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<Eigen::Matrix3d> out;
  const double angles[] = {0.0, 1e-9, 0.01, 0.2, 0.24, 0.3, 1.0, 2.0, 2.6, 3.0, 3.1};
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d axis = Eigen::Vector3d(unit(random), unit(random), unit(random)).normalized();
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angles[k % 11], axis).toRotationMatrix();
    Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
    const double strength = k % 3 == 0 ? 0.02 : k % 3 == 1 ? 0.3 : 2.0;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) S(i, j) = S(j, i) = S(i, j) + strength * unit(random);
    S += 3 * strength * Eigen::Matrix3d::Identity();  // positive definite
    out.push_back(R * S);
  }
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  out.push_back(R * Eigen::Vector3d(50, 1, 0.02).asDiagonal());  // strong stretch
  out.push_back(R * Eigen::Vector3d(1, 1, -1).asDiagonal());     // reflection
  Eigen::Matrix3d rank_two = R;
  rank_two.col(2).setZero();
  out.push_back(rank_two);
  out.push_back(Eigen::Matrix3d::Zero());
  out.push_back(Eigen::Matrix3d::Identity());
  out.push_back(1e-30 * R);  // tiny but a rotation
  return out;
}

// pack_dr(polar_decomposition(T)), one at a time.
std::vector<float> one_at_a_time(const std::vector<Eigen::Matrix3d>& gradients) {
  std::vector<float> out(gradients.size() * kDrWidth);
  for (size_t i = 0; i < gradients.size(); ++i) {
    const PolarDecomposition p = polar_decomposition(gradients[i]);
    pack_dr(p.rotation, p.stretch, out.data() + i * kDrWidth);
  }
  return out;
}

}  // namespace

TEST_CASE("DR packing in vector lanes agrees with one gradient at a time, on every version this CPU runs",
          "[dr_pack_lanes]") {
  const std::vector<Eigen::Matrix3d> gradients = gradients_of_every_kind();
  const std::vector<float> expected = one_at_a_time(gradients);
  int versions = 0;
  for (DrLanes lanes : {DrLanes::automatic, DrLanes::avx512, DrLanes::avx2, DrLanes::baseline}) {
    if (!dr_lanes_available(lanes)) {
      CHECK_THROWS_AS(pack_dr_lanes(gradients.data(), 1, std::vector<float>(kDrWidth).data(), lanes), Error);
      continue;
    }
    ++versions;
    INFO(dr_lanes_name(lanes));
    std::vector<float> got(expected.size(), -99.0f);
    pack_dr_lanes(gradients.data(), static_cast<int>(gradients.size()), got.data(), lanes);
    double worst = 0;
    for (size_t i = 0; i < gradients.size(); ++i) {
      INFO("gradient " << i << "\n" << gradients[i]);
      const double scale = std::max(1.0, gradients[i].norm());
      for (int k = 0; k < kDrWidth; ++k) {
        const double difference = std::abs(got[i * kDrWidth + k] - expected[i * kDrWidth + k]);
        worst = std::max(worst, difference / scale);
        CHECK(difference <= 1e-6 * scale);
      }
    }
    INFO("worst difference " << worst);
    CHECK(worst < 1e-6);
  }
  CHECK(versions >= 2);  // automatic and baseline run everywhere
  CHECK(std::string(dr_lanes_name(DrLanes::baseline)) == "baseline");
  const std::string in_use = dr_lanes_name();
  CHECK((in_use == "AVX-512" || in_use == "AVX2" || in_use == "baseline"));
  CHECK(dr_lanes_available(in_use == "AVX-512" ? DrLanes::avx512
                           : in_use == "AVX2"  ? DrLanes::avx2
                                               : DrLanes::baseline));
}

TEST_CASE("DR packing in vector lanes: any count, each row its own gradient's whatever its place in a group",
          "[dr_pack_lanes]") {
  const std::vector<Eigen::Matrix3d> all = gradients_of_every_kind();
  for (int count : {0, 1, 7, 8, 9, 17, 61}) {
    INFO("count " << count);
    // The same gradients in reverse order: each lands in another lane of another group.
    const std::vector<Eigen::Matrix3d> forward(all.begin(), all.begin() + count);
    const std::vector<Eigen::Matrix3d> backward(forward.rbegin(), forward.rend());
    std::vector<float> a(count * kDrWidth + 1, 42.0f), b(count * kDrWidth + 1, 42.0f);
    pack_dr_lanes(forward.data(), count, a.data());
    pack_dr_lanes(backward.data(), count, b.data());
    CHECK(a.back() == 42.0f);  // nothing written past the last row
    for (int i = 0; i < count; ++i)
      for (int k = 0; k < kDrWidth; ++k) CHECK(a[i * kDrWidth + k] == b[(count - 1 - i) * kDrWidth + k]);
  }
}

TEST_CASE("DR packing in vector lanes: the rest pose is all zeros and a pure rotation has no stretch",
          "[dr_pack_lanes]") {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  std::vector<Eigen::Matrix3d> gradients = {Eigen::Matrix3d::Identity()};
  for (double angle : {0.1, 0.2, 1.5}) gradients.push_back(Eigen::AngleAxisd(angle, axis).toRotationMatrix());
  std::vector<float> out(gradients.size() * kDrWidth);
  pack_dr_lanes(gradients.data(), static_cast<int>(gradients.size()), out.data());
  for (int k = 0; k < kDrWidth; ++k) CHECK(out[k] == 0.0f);
  const double angles[] = {0.1, 0.2, 1.5};
  for (int i = 1; i < 4; ++i) {
    const float* row = out.data() + i * kDrWidth;
    const Eigen::Vector3d r(row[0], row[1], row[2]);
    CHECK(std::abs(r.norm() - angles[i - 1]) < 1e-6);
    CHECK((r.normalized() - axis).norm() < 1e-6);
    for (int k = 3; k < kDrWidth; ++k) CHECK(std::abs(row[k]) < 1e-6);
  }
}
