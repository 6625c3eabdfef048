#include "geometry/dr_pack_lanes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "geometry/dr_features.h"
#include "geometry/rotation.h"

namespace retarget {

namespace {

constexpr int kLanes = 8;  // doubles in an AVX-512 register

// What a lane's polar decomposition came to.
enum LaneState : int64_t { kIterating = 0, kConverged = 1, kOffPath = 2 };

// One group of up to kLanes gradients, structure of arrays: entry e of the column-major 3 x 3
// matrix (e = 3 column + row) of lane l at [e][l].
struct Group {
  alignas(64) double t[9][kLanes];  // T
  alignas(64) double x[9][kLanes];  // the polar iterate, then R
  alignas(64) double e[6][kLanes];  // E = X^T X - I: e00 e11 e22 e01 e02 e12
  alignas(64) double error[kLanes];
  alignas(64) int64_t state[kLanes];
  alignas(64) int64_t step[kLanes];      // this iteration: 0 none, 1 Newton-Schulz, 2 scaled Newton
  alignas(64) int64_t log_done[kLanes];  // the rotation's log came from the series
  alignas(64) float packed[9][kLanes];
};

// Norm and determinant of T; lanes with det(T) > 1e-9 |T|^3 start at X = sqrt(3) T / |T|, as
// polar_decomposition does; the others are off the path.
inline __attribute__((always_inline)) void start(Group& g) {
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    // column-major: T(r, c) = t[3 c + r]
    const double t0 = g.t[0][l], t1 = g.t[1][l], t2 = g.t[2][l], t3 = g.t[3][l], t4 = g.t[4][l];
    const double t5 = g.t[5][l], t6 = g.t[6][l], t7 = g.t[7][l], t8 = g.t[8][l];
    const double norm =
        std::sqrt(t0 * t0 + t1 * t1 + t2 * t2 + t3 * t3 + t4 * t4 + t5 * t5 + t6 * t6 + t7 * t7 + t8 * t8);
    const double det = t0 * (t4 * t8 - t5 * t7) - t3 * (t1 * t8 - t2 * t7) + t6 * (t1 * t5 - t2 * t4);
    const bool ok = (norm > 0) & (det > 1e-9 * norm * norm * norm);
    const double scale = std::sqrt(3.0) / norm;
    g.x[0][l] = ok ? t0 * scale : 1.0;
    g.x[1][l] = ok ? t1 * scale : 0.0;
    g.x[2][l] = ok ? t2 * scale : 0.0;
    g.x[3][l] = ok ? t3 * scale : 0.0;
    g.x[4][l] = ok ? t4 * scale : 1.0;
    g.x[5][l] = ok ? t5 * scale : 0.0;
    g.x[6][l] = ok ? t6 * scale : 0.0;
    g.x[7][l] = ok ? t7 * scale : 0.0;
    g.x[8][l] = ok ? t8 * scale : 1.0;
    g.state[l] = ok ? kIterating : kOffPath;
  }
}

// E = X^T X - I and |E|^2 of every lane; decides each iterating lane's step as
// polar_decomposition does. Returns the number of lanes that take the scaled Newton step.
inline __attribute__((always_inline)) int decide(Group& g) {
  int scaled = 0;
#pragma omp simd reduction(+ : scaled)
  for (int l = 0; l < kLanes; ++l) {
    const double x0 = g.x[0][l], x1 = g.x[1][l], x2 = g.x[2][l], x3 = g.x[3][l], x4 = g.x[4][l];
    const double x5 = g.x[5][l], x6 = g.x[6][l], x7 = g.x[7][l], x8 = g.x[8][l];
    const double e00 = x0 * x0 + x1 * x1 + x2 * x2 - 1;
    const double e11 = x3 * x3 + x4 * x4 + x5 * x5 - 1;
    const double e22 = x6 * x6 + x7 * x7 + x8 * x8 - 1;
    const double e01 = x0 * x3 + x1 * x4 + x2 * x5;
    const double e02 = x0 * x6 + x1 * x7 + x2 * x8;
    const double e12 = x3 * x6 + x4 * x7 + x5 * x8;
    const double error = e00 * e00 + e11 * e11 + e22 * e22 + 2 * (e01 * e01 + e02 * e02 + e12 * e12);
    g.e[0][l] = e00;
    g.e[1][l] = e11;
    g.e[2][l] = e22;
    g.e[3][l] = e01;
    g.e[4][l] = e02;
    g.e[5][l] = e12;
    g.error[l] = error;
    const bool iterating = g.state[l] == kIterating;
    const bool converged = iterating && error < 1e-24;
    const int64_t step = !iterating || converged ? 0 : error < 0.25 ? 1 : 2;
    g.state[l] = converged ? kConverged : g.state[l];
    g.step[l] = step;
    scaled += step == 2 ? 1 : 0;
  }
  return scaled;
}

// X <- X (I - E / 2) where the step is Newton-Schulz; such a lane is done once |E|^2 < 1e-8.
inline __attribute__((always_inline)) void newton_schulz(Group& g) {
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    const bool take = g.step[l] == 1;
    const double e00 = g.e[0][l], e11 = g.e[1][l], e22 = g.e[2][l], e01 = g.e[3][l], e02 = g.e[4][l], e12 = g.e[5][l];
#pragma GCC unroll 3
    for (int r = 0; r < 3; ++r) {
      const double c0 = g.x[r][l], c1 = g.x[3 + r][l], c2 = g.x[6 + r][l];
      const double n0 = c0 - 0.5 * (c0 * e00 + c1 * e01 + c2 * e02);
      const double n1 = c1 - 0.5 * (c0 * e01 + c1 * e11 + c2 * e12);
      const double n2 = c2 - 0.5 * (c0 * e02 + c1 * e12 + c2 * e22);
      g.x[r][l] = take ? n0 : c0;
      g.x[3 + r][l] = take ? n1 : c1;
      g.x[6 + r][l] = take ? n2 : c2;
    }
    g.state[l] = take && g.error[l] < 1e-8 ? kConverged : g.state[l];
  }
}

