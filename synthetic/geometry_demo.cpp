#include "synthetic/geometry_demo.h"

#include <cmath>
#include <filesystem>
#include <functional>

#include "core/error.h"
#include "core/log.h"
#include "core/timer.h"
#include "geometry/deformation_transfer.h"
#include "geometry/dr_features.h"
#include "geometry/mesh_io.h"
#include "geometry/metrics.h"
#include "geometry/primitive_meshes.h"
#include "geometry/reconstruction.h"
#include "geometry/rigid_alignment.h"

namespace retarget {

namespace fs = std::filesystem;

void GeometryDemoOptions::validate() const {
  if (out.empty()) throw Error("demo.out", "expected an output folder");
  if (source_resolution < 8) throw Error("demo.source_resolution", "expected at least 8");
  if (target_columns < 8 || target_rows < 8) throw Error("demo.target_columns/rows", "expected at least 8 each");
}

namespace {

// A face-like height field over [-1, 1]^2 (u across, v up), units cm after scaling:
// a dome with a nose ridge, brow, eye sockets and a mouth crease. `style` changes the
// proportions so source and target differ in shape as well as in topology.
struct FaceShape {
  double width, height, depth, nose, eye_depth;
  double z(double u, double v) const {
    const double dome = depth * std::sqrt(std::max(0.0, 1 - 0.55 * u * u - 0.45 * v * v));
    const double nose_ridge = nose * std::exp(-(u * u) / 0.02 - (v + 0.05) * (v + 0.05) / 0.08);
    const double sockets = -eye_depth * (std::exp(-((u - 0.38) * (u - 0.38) + (v - 0.28) * (v - 0.28)) / 0.02) +
                                         std::exp(-((u + 0.38) * (u + 0.38) + (v - 0.28) * (v - 0.28)) / 0.02));
    return dome + nose_ridge + sockets;
  }
};

Mesh face(int columns, int rows, const FaceShape& shape) {
  Mesh mesh = quad_grid(columns, rows, 2.0, 2.0);
  for (int i = 0; i < mesh.vertex_count(); ++i) {
    const double u = mesh.vertices(i, 0) - 1, v = mesh.vertices(i, 1) - 1;
    mesh.vertices.row(i) << shape.width * u, shape.height * v, shape.z(u, v);
  }
  return mesh;
}

// An expression as a displacement field in the face's normalised coordinates (u, v),
// scaled by the face's own size, so "the same expression" is defined on any face.
struct Expression {
  const char* name;
  std::function<Eigen::Vector3d(double u, double v)> offset;  // in units of the face half-height
};

double demo_bump(double u, double v, double cu, double cv, double r) {
  return std::exp(-((u - cu) * (u - cu) + (v - cv) * (v - cv)) / (r * r));
}

std::vector<Expression> expressions() {
  auto smooth = [](double a, double b, double x) {
    const double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
    return t * t * (3 - 2 * t);
  };
  return {
      {"jawOpen",
       [=](double u, double v) {
         const double jaw = (1 - smooth(-0.45, -0.15, v)) * (1 - smooth(0.55, 0.9, std::abs(u)));
         return Eigen::Vector3d(0, -0.22 * jaw, -0.06 * jaw);
       }},
      {"mouthSmile_L",
       [](double u, double v) {
         const double b = demo_bump(u, v, 0.3, -0.4, 0.22);
         return Eigen::Vector3d(0.06 * b, 0.08 * b, -0.02 * b);
       }},
      {"browInnerUp",
       [](double u, double v) {
         const double b = demo_bump(u, v, 0.15, 0.5, 0.2) + demo_bump(u, v, -0.15, 0.5, 0.2);
         return Eigen::Vector3d(0, 0.07 * b, 0.01 * b);
       }},
      {"cheekPuff",
       [](double u, double v) {
         const double b = demo_bump(u, v, 0.45, -0.2, 0.25) + demo_bump(u, v, -0.45, -0.2, 0.25);
         return Eigen::Vector3d(0.03 * (u > 0 ? b : -b), 0, 0.12 * b);
       }},
  };
}

Positions apply(const Mesh& mesh, const FaceShape& shape, const Expression& e) {
  Positions out = mesh.vertices;
  for (int i = 0; i < mesh.vertex_count(); ++i) {
    const double u = mesh.vertices(i, 0) / shape.width, v = mesh.vertices(i, 1) / shape.height;
    out.row(i) += shape.height * e.offset(u, v).transpose();
  }
  return out;
}

int nearest_vertex(const Mesh& mesh, const FaceShape& shape, double u, double v) {
  int best = 0;
  double best_d = 1e300;
  for (int i = 0; i < mesh.vertex_count(); ++i) {
    const double du = mesh.vertices(i, 0) / shape.width - u, dv = mesh.vertices(i, 1) / shape.height - v;
    if (du * du + dv * dv < best_d) best_d = du * du + dv * dv, best = i;
  }
  return best;
}

}  // namespace

std::vector<GeometryDemoRow> run_geometry_demo(const GeometryDemoOptions& options) {
  options.validate();
  const FaceShape source_shape{7.0, 9.0, 5.0, 1.2, 0.5};
  const FaceShape target_shape{8.5, 8.0, 4.0, 0.6, 0.9};  // rounder, flatter, deeper eyes
  const Mesh source = face(options.source_resolution, options.source_resolution, source_shape);
  const Mesh target = face(options.target_columns, options.target_rows, target_shape);
  log::info("source face: {} vertices; target face: {} vertices (its own topology)", source.vertex_count(),
            target.vertex_count());

  // 42 landmarks on a 7 x 6 lattice of (u, v), found on each mesh; eyes at (+-0.38, 0.28).
  std::vector<LandmarkPair> landmarks;
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 6; ++j) {
      const double u = -0.8 + 1.6 * i / 6, v = -0.8 + 1.6 * j / 5;
      landmarks.push_back({nearest_vertex(source, source_shape, u, v), nearest_vertex(target, target_shape, u, v)});
    }
  auto eyes_of = [](const Mesh& m, const FaceShape& s) {
    return EyeLandmarks{{nearest_vertex(m, s, 0.38, 0.28)}, {nearest_vertex(m, s, -0.38, 0.28)}};
  };
  const double source_mm = millimetres_per_unit(source.vertices, eyes_of(source, source_shape));
  const double target_mm = millimetres_per_unit(target.vertices, eyes_of(target, target_shape));

