#include "avatar/landmark_sheet.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace retarget {

void LandmarkSheetOptions::validate(const std::string& key_path) const {
  if (view_size < 64 || view_size > 4096)
    throw Error(key_path + ".view_size", "must be in 64..4096 (got " + std::to_string(view_size) + ")");
}

namespace sheet_detail {

void dot(Image& image, double cx, double cy, int radius, const Eigen::Vector3f& colour) {
  for (int y = static_cast<int>(cy) - radius - 1; y <= static_cast<int>(cy) + radius + 1; ++y)
    for (int x = static_cast<int>(cx) - radius - 1; x <= static_cast<int>(cx) + radius + 1; ++x) {
      if (x < 0 || y < 0 || x >= image.width || y >= image.height) continue;
      const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
      if (d > radius + 0.5) continue;
      const Eigen::Vector3f c = d > radius - 1 ? Eigen::Vector3f(0.1f, 0.1f, 0.1f) : colour;
      for (int k = 0; k < 3; ++k)
        image.rgb[static_cast<size_t>(3 * (y * image.width + x) + k)] =
            static_cast<uint8_t>(std::lround(std::clamp(c[k], 0.0f, 1.0f) * 255));
    }
}

Eigen::Vector3f confidence_colour(double confidence) {
  if (confidence >= 0.7) return {0.15f, 0.75f, 0.25f};
  if (confidence >= 0.4) return {1.0f, 0.6f, 0.1f};
  return {0.9f, 0.15f, 0.15f};
}

}  // namespace sheet_detail

Image landmark_sheet(const Rig& rig, const LandmarkProposal& proposal, const LandmarkSheetOptions& options) {
  options.validate();
  const Positions& V = rig.neutral.vertices;
  const FaceFrame& f = proposal.frame;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (int v : proposal.eyes.left) origin += V.row(v).transpose();
  for (int v : proposal.eyes.right) origin += V.row(v).transpose();
  origin /= std::max<double>(1, static_cast<double>(proposal.eyes.left.size() + proposal.eyes.right.size()));
  const auto to_frame = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = p - origin;
    return Eigen::Vector3d(f.left.dot(d), f.up.dot(d), f.forward.dot(d));
  };
  Positions framed(V.rows(), 3);
  for (Eigen::Index i = 0; i < V.rows(); ++i) framed.row(i) = to_frame(V.row(i).transpose()).transpose();
  VertexColours colours(V.rows(), 3);
  colours.rowwise() = Eigen::RowVector3f(0.80f, 0.74f, 0.70f);
  for (const std::vector<int>* set : {&proposal.eyes.left, &proposal.eyes.right})
    for (int v : *set) colours.row(v) << 0.45f, 0.6f, 0.95f;

  std::vector<Image> views;
  for (const RenderOptions::View view : {RenderOptions::View::front, RenderOptions::View::side}) {
    RenderOptions o;
    o.width = o.height = options.view_size;
    o.view = view;
    o.margin = 0.08;
    Image image = render(rig.neutral, framed, o, colours);
    std::vector<Eigen::Vector4i> placed;  // x, y, width, height of the labels drawn
    for (const auto& [name, landmark] : proposal.landmarks) {
      const Eigen::Vector3d p = framed.row(landmark.vertex).transpose();
      const bool right_side = name.size() > 6 && name.compare(name.size() - 6, 6, "_right") == 0;
      if (view == RenderOptions::View::side && right_side) continue;
      const Eigen::Vector3d pixel = project_to_image(framed, o, p);
      sheet_detail::dot(image, pixel.x(), pixel.y(), 4, sheet_detail::confidence_colour(landmark.confidence));
      const std::string label = fmt::format("{} {:.2f}", name, landmark.confidence);
      // Labels to the outside of the face: left of the dot for the face's right side (seen on the
      // picture's left), right of it otherwise.
      const bool label_left = view == RenderOptions::View::front && p.x() < 0;
      const int w = text_width(label, 1), h = 10;
      const int x = static_cast<int>(pixel.x()) + (label_left ? -6 - w : 6);
      int y = static_cast<int>(pixel.y()) - 4;
      // Move a label down until it no longer covers one already placed.
      for (int attempt = 0; attempt < 6; ++attempt) {
        const bool clash = std::any_of(placed.begin(), placed.end(), [&](const Eigen::Vector4i& r) {
          return x < r[0] + r[2] && r[0] < x + w && y < r[1] + r[3] && r[1] < y + h;
        });
        if (!clash) break;
        y += h;
      }
      placed.emplace_back(x, y, w, h);
      draw_text(image, x, y, label, 1, Eigen::Vector3f(0.05f, 0.05f, 0.05f));
    }
    views.push_back(std::move(image));
  }
  Image body = hconcat(views, Eigen::Vector3f(0.97f, 0.97f, 0.97f));
  const int band = text_band_height(2);
  Image title(body.width, band, Eigen::Vector3f(0.97f, 0.97f, 0.97f));
  draw_text(title, 8, 4,
            fmt::format("{}: {} proposed landmarks (front | left side)", rig.name, proposal.landmarks.size()), 2,
            Eigen::Vector3f(0.05f, 0.05f, 0.05f));
  draw_text(title, title.width - text_width("green: sure  orange: check  red: doubtful", 1) - 8, 8,
            "green: sure  orange: check  red: doubtful", 1, Eigen::Vector3f(0.2f, 0.2f, 0.2f));
  return vconcat({title, body}, Eigen::Vector3f(0.97f, 0.97f, 0.97f));
}

}  // namespace retarget
