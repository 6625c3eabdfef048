// The light-field descriptor of a mesh (Chen et al. 2003, "On visual similarity based 3D model
// retrieval"; the paper's reference [51]), the similarity the CycleGAN+LFD baseline (its
// reference [44]) compares human and avatar shapes by: silhouettes of the mesh from the ten view
// directions of a dodecahedron's vertices (opposite vertices see the same silhouette mirrored,
// so ten of the twenty), each described by
//   - Zernike moment magnitudes |Z_nm| up to order `zernike_order` (region shape; invariant to
//     the silhouette's rotation in the image), divided by |Z_00| (its area), and
//   - Fourier descriptors of the centroid distance of its outline (contour shape): the DFT
//     magnitudes |F_1| .. |F_fourier| of r(angle) sampled at 64 angles, divided by |F_0|.
// Every silhouette is centred on its centroid and scaled to the unit disk, so the descriptor does
// not change with the mesh's position or size: a fox and a person compare by shape alone.
//
// Chen et al. also search 10 rotations of the camera set and the 60 ways to pair its views,
// because their models come in any orientation. Faces here share one frame (+y up, +z towards
// the viewer; render/render.h), so the views are compared as they stand: view i with view i.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "geometry/mesh.h"

namespace retarget {

struct LightFieldOptions {
  int size = 64;           // silhouette pixels per side, 16..1024
  int zernike_order = 10;  // moments |Z_nm| with n <= order, 0 <= m <= n, n - m even; 1..20
  int fourier = 10;        // Fourier descriptors of the outline, 1..31
  void validate(const std::string& key_path = "light_field") const;  // throws retarget::Error naming the key
};

// The number of values per view and in all (10 views).
int light_field_view_size(const LightFieldOptions& options);
int light_field_size(const LightFieldOptions& options);

// One silhouette's values (light_field_view_size): mask is width x height, row-major, nonzero =
// inside. An empty mask gives zeros.
Eigen::VectorXf silhouette_descriptor(const std::vector<uint8_t>& mask, int width, int height,
                                      const LightFieldOptions& options = {});

// The mesh's silhouette seen along view `view` (0..9), options.size pixels square, framed by its
// own bounding box: row-major, 1 = covered.
std::vector<uint8_t> light_field_silhouette(const Mesh& topology, const Positions& vertices, int view,
                                            const LightFieldOptions& options = {});

// The descriptor (light_field_size values): the ten views' silhouette descriptors in order.
// Throws retarget::Error for a vertex count other than topology's or a mesh without triangles.
Eigen::VectorXf light_field_descriptor(const Mesh& topology, const Positions& vertices,
                                       const LightFieldOptions& options = {});

// The light-field distance: the L1 distance between two descriptors of the same options.
double light_field_distance(const Eigen::VectorXf& a, const Eigen::VectorXf& b);

}  // namespace retarget