// X <- (gamma X + X^-T / gamma) / 2, gamma = (|X^-T| / |X|)^(1/2), where the step is the scaled
// Newton step (X far from orthogonal).
inline __attribute__((always_inline)) void scaled_newton(Group& g) {
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    const bool take = g.step[l] == 2;
    // column-major: X(r, c) = x[3 c + r]; lanes not taking the step work on I (no division by 0)
    const double x0 = take ? g.x[0][l] : 1.0, x1 = take ? g.x[1][l] : 0.0, x2 = take ? g.x[2][l] : 0.0;
    const double x3 = take ? g.x[3][l] : 0.0, x4 = take ? g.x[4][l] : 1.0, x5 = take ? g.x[5][l] : 0.0;
    const double x6 = take ? g.x[6][l] : 0.0, x7 = take ? g.x[7][l] : 0.0, x8 = take ? g.x[8][l] : 1.0;
    // Cofactors C(r, c), named like X's entries (c0 = C(0, 0), c3 = C(0, 1), ...): X^-T = C / det(X).
    const double c0 = x4 * x8 - x7 * x5, c3 = x7 * x2 - x1 * x8, c6 = x1 * x5 - x4 * x2;
    const double c1 = x6 * x5 - x3 * x8, c4 = x0 * x8 - x6 * x2, c7 = x3 * x2 - x0 * x5;
    const double c2 = x3 * x7 - x6 * x4, c5 = x6 * x1 - x0 * x7, c8 = x0 * x4 - x3 * x1;
    const double inverse_det = 1.0 / (x0 * c0 + x3 * c3 + x6 * c6);
    const double y2 = (c0 * c0 + c1 * c1 + c2 * c2 + c3 * c3 + c4 * c4 + c5 * c5 + c6 * c6 + c7 * c7 + c8 * c8) *
                      (inverse_det * inverse_det);
    const double x_2 = x0 * x0 + x1 * x1 + x2 * x2 + x3 * x3 + x4 * x4 + x5 * x5 + x6 * x6 + x7 * x7 + x8 * x8;
    const double gamma = std::sqrt(std::sqrt(y2 / x_2));
    const double a = 0.5 * gamma, b = 0.5 * inverse_det / gamma;  // X <- a X + b C
    g.x[0][l] = take ? a * x0 + b * c0 : g.x[0][l];
    g.x[1][l] = take ? a * x1 + b * c1 : g.x[1][l];
    g.x[2][l] = take ? a * x2 + b * c2 : g.x[2][l];
    g.x[3][l] = take ? a * x3 + b * c3 : g.x[3][l];
    g.x[4][l] = take ? a * x4 + b * c4 : g.x[4][l];
    g.x[5][l] = take ? a * x5 + b * c5 : g.x[5][l];
    g.x[6][l] = take ? a * x6 + b * c6 : g.x[6][l];
    g.x[7][l] = take ? a * x7 + b * c7 : g.x[7][l];
    g.x[8][l] = take ? a * x8 + b * c8 : g.x[8][l];
  }
}

