// Writes the fuzzers' seed corpora: small valid files of every kind they read, so that no binary
// blob is checked in. Usage: write_fuzz_seeds OUT [CONFIGS]
//   ->  OUT/{obj,ply,off,gltf,yaml,manifest,take,weights}/...; with CONFIGS (the repository's
//   configs/ folder) also OUT/train/: its training profiles as train_config_fuzzer reads them.
#include <tiny_gltf.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "bundle/bundle_format.h"
#include "core/config_base.h"
#include "geometry/mesh_io.h"
#include "geometry/primitive_meshes.h"

namespace fs = std::filesystem;
using namespace retarget;

namespace {

void write_text(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

void meshes(const fs::path& out) {
  const Mesh grid = quad_grid(2, 2, 2.0, 2.0);
  const Mesh sphere = uv_sphere(4, 5, 1.0);
  for (const auto& [name, mesh] : {std::pair{"grid", grid}, std::pair{"sphere", sphere}}) {
    write_mesh((out / "obj" / (std::string(name) + ".obj")).string(), mesh);
    write_mesh((out / "off" / (std::string(name) + ".off")).string(), mesh);
    write_mesh((out / "ply" / (std::string(name) + "_binary.ply")).string(), mesh, MeshWriteOptions{true});
    write_mesh((out / "ply" / (std::string(name) + "_ascii.ply")).string(), mesh, MeshWriteOptions{false});
  }
  write_text(out / "obj" / "variants.obj",
             "# variants\nv 0 0 0\nv 1 0 0 1\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
             "f 1/1/1 2/1/1 3/1/1\nf -4//1 -2//1 \\\n -1//1\n");
  write_text(out / "off" / "variants.off",
             "# a square\nCOFF 4 2 0\n0 0 0 1 0 0 1\n1 0 0 1 0 0 1\n1 1 0 0 1 0 1\n0 1 0 0 0 1 1\n"
             "3 0 1 2 255 0 0\n3 0 2 3\n");
  write_text(out / "ply" / "variants.ply",
             "ply\nformat ascii 1.0\ncomment normals and colours\nelement vertex 4\nproperty double x\n"
             "property double y\nproperty double z\nproperty float nx\nproperty float ny\nproperty float nz\n"
             "property uchar red\nelement face 2\nproperty list uchar uint vertex_indices\nproperty int flags\n"
             "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
             "0 0 0 0 0 1 9\n1 0 0 0 0 1 9\n1 1 0 0 0 1 9\n0 1 0 0 0 1 9\n3 0 1 2 0\n3 0 2 3 1\n0 1\n");
  // Big-endian binary with a short-count list.
  std::string big =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list ushort int vertex_indices\nend_header\n";
  const auto put = [&big](const void* value, size_t size) {
    const char* bytes = static_cast<const char*>(value);
    for (size_t k = size; k-- > 0;) big += bytes[k];
  };
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(&v, 4);
  const uint16_t degree = 3;
  put(&degree, 2);
  for (int32_t index : {0, 1, 2}) put(&index, 4);
  write_text(out / "ply" / "big_endian.ply", big);
}

// A quad with uint16 indices and two morph targets, one of them sparse.
void gltf(const fs::path& out) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.buffers.emplace_back();
  std::vector<unsigned char>& data = model.buffers[0].data;
  const auto view = [&](const void* values, size_t bytes) {
    while (data.size() % 4) data.push_back(0);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = data.size();
    v.byteLength = bytes;
    data.resize(data.size() + bytes);
    std::memcpy(data.data() + v.byteOffset, values, bytes);
    model.bufferViews.push_back(v);
    return static_cast<int>(model.bufferViews.size()) - 1;
  };
  const auto accessor = [&](int view_index, int component, size_t count, int type) {
    tinygltf::Accessor a;
    a.bufferView = view_index;
    a.componentType = component;
    a.count = count;
    a.type = type;
    if (type == TINYGLTF_TYPE_VEC3) {
      a.minValues = {-10, -10, -10};
      a.maxValues = {10, 10, 10};
    }
    model.accessors.push_back(a);
    return static_cast<int>(model.accessors.size()) - 1;
  };
  const float positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const float smile[] = {0, 0, 0.5f, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  const uint16_t indices[] = {0, 1, 2, 0, 2, 3};
  const int position =
      accessor(view(positions, sizeof positions), TINYGLTF_COMPONENT_TYPE_FLOAT, 4, TINYGLTF_TYPE_VEC3);
  const int target = accessor(view(smile, sizeof smile), TINYGLTF_COMPONENT_TYPE_FLOAT, 4, TINYGLTF_TYPE_VEC3);
  const int index =
      accessor(view(indices, sizeof indices), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 6, TINYGLTF_TYPE_SCALAR);
  const int sparse = accessor(-1, TINYGLTF_COMPONENT_TYPE_FLOAT, 4, TINYGLTF_TYPE_VEC3);
  {
    const uint8_t rows[] = {2};
    const float values[] = {0, -0.25f, 0};
    tinygltf::Accessor& a = model.accessors[sparse];
    a.sparse.isSparse = true;
    a.sparse.count = 1;
    a.sparse.indices.bufferView = view(rows, sizeof rows);
    a.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
    a.sparse.values.bufferView = view(values, sizeof values);
  }
  tinygltf::Primitive primitive;
  primitive.attributes["POSITION"] = position;
  primitive.indices = index;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  primitive.targets = {{{"POSITION", target}}, {{"POSITION", sparse}}};
  tinygltf::Mesh mesh;
  mesh.name = "Face";
  mesh.primitives = {primitive};
  tinygltf::Value::Array names{tinygltf::Value(std::string("smile")), tinygltf::Value(std::string("frown"))};
  tinygltf::Value::Object extras;
  extras["targetNames"] = tinygltf::Value(names);
  mesh.extras = tinygltf::Value(extras);
  model.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes = {0};
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  fs::create_directories(out / "gltf");
  tinygltf::TinyGLTF writer;
  for (const bool binary : {true, false}) {
    const fs::path path = out / "gltf" / (binary ? "face.glb" : "face.gltf");
    if (!writer.WriteGltfSceneToFile(&model, path.string(), false, true, true, binary))
      throw std::runtime_error("cannot write " + path.string());
  }
}

void yaml(const fs::path& out) {
  write_text(
      out / "yaml" / "rig.yaml",
      "neutral: neutral.obj\ntargets: offsets\nunits: cm\ncontrollers:\n  - {name: a, file: a.obj}\n"
      "  - {name: b, file: b.obj, range: [-1, 2]}\nlandmarks: {nose_tip: 4}\neyes: {left: [0, 1], right: [6]}\n");
  write_text(out / "yaml" / "override.yaml",
             "model.latent_size=[9, 32, 1]\nmodel: {latent_size: 25, channels: [16, 32]}\n"
             "training:\n  lr: 1.0e-3\n  epochs: 10\n  stages:\n    - {lr: 0.5, epochs: 3}\n    - &s {lr: .inf}\n"
             "    - *s\nflag: true\nname: \"quoted \\u00e9\"\n");
}

void manifest(const fs::path& out) {
  BundleMetadata m;
  m.software_version = "0.1.0";
  m.created = "2026-11-21T09:30:00Z";
  m.human = {"ict", 11248, 11144, "0123456789abcdef", 25, "cm", DrOptions{}, {}};
  m.avatar = {"lapin", 900, 880, "fedcba9876543210", 25, "m", DrOptions{}, {0, 3, 17}};
  m.translation_hidden = 100;
  write_text(out / "manifest" / "manifest.yaml", bundle_manifest_text(m));
  write_text(out / "manifest" / "metadata.json", bundle_metadata_json(m));
  m.rig = BundleRigMetadata{{{"jawOpen", 0, 1}, {"browRaise_L", -1, 1}, {"squash", 0, 2.5}}, 16.1};
  write_text(out / "manifest" / "manifest_rig.yaml", bundle_manifest_text(m));
  write_text(out / "manifest" / "metadata_rig.json", bundle_metadata_json(m));
}

// The training profiles under CONFIGS/train as one document each, the way train_config_fuzzer
// reads its input: their bases merged (core/config_base.h) and the run's files, which no profile
// names, set as `retarget train --set/--out` would (placeholders: the fuzzer opens no run).
void train_profiles(const fs::path& out, const fs::path& configs) {
  const fs::path train = configs / "train";
  for (const auto& entry : fs::recursive_directory_iterator(train)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".yaml") continue;
    ConfigNode root = load_config_with_bases(entry.path().string());
    const bool vae = root.has("task") && root.child("task").as<std::string>() == "vae";
    const std::vector<const char*> run_files =
        vae ? std::vector<const char*>{"data.dataset=dataset", "output=run"}
            : std::vector<const char*>{"data.human_vae=human_vae", "data.avatar_vae=avatar_vae",
                                       "data.correspondences=correspondences", "data.triplets=annotation",
                                       "output=run"};
    for (const char* assignment : run_files) root.apply_override(assignment);
    YAML::Emitter text;
    text << root.yaml();
    std::string name = entry.path().lexically_relative(train).generic_string();
    for (char& c : name)
      if (c == '/') c = '_';
    write_text(out / "train" / name, std::string(text.c_str()) + "\n");
  }
}

}  // namespace

