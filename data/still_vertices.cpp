#include "data/still_vertices.h"

#include <algorithm>

#include "core/error.h"
#include "core/log.h"
#include "geometry/reconstruction.h"
#include "geometry/rig.h"
#include "geometry/rig_footprint.h"
#include "geometry/topology_fingerprint.h"

namespace retarget {

std::vector<int> still_vertices(const Dataset& d, double threshold_mm) {
  if (d.kind != DatasetKind::avatar || d.vertex_count() == 0) return {};
  const double mm = (!d.eyes.left.empty() && !d.eyes.right.empty()) ? millimetres_per_unit(d.rest.vertices, d.eyes) : 1;
  Eigen::VectorXd motion;
  try {
    motion = rig_footprint(load_dataset_rig(d), 0).motion;
  } catch (const Error& e) {
    log::warn("{}: the rig does not load ({}); still vertices from the training samples", d.folder, e.what());
  }
  if (motion.size() == 0) {
    const Reconstruction reconstruction(d.rest);
    motion = Eigen::VectorXd::Zero(d.vertex_count());
    constexpr int kBatch = 64;
    for (size_t begin = 0; begin < d.train.size(); begin += kBatch) {
      const size_t end = std::min(d.train.size(), begin + kBatch);
      const std::vector<int64_t> rows(d.train.begin() + static_cast<std::ptrdiff_t>(begin),
                                      d.train.begin() + static_cast<std::ptrdiff_t>(end));
      const torch::Tensor f =
          d.features.index_select(0, torch::tensor(rows, torch::kInt64)).to(torch::kFloat32).contiguous();
      const std::vector<Positions> meshes =
          reconstruction.reconstruct_batch(f.data_ptr<float>(), static_cast<int>(rows.size()));
      motion = motion.cwiseMax(vertex_motion(d.rest.vertices, meshes));
    }
  }
  std::vector<int> still;
  for (int v = 0; v < d.vertex_count(); ++v)
    if (motion(v) * mm <= threshold_mm) still.push_back(v);
  if (still.size() < 3) still.clear();
  return still;
}

}  // namespace retarget
