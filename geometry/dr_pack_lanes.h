// The last step of DR feature extraction for many vertices at once: each deformation gradient's
// polar decomposition T = R S and R's logarithm, packed into the 9 floats of dr_features.h,
// vectorised across vertices (8 at a time in double precision: one AVX-512 register, two AVX2
// ones, chosen at run time for the CPU). It was the largest part of the features' time (issue 32's
// profile of a batch run: polar decomposition, rotation log and the stretch's product ~11% of all
// samples, each vertex on its own in scalar code).
//
// Each lane runs the steps polar_decomposition and rotation_log (geometry/rotation.h) run, with
// the same thresholds; only the rounding of the vector arithmetic (fused multiply-adds) differs, so
// the packed floats agree with pack_dr(polar_decomposition(T)) to ~1e-7 (tests/geometry). Lanes off
// the common path go through those functions one at a time: reflections and near-singular T
// (the eigen path), T not converged in 40 steps, and rotations past ~14 degrees or near pi
// (atan2 and the quaternion path of rotation_log).
#pragma once

#include <Eigen/Core>

namespace retarget {

// The compiled versions of the lanes: the best this CPU runs (automatic), or one by name, for
// tests and benchmarks.
enum class DrLanes { automatic, avx512, avx2, baseline };

// Whether this CPU runs `lanes` (AVX-512 F, VL and DQ; AVX2 and FMA; baseline and automatic always).
bool dr_lanes_available(DrLanes lanes);

// The version's name ("AVX-512", "AVX2" or "baseline"); for automatic, the one this CPU runs, for
// benchmarks' and logs' labels.
const char* dr_lanes_name(DrLanes lanes = DrLanes::automatic);

// gradients: `count` deformation gradients T_i (any count >= 0). out: count x 9 floats (row i at
// out + 9 i) = pack_dr(R_i, S_i) for polar_decomposition(T_i) = {R_i, S_i}. No allocation.
// Throws retarget::Error for a version the CPU does not run.
void pack_dr_lanes(const Eigen::Matrix3d* gradients, int count, float* out, DrLanes lanes = DrLanes::automatic);

}  // namespace retarget
