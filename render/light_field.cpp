#include "render/light_field.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <complex>

#include "core/error.h"
#include "render/render.h"

namespace retarget {

namespace {

constexpr int kViews = 10;
constexpr int kOutlineAngles = 64;

// The ten view directions: the dodecahedron's vertices with z > 0, and the two with z = 0, y > 0
// (one of each opposite pair).
const std::array<Eigen::Vector3d, kViews>& view_directions() {
  static const std::array<Eigen::Vector3d, kViews> directions = [] {
    const double phi = (1 + std::sqrt(5.0)) / 2, inv = 1 / phi;
    return std::array<Eigen::Vector3d, kViews>{Eigen::Vector3d(1, 1, 1),     Eigen::Vector3d(-1, 1, 1),
                                               Eigen::Vector3d(1, -1, 1),    Eigen::Vector3d(-1, -1, 1),
                                               Eigen::Vector3d(0, inv, phi), Eigen::Vector3d(0, -inv, phi),
                                               Eigen::Vector3d(phi, 0, inv), Eigen::Vector3d(-phi, 0, inv),
                                               Eigen::Vector3d(inv, phi, 0), Eigen::Vector3d(-inv, phi, 0)};
  }();
  return directions;
}

// The (n, m) pairs of the Zernike moments kept, in order.
std::vector<std::array<int, 2>> zernike_indices(int order) {
  std::vector<std::array<int, 2>> nm;
  for (int n = 0; n <= order; ++n)
    for (int m = n % 2; m <= n; m += 2) nm.push_back({n, m});
  return nm;
}

double factorial(int k) { return std::tgamma(k + 1.0); }

// Coefficients c[s] of the radial polynomial R_nm(rho) = sum_s c[s] rho^(n - 2s).
std::vector<double> radial_coefficients(int n, int m) {
  std::vector<double> c;
  for (int s = 0; s <= (n - m) / 2; ++s)
    c.push_back((s % 2 ? -1.0 : 1.0) * factorial(n - s) /
                (factorial(s) * factorial((n + m) / 2 - s) * factorial((n - m) / 2 - s)));
  return c;
}

}  // namespace

void LightFieldOptions::validate(const std::string& key_path) const {
  if (size < 16 || size > 1024) throw Error(key_path + ".size", fmt::format("expected 16..1024 pixels, got {}", size));
  if (zernike_order < 1 || zernike_order > 20)
    throw Error(key_path + ".zernike_order", fmt::format("expected 1..20, got {}", zernike_order));
  if (fourier < 1 || fourier >= kOutlineAngles / 2)
    throw Error(key_path + ".fourier", fmt::format("expected 1..{}, got {}", kOutlineAngles / 2 - 1, fourier));
}

int light_field_view_size(const LightFieldOptions& options) {
  return static_cast<int>(zernike_indices(options.zernike_order).size()) + options.fourier;
}

int light_field_size(const LightFieldOptions& options) { return kViews * light_field_view_size(options); }

Eigen::VectorXf silhouette_descriptor(const std::vector<uint8_t>& mask, int width, int height,
                                      const LightFieldOptions& options) {
  const std::vector<std::array<int, 2>> nm = zernike_indices(options.zernike_order);
  Eigen::VectorXf out = Eigen::VectorXf::Zero(light_field_view_size(options));
  if (mask.size() != static_cast<size_t>(width) * height)
    throw Error("silhouette", fmt::format("{} mask values for {} x {} pixels", mask.size(), width, height));
  double cx = 0, cy = 0, area = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (mask[static_cast<size_t>(y) * width + x]) cx += x + 0.5, cy += y + 0.5, area += 1;
  if (area == 0) return out;
  cx /= area, cy /= area;
  double radius = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (mask[static_cast<size_t>(y) * width + x]) radius = std::max(radius, std::hypot(x + 0.5 - cx, y + 0.5 - cy));
  radius += 0.5;  // the farthest pixel's far edge

  std::vector<std::vector<double>> coefficients;
  for (const auto& [n, m] : nm) coefficients.push_back(radial_coefficients(n, m));
  std::vector<std::complex<double>> moment(nm.size());
  std::array<double, kOutlineAngles> outline{};
  std::vector<double> rho_power(static_cast<size_t>(options.zernike_order) + 1);
  std::vector<std::complex<double>> turn(static_cast<size_t>(options.zernike_order) + 1);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      if (!mask[static_cast<size_t>(y) * width + x]) continue;
      const double dx = x + 0.5 - cx, dy = cy - (y + 0.5), r = std::hypot(dx, dy);
      const double rho = r / radius, theta = std::atan2(dy, dx);
      rho_power[0] = 1;
      turn[0] = 1;
      const std::complex<double> step = std::polar(1.0, -theta);
      for (size_t k = 1; k < rho_power.size(); ++k) rho_power[k] = rho_power[k - 1] * rho, turn[k] = turn[k - 1] * step;
      for (size_t i = 0; i < nm.size(); ++i) {
        const auto [n, m] = nm[i];
        double radial = 0;
        for (size_t s = 0; s < coefficients[i].size(); ++s) radial += coefficients[i][s] * rho_power[n - 2 * s];
        moment[i] += radial * turn[static_cast<size_t>(m)];
      }
      const int bin = static_cast<int>(std::floor((theta + M_PI) / (2 * M_PI) * kOutlineAngles)) % kOutlineAngles;
      outline[static_cast<size_t>(bin)] = std::max(outline[static_cast<size_t>(bin)], rho);
    }
  // Z_nm = (n + 1) / pi * sum over the disk, each pixel 1 / radius^2 of it; |Z_00| = area / pi.
  const double z00 = std::abs(moment[0]);
  for (size_t i = 0; i < nm.size(); ++i) out[static_cast<int>(i)] = static_cast<float>(std::abs(moment[i]) / z00);
  std::complex<double> f0 = 0;
  for (double r : outline) f0 += r;
  for (int j = 1; j <= options.fourier; ++j) {
    std::complex<double> fj = 0;
    for (int k = 0; k < kOutlineAngles; ++k)
      fj += outline[static_cast<size_t>(k)] * std::polar(1.0, -2 * M_PI * j * k / kOutlineAngles);
    out[static_cast<int>(nm.size()) + j - 1] = static_cast<float>(std::abs(fj) / std::abs(f0));
  }
  return out;
}