// S = sym(R^T T) and log R where it comes from the series (rotations up to ~14 degrees), packed.
inline __attribute__((always_inline)) void pack(Group& g) {
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    // (R^T T)(i, j) = sum_k R(k, i) T(k, j), column-major entries as above
    auto product = [&g, l](int i, int j) {
      return g.x[3 * i][l] * g.t[3 * j][l] + g.x[3 * i + 1][l] * g.t[3 * j + 1][l] +
             g.x[3 * i + 2][l] * g.t[3 * j + 2][l];
    };
    const double s00 = product(0, 0), s11 = product(1, 1), s22 = product(2, 2);
    const double s01 = 0.5 * (product(0, 1) + product(1, 0)), s02 = 0.5 * (product(0, 2) + product(2, 0)),
                 s12 = 0.5 * (product(1, 2) + product(2, 1));
    g.packed[3][l] = static_cast<float>(s00 - 1);
    g.packed[4][l] = static_cast<float>(s01);
    g.packed[5][l] = static_cast<float>(s02);
    g.packed[6][l] = static_cast<float>(s11 - 1);
    g.packed[7][l] = static_cast<float>(s12);
    g.packed[8][l] = static_cast<float>(s22 - 1);
    // R(r, c) = x[3 c + r]
    const double c = 0.5 * (g.x[0][l] + g.x[4][l] + g.x[8][l] - 1);
    const double v0 = 0.5 * (g.x[5][l] - g.x[7][l]), v1 = 0.5 * (g.x[6][l] - g.x[2][l]),
                 v2 = 0.5 * (g.x[1][l] - g.x[3][l]);
    const double sine = std::sqrt(v0 * v0 + v1 * v1 + v2 * v2);
    // rotation_log's series branch (c > -0.85 and sine <= c / 4, so c >= 0); c > 0 keeps the
    // division below finite in the lanes that do not take it
    const bool series = (sine <= 0.25 * c) & (c > 0);
    const double safe_c = series ? c : 1.0;
    const double factor = atan_over_x(sine / safe_c) / safe_c;  // rotation.h; used where `series` only
    g.packed[0][l] = static_cast<float>(factor * v0);
    g.packed[1][l] = static_cast<float>(factor * v1);
    g.packed[2][l] = static_cast<float>(factor * v2);
    g.log_done[l] = series ? 1 : 0;
  }
}

// The whole group in the vector lanes; the state and log_done say which lanes need more.
inline __attribute__((always_inline)) void run_group(Group& g) {
  start(g);
  for (int iteration = 0; iteration < 40; ++iteration) {
    const int scaled = decide(g);
    int iterating = 0;
    for (int l = 0; l < kLanes; ++l) iterating += g.step[l] != 0 ? 1 : 0;
    if (iterating == 0) break;
    newton_schulz(g);
    if (scaled > 0) scaled_newton(g);
  }
  for (int l = 0; l < kLanes; ++l)
    if (g.state[l] == kIterating) g.state[l] = kOffPath;  // not converged: the scalar path decides
  pack(g);
}

__attribute__((target("avx512f,avx512vl,avx512dq,avx2,fma"))) void run_group_avx512(Group& g) { run_group(g); }
__attribute__((target("avx2,fma"))) void run_group_avx2(Group& g) { run_group(g); }
void run_group_baseline(Group& g) { run_group(g); }

using GroupRunner = void (*)(Group&);

bool avx512_runs() {
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq");
}
bool avx2_runs() { return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"); }

GroupRunner group_runner(DrLanes lanes) {
  static const GroupRunner best = avx512_runs() ? &run_group_avx512
                                  : avx2_runs() ? &run_group_avx2
                                                : &run_group_baseline;
  if (!dr_lanes_available(lanes))
    throw Error("DR features",
                std::string("this CPU does not run the ") + (lanes == DrLanes::avx512 ? "AVX-512" : "AVX2") + " lanes");
  switch (lanes) {
    case DrLanes::avx512:
      return &run_group_avx512;
    case DrLanes::avx2:
      return &run_group_avx2;
    case DrLanes::baseline:
      return &run_group_baseline;
    case DrLanes::automatic:
      break;
  }
  return best;
}

}  // namespace

bool dr_lanes_available(DrLanes lanes) {
  switch (lanes) {
    case DrLanes::avx512:
      return avx512_runs();
    case DrLanes::avx2:
      return avx2_runs();
    default:
      return true;
  }
}

const char* dr_lanes_name(DrLanes lanes) {
  const GroupRunner run = lanes == DrLanes::automatic ? group_runner(lanes) : nullptr;
  if (lanes == DrLanes::avx512 || run == &run_group_avx512) return "AVX-512";
  if (lanes == DrLanes::avx2 || run == &run_group_avx2) return "AVX2";
  return "baseline";
}

void pack_dr_lanes(const Eigen::Matrix3d* gradients, int count, float* out, DrLanes lanes) {
  const GroupRunner run = group_runner(lanes);
  Group g;
  for (int first = 0; first < count; first += kLanes) {
    const int n = std::min(kLanes, count - first);
    for (int l = 0; l < kLanes; ++l) {
      const double* m = gradients[first + std::min(l, n - 1)].data();  // spare lanes repeat the last
      for (int k = 0; k < 9; ++k) g.t[k][l] = m[k];
    }
    run(g);
    for (int l = 0; l < n; ++l) {
      float* row = out + static_cast<size_t>(first + l) * kDrWidth;
      if (g.state[l] == kOffPath) {
        const PolarDecomposition p = polar_decomposition(gradients[first + l]);
        pack_dr(p.rotation, p.stretch, row);
        continue;
      }
      for (int k = 0; k < kDrWidth; ++k) row[k] = g.packed[k][l];
      if (!g.log_done[l]) {
        Eigen::Matrix3d R;
        for (int k = 0; k < 9; ++k) R.data()[k] = g.x[k][l];
        const Eigen::Vector3d r = rotation_log(R);
        for (int k = 0; k < 3; ++k) row[k] = static_cast<float>(r[k]);
      }
    }
  }
}

}  // namespace retarget