  const fs::path out(options.out);
  write_mesh((out / "source" / "neutral.obj").string(), source);
  write_mesh((out / "target" / "neutral.obj").string(), target);

  Stopwatch clock;
  const DrFeatures features(source);
  const Reconstruction reconstruction(source);
  const DeformationTransfer transfer(source, target, landmarks);
  log::info("factorised reconstruction and deformation transfer in {:.2f} s", clock.seconds());

  std::vector<GeometryDemoRow> rows;
  for (const Expression& e : expressions()) {
    GeometryDemoRow row;
    row.expression = e.name;
    const Positions expression = apply(source, source_shape, e);
    write_mesh((out / "source" / (row.expression + ".obj")).string(), with_positions(source, expression));

    clock.restart();
    const DrFeatureMatrix f = features.compute(expression);
    row.features_ms = clock.restart() * 1e3;
    Positions back = reconstruction.reconstruct(f);
    row.reconstruction_ms = clock.restart() * 1e3;
    back = rigid_alignment(back, expression).apply(back);
    const VertexError round = vertex_error(back, expression, source_mm);
    row.roundtrip_mean_mm = round.mean, row.roundtrip_max_mm = round.max;
    write_mesh((out / "roundtrip" / (row.expression + ".obj")).string(), with_positions(source, back));

    clock.restart();
    const Positions moved = transfer.transfer(expression);
    row.transfer_ms = clock.seconds() * 1e3;
    const Positions truth = apply(target, target_shape, e);
    const VertexError dt = vertex_error(moved, truth, target_mm);
    row.transfer_mean_mm = dt.mean, row.transfer_max_mm = dt.max;
    write_mesh((out / "target" / (row.expression + ".obj")).string(), with_positions(target, moved));
    write_mesh((out / "target_truth" / (row.expression + ".obj")).string(), with_positions(target, truth));
    rows.push_back(row);
  }
  return rows;
}

}  // namespace retarget