std::vector<uint8_t> light_field_silhouette(const Mesh& topology, const Positions& vertices, int view,
                                            const LightFieldOptions& options) {
  options.validate();
  if (view < 0 || view >= kViews) throw Error("light field", fmt::format("view {} is not in 0..{}", view, kViews - 1));
  const Eigen::Vector3d d = view_directions()[static_cast<size_t>(view)].normalized();
  RenderOptions r;
  r.width = r.height = options.size;
  r.supersample = 1;  // one sample per pixel: a pixel is background or mesh, never a blend
  r.margin = 0.02;
  r.yaw_deg = std::atan2(d.x(), d.z()) * 180 / M_PI;
  r.pitch_deg = std::asin(d.y()) * 180 / M_PI;
  r.colour = Eigen::Vector3f(0, 0, 0);
  r.background = Eigen::Vector3f(1, 0, 1);  // no shade of the grey surface is magenta
  r.smooth_shading = false;
  const Image image = render(topology, vertices, r);
  std::vector<uint8_t> mask(static_cast<size_t>(options.size) * options.size);
  for (size_t i = 0; i < mask.size(); ++i) {
    const uint8_t* p = image.rgb.data() + 3 * i;
    mask[i] = !(p[0] == 255 && p[1] == 0 && p[2] == 255);
  }
  return mask;
}

Eigen::VectorXf light_field_descriptor(const Mesh& topology, const Positions& vertices,
                                       const LightFieldOptions& options) {
  const int per_view = light_field_view_size(options);
  Eigen::VectorXf out(light_field_size(options));
  for (int v = 0; v < kViews; ++v)
    out.segment(v * per_view, per_view) = silhouette_descriptor(light_field_silhouette(topology, vertices, v, options),
                                                                options.size, options.size, options);
  return out;
}

double light_field_distance(const Eigen::VectorXf& a, const Eigen::VectorXf& b) {
  if (a.size() != b.size())
    throw Error("light field distance", fmt::format("descriptors of {} and {} values", a.size(), b.size()));
  return (a - b).cwiseAbs().cast<double>().sum();
}

}  // namespace retarget
