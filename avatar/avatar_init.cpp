#include "avatar/avatar_init.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>

#include "avatar/landmark_sheet.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "geometry/metrics.h"
#include "render/render.h"

namespace retarget {

namespace fs = std::filesystem;

Rig with_proposed_landmarks(const Rig& rig, const LandmarkProposal& proposal) {
  Rig out = rig;
  out.landmarks.clear();
  for (const auto& [name, landmark] : proposal.landmarks) out.landmarks[name] = landmark.vertex;
  out.eyes = proposal.eyes;
  // The parts, in the rig's vocabulary (an eye, the teeth; pieces inside the mouth that cannot be
  // told apart, and others, as "other").
  out.parts.clear();
  for (const ProposedPart& part : proposal.parts) {
    RigPart p;
    p.name = part.name;
    p.vertices = part.vertices;
    p.kind = part.kind == ProposedPart::Kind::eye ? (part.name == "eye_left" ? PartKind::eye_left : PartKind::eye_right)
             : part.kind == ProposedPart::Kind::teeth ? PartKind::teeth
                                                      : PartKind::other;
    out.parts.push_back(std::move(p));
  }
  return out;
}

namespace avatar_init_detail {

Eigen::Vector3d centre_of(const Positions& V, const std::vector<int>& vertices) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v : vertices) c += V.row(v).transpose();
  return vertices.empty() ? c : Eigen::Vector3d(c / static_cast<double>(vertices.size()));
}

std::string vector_text(const Eigen::Vector3d& v) {
  return fmt::format("[{:.6g}, {:.6g}, {:.6g}]", v.x(), v.y(), v.z());
}

// rig.yaml as written by write_rig_folder, with the proposals' confidences and the frame,
// scale and parts added as comments.
void write_commented_rig_yaml(const std::string& path, const Rig& rig, const LandmarkProposal& p) {
  const YAML::Node written = YAML::LoadFile(path);
  const double mm = millimetres_per_unit(rig.neutral.vertices, p.eyes);
  write_file_atomically(path, [&](std::ostream& out) {
    out << "# Written by `retarget avatar init` from " << (rig.source.empty() ? rig.name : rig.source) << ".\n"
        << "# Landmarks and eyes are PROPOSALS read off the rig (see proposals.yaml and landmarks.png);\n"
        << "# check them before training, and correct any by editing the vertex index.\n"
        << fmt::format("# Face frame (rig coordinates): left {}, up {}, forward {}.\n", vector_text(p.frame.left),
                       vector_text(p.frame.up), vector_text(p.frame.forward))
        << fmt::format("# Mirror plane: normal {} . x = {:.6g} (mirrored points within {:.2f}% of the head's size).\n",
                       vector_text(p.mirror.normal), p.mirror.offset, 100 * p.mirror.error)
        << fmt::format("# Scale: eye centres {:.6g} {} apart, so {:.6g} mm per unit by the paper's 10 cm convention.\n",
                       p.eye_distance, rig.units, mm);
    if (!p.parts.empty()) {
      out << "# Parts (pieces other than the head):\n";
      for (const ProposedPart& part : p.parts)
        out << fmt::format("#   {} ({}): {} vertices from {} to {}, centre {}\n", part.name, part_kind_name(part.kind),
                           part.vertices.size(), part.vertices.front(), part.vertices.back(), vector_text(part.centre));
    }
    out << "name: " << written["name"].as<std::string>() << "\n";
    if (written["units"]) out << "units: " << written["units"].as<std::string>() << "\n";
    out << "neutral: " << written["neutral"].as<std::string>() << "\n";
    if (written["targets"]) out << "targets: " << written["targets"].as<std::string>() << "\n";
    out << "controllers:\n";
    for (const YAML::Node& c : written["controllers"]) {
      YAML::Emitter e;
      e << YAML::Flow << c;
      out << "  - " << e.c_str() << "\n";
    }
    if (written["parts"]) {
      YAML::Emitter e;
      e << YAML::BeginMap << YAML::Key << "parts" << YAML::Value << written["parts"] << YAML::EndMap;
      out << e.c_str() << "\n";
    }
    out << "landmarks:\n";
    for (const auto& [name, landmark] : p.landmarks)
      out << fmt::format("  {}: {}  # confidence {:.2f}: {}\n", name, landmark.vertex, landmark.confidence,
                         landmark.how);
    out << "eyes:\n";
    for (int e = 0; e < 2; ++e) {
      const std::vector<int>& set = e == 0 ? p.eyes.left : p.eyes.right;
      out << (e == 0 ? "  left: [" : "  right: [");
      for (size_t i = 0; i < set.size(); ++i) out << (i ? ", " : "") << set[i];
      out << "]\n";
    }
  });
}