// Takes as Live Link Face, JSON lines and MediaPipe write them; weights tables as retarget-infer
// --weights writes them.
void takes_and_weights(const fs::path& out) {
  write_text(out / "take" / "live_link.csv",
             "Timecode,BlendShapeCount,EyeBlinkLeft,EyeBlinkRight,JawOpen,MouthSmileLeft,BrowInnerUp,HeadYaw\n"
             "12:34:56:07.123,61,0.03,0.04,0.41,0.2,0.1,0.01\n"
             "12:34:56:08.123,61,0.5,0.6,0.0,1.2,-0.1,0.02\n\n");
  write_text(out / "take" / "nested.jsonl",
             "{\"timecode\": \"00:00:01\", \"weights\": {\"eyeBlinkLeft\": 0.03, \"jawOpen\": 0.41}}\n"
             "{\"timecode\": 1.25, \"eyeBlink_L\": 0.5, \"mouthSmile_R\": 0.2}\n");
  write_text(out / "take" / "mediapipe.jsonl",
             "[{\"index\": 0, \"score\": 0.0001, \"categoryName\": \"_neutral\"}, {\"score\": 0.41, "
             "\"categoryName\": \"jawOpen\"}]\n"
             "{\"timecode\": 2, \"blendshapes\": [[{\"categoryName\": \"cheekPuff\", \"score\": 0.3}]]}\n");
  write_text(out / "weights" / "weights.csv",
             "frame,jawOpen,smileLeft,blink,residual_mm\n"
             "take_0001,0.25,0,1,0.125\r\n"
             "\"a, b\",-0.5, 1e-3 ,0.75,nan\n");
  write_text(out / "weights" / "bare.csv", "frame,jawOpen,smileLeft,blink\n0,1,2,3\n");
}

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3) {
    std::cerr << "usage: write_fuzz_seeds OUT [CONFIGS]\n";
    return 2;
  }
  const fs::path out = argv[1];
  meshes(out);
  gltf(out);
  yaml(out);
  manifest(out);
  takes_and_weights(out);
  if (argc == 3) train_profiles(out, argv[2]);
  return 0;
}
