#include "data/dataset_preview.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.h"
#include "geometry/reconstruction.h"

namespace retarget {

void DatasetPreviewOptions::validate() const {
  if (count < 1 || count > 200) throw Error("preview.count", fmt::format("expected 1..200 samples, got {}", count));
  if (size < 32 || size > 2048) throw Error("preview.size", fmt::format("expected 32..2048 pixels, got {}", size));
}

namespace {

std::string strongest_controllers(const Dataset& d, int64_t sample) {
  const torch::Tensor w = d.weights[sample];
  std::vector<std::pair<double, int>> active;
  for (int c = 0; c < w.size(0); ++c)
    if (w[c].item<double>() != 0) active.emplace_back(w[c].item<double>(), c);
  if (active.empty()) return "rest";
  std::sort(active.rbegin(), active.rend());
  std::string caption;
  for (size_t k = 0; k < std::min<size_t>(2, active.size()); ++k)
    caption += fmt::format("{}{} {:.2f}", k ? " + " : "", d.controllers[active[k].second], active[k].first);
  if (active.size() > 2) caption += fmt::format(" +{}", active.size() - 2);
  return caption;
}

}  // namespace

Image dataset_preview(const Dataset& d, const DatasetPreviewOptions& options) {
  options.validate();
  ReconstructionOptions ro;
  ro.weighting = d.dr.weighting;
  ro.align_to_rest = true;
  const Reconstruction reconstruction(d.rest, ro);
  const auto topology = std::make_shared<const Mesh>(d.rest);
  auto cell = [&](const torch::Tensor& features, std::string caption) {
    const torch::Tensor f = features.to(torch::kFloat32).contiguous();
    return GridCell{topology, reconstruction.reconstruct(f.data_ptr<float>()), {}, std::move(caption)};
  };

  std::vector<GridCell> cells;
  int columns = 4;
  if (d.kind == DatasetKind::avatar) {
    const int64_t n = d.sample_count();
    const int shown = static_cast<int>(std::min<int64_t>(options.count, n));
    for (int k = 0; k < shown; ++k) {
      const int64_t sample = shown == 1 ? 0 : k * (n - 1) / (shown - 1);
      cells.push_back(cell(d.features[sample], fmt::format("#{}: {}", sample, strongest_controllers(d, sample))));
    }
  } else {
    // A few expressions spread over the recipe list, shown as columns: first the
    // identity-averaged targets, then the same expressions for up to three training subjects.
    const int expressions = static_cast<int>(d.expressions.size());
    const int subjects = std::min<int>(3, static_cast<int>(d.train_subjects.size()));
    columns = std::max(1, std::min(expressions, options.count / (subjects + 1)));
    std::vector<int> chosen;
    for (int k = 0; k < columns; ++k) chosen.push_back(columns == 1 ? 0 : k * (expressions - 1) / (columns - 1));
    for (int e : chosen) cells.push_back(cell(d.targets[e], fmt::format("mean: {}", d.expressions[e])));
    const torch::Tensor subject = d.subject.to(torch::kLong), expression = d.expression.to(torch::kLong);
    for (int s = 0; s < subjects; ++s) {
      const auto it = std::find(d.subjects.begin(), d.subjects.end(), d.train_subjects[s]);
      const int64_t id = it - d.subjects.begin();
      for (int e : chosen) {
        const torch::Tensor match = ((subject == id) & (expression == e)).nonzero();
        if (match.size(0) == 0) continue;
        const int64_t sample = match[0][0].item<int64_t>();
        cells.push_back(cell(d.features[sample], fmt::format("{}: {}", d.train_subjects[s], d.expressions[e])));
      }
    }
  }
  GridOptions grid;
  grid.render.width = grid.render.height = options.size;
  if (options.both_views)
    grid.views = {RenderOptions::View::front, RenderOptions::View::three_quarter};
  else
    grid.views = {RenderOptions::View::front};
  grid.title = fmt::format("{} dataset \"{}\": {} samples, {} vertices", to_string(d.kind), d.name, d.sample_count(),
                           d.vertex_count());
  return render_grid(cells, columns, grid);
}

}  // namespace retarget