void write_proposals_yaml(const std::string& path, const Rig& rig, const LandmarkProposal& p) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  e << YAML::Key << "rig" << YAML::Value << (rig.source.empty() ? rig.name : rig.source);
  e << YAML::Key << "units" << YAML::Value << rig.units;
  e << YAML::Key << "eye_distance" << YAML::Value << p.eye_distance;
  e << YAML::Key << "mm_per_unit" << YAML::Value << millimetres_per_unit(rig.neutral.vertices, p.eyes);
  const auto vec = [&](const Eigen::Vector3d& v) {
    e << YAML::Flow << YAML::BeginSeq << v.x() << v.y() << v.z() << YAML::EndSeq;
  };
  e << YAML::Key << "frame" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "left" << YAML::Value;
  vec(p.frame.left);
  e << YAML::Key << "up" << YAML::Value;
  vec(p.frame.up);
  e << YAML::Key << "forward" << YAML::Value;
  vec(p.frame.forward);
  e << YAML::EndMap;
  e << YAML::Key << "mirror_plane" << YAML::Value << YAML::BeginMap << YAML::Key << "normal" << YAML::Value;
  vec(p.mirror.normal);
  e << YAML::Key << "offset" << YAML::Value << p.mirror.offset << YAML::Key << "error" << YAML::Value << p.mirror.error
    << YAML::EndMap;
  e << YAML::Key << "mouth_controller" << YAML::Value << p.mouth_controller;
  e << YAML::Key << "eye_controllers" << YAML::Value << YAML::Flow << p.eye_controllers;
  e << YAML::Key << "landmarks" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, l] : p.landmarks) {
    e << YAML::Key << name << YAML::Value << YAML::BeginMap << YAML::Key << "vertex" << YAML::Value << l.vertex
      << YAML::Key << "confidence" << YAML::Value << l.confidence << YAML::Key << "position" << YAML::Value;
    vec(rig.neutral.vertices.row(l.vertex).transpose());
    e << YAML::Key << "how" << YAML::Value << l.how << YAML::EndMap;
  }
  e << YAML::EndMap;
  e << YAML::Key << "parts" << YAML::Value << YAML::BeginSeq;
  for (const ProposedPart& part : p.parts) {
    e << YAML::BeginMap << YAML::Key << "name" << YAML::Value << part.name << YAML::Key << "kind" << YAML::Value
      << part_kind_name(part.kind) << YAML::Key << "centre" << YAML::Value;
    vec(part.centre);
    e << YAML::Key << "vertices" << YAML::Value << YAML::Flow << part.vertices << YAML::EndMap;
  }
  e << YAML::EndSeq;
  e << YAML::Key << "notes" << YAML::Value << p.notes;
  e << YAML::EndMap;
  write_file_atomically(path, [&](std::ostream& out) { out << e.c_str() << "\n"; });
}

}  // namespace avatar_init_detail

void write_avatar_folder(const std::string& folder, const Rig& rig, const LandmarkProposal& proposal) {
  const Rig proposed = with_proposed_landmarks(rig, proposal);
  write_rig_folder(folder, proposed);
  avatar_init_detail::write_proposals_yaml((fs::path(folder) / "proposals.yaml").string(), proposed, proposal);
  write_png((fs::path(folder) / "landmarks.png").string(), landmark_sheet(proposed, proposal));
  avatar_init_detail::write_commented_rig_yaml((fs::path(folder) / "rig.yaml").string(), proposed, proposal);
}

std::map<std::string, double> landmark_distances(const Rig& reference, const LandmarkProposal& proposal) {
  const Positions& V = reference.neutral.vertices;
  const int n = reference.neutral.vertex_count();
  double eye_distance = proposal.eye_distance;
  if (!reference.eyes.left.empty() && !reference.eyes.right.empty())
    eye_distance =
        (avatar_init_detail::centre_of(V, reference.eyes.left) - avatar_init_detail::centre_of(V, reference.eyes.right))
            .norm();
  std::map<std::string, double> out;
  for (const auto& [name, landmark] : proposal.landmarks) {
    const auto it = reference.landmarks.find(name);
    if (it == reference.landmarks.end()) continue;
    if (landmark.vertex >= n || it->second >= n)
      throw Error(reference.source, "the reference rig's mesh has " + std::to_string(n) +
                                        " vertices, fewer than the proposal refers to: not the same mesh");
    out[name] = (V.row(landmark.vertex) - V.row(it->second)).norm() / eye_distance;
  }
  return out;
}

}  // namespace retarget
