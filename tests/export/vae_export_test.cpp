#include "export/vae_export.h"

#include <torch/script.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/tensor_io.h"
#include "models/graph_operator.h"
#include "tests/export/export_test_support.h"
#include "tests/export/python_torch.h"
#include "tests/models/model_test_support.h"

namespace retarget {
namespace {

namespace fs = std::filesystem;

// test::scratch_dir of tests/test_support.h, which the model tests cannot include (it pulls in
// geometry/): a fresh, empty folder below the build tree.
fs::path scratch_dir(const std::string& name) {
  const fs::path dir = fs::path(RETARGET_TEST_TMP) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

constexpr int64_t kRows = 12, kCols = 15, kV = kRows * kCols;  // a 180-vertex triangulated grid
using test::kExportTolerance;
using test::max_difference;
using test::read_text;
using test::write_text;

struct Fixture {
  MeshVae vae{nullptr};
  torch::Tensor min, max;  // [V, 9] normaliser ranges
  VaeExportMetadata metadata;
};

// A randomly initialised VAE (eval mode) with a non-trivial normaliser.
Fixture fixture(const MeshVaeOptions& options, bool dense_laplacian = false, const std::string& name = "rabbit") {
  torch::Tensor laplacian = graph_operator(test::grid_edges(kRows, kCols), kV);
  if (dense_laplacian) laplacian = laplacian.to_dense();
  Fixture f;
  f.vae = MeshVae(laplacian, options);
  f.vae->eval();
  f.min = torch::randn({kV, 9}) * 0.3;
  f.max = f.min + 0.05 + torch::rand({kV, 9}) * 2;
  f.metadata.kind = "avatar";
  f.metadata.name = name;
  f.metadata.fingerprint = "0123456789abcdef";
  f.metadata.software_version = RETARGET_VERSION;
  f.metadata.created = "2024-05-01T12:00:00Z";
  f.metadata.vertices = kV;
  f.metadata.latent = options.latent();
  f.metadata.features = options.features();
  return f;
}

MeshVaeOptions small_options() { return MeshVaeOptions(kV).channels({9, 16, 8, 1}).hidden(32).latent(6); }

// The project's normalisation, written out independently of the exported script.
torch::Tensor normalise(const Fixture& f, const torch::Tensor& x) { return 1.8 * (x - f.min) / (f.max - f.min) - 0.9; }
torch::Tensor denormalise(const Fixture& f, const torch::Tensor& y) {
  return (y + 0.9) / 1.8 * (f.max - f.min) + f.min;
}

// Raw features a little beyond the training range, as test data can be.
torch::Tensor raw_features(const Fixture& f, int64_t batch) {
  return f.min + (f.max - f.min) * (torch::rand({batch, kV, 9}) * 1.2 - 0.1);
}

torch::jit::Module load_with_metadata(const fs::path& path, std::string& metadata) {
  torch::jit::ExtraFilesMap extra{{"metadata.json", ""}};
  torch::jit::Module module = torch::jit::load(path.string(), torch::kCPU, extra);
  metadata = extra["metadata.json"];
  return module;
}

TEST_CASE("export_vae: the exported encoder and decoder equal the MeshVae in eval", "[vae_export]") {
  // {channels, order, dense operator, encoder skip}: the conv layers are unrolled from the options.
  const auto [channels, order, dense, skip] = GENERATE(table<std::vector<int64_t>, int64_t, bool, bool>({
      {{9, 16, 8, 1}, 2, false, false},
      {{9, 8, 8, 4, 2}, 3, false, false},
      {{9, 4}, 0, false, false},
      {{9, 6, 1}, 1, true, false},
      {{9, 16, 8, 1}, 2, false, true},
  }));
  INFO("channels " << channels.size() << " widths, order " << order << ", dense operator " << dense << ", skip "
                   << skip);
  torch::manual_seed(11);
  Fixture f = fixture(small_options().channels(channels).order(order).encoder_skip(skip), dense);
  const fs::path dir = scratch_dir("vae_export_equal");
  export_vae(*f.vae, f.min, f.max, f.metadata, dir.string());
  for (const auto& entry : fs::directory_iterator(dir)) {
    CHECK(entry.path().filename().string().find(".tmp") == std::string::npos);  // nothing left over
  }

  torch::jit::Module encoder = torch::jit::load((dir / "encoder.pt").string());
  torch::jit::Module decoder = torch::jit::load((dir / "decoder.pt").string());
  const torch::Tensor x = raw_features(f, 5);
  const torch::Tensor z = torch::randn({4, 6});
  torch::NoGradGuard no_grad;
  const VaeEncoding expected = f.vae->encode(normalise(f, x));

  const torch::Tensor mean = encoder.forward({x}).toTensor();
  CHECK(max_difference(mean, expected.mean) <= kExportTolerance);
  const auto code = encoder.get_method("encode")({x}).toTuple();
  CHECK(max_difference(code->elements()[0].toTensor(), expected.mean) <= kExportTolerance);
  CHECK(max_difference(code->elements()[1].toTensor(), expected.logvar) <= kExportTolerance);
  const auto normalised_code = encoder.get_method("encode_normalised")({normalise(f, x)}).toTuple();
  CHECK(max_difference(normalised_code->elements()[0].toTensor(), expected.mean) <= kExportTolerance);
  CHECK(max_difference(encoder.get_method("normalise")({x}).toTensor(), normalise(f, x)) <= kExportTolerance);

  const torch::Tensor decoded = f.vae->decode(z);
  CHECK(max_difference(decoder.forward({z}).toTensor(), denormalise(f, decoded)) <= kExportTolerance);
  CHECK(max_difference(decoder.get_method("decode")({z}).toTensor(), denormalise(f, decoded)) <= kExportTolerance);
  CHECK(max_difference(decoder.get_method("decode_normalised")({z}).toTensor(), decoded) <= kExportTolerance);
  CHECK(max_difference(decoder.get_method("denormalise")({decoded}).toTensor(), denormalise(f, decoded)) <=
        kExportTolerance);
  // Wrong shapes are caught with a message in the user's terms.
  CHECK_THROWS_WITH(encoder.forward({torch::zeros({2, 5, 9})}),
                    Catch::Contains("expected x of shape [B, 180, 9]") && Catch::Contains("got [2, 5, 9]"));
  CHECK_THROWS_WITH(decoder.forward({torch::zeros({2, 7})}), Catch::Contains("expected z of shape [B, 6]"));
  // A second call (the TorchScript executor optimises after profiling runs) gives the same.
  CHECK(max_difference(encoder.forward({x}).toTensor(), mean) == 0.0);
}

TEST_CASE("export_vae: the encoder's graph convs match MeshVae, widening, equal and narrowing, any batch",
          "[vae_export]") {
  // The script encoder computes terms first for out >= in and the Linear first (Clenshaw) for
  // out < in, in the [V, B, C] layout with one sparse product per term for the whole batch.
  const auto [channels, order] = GENERATE(table<std::vector<int64_t>, int64_t>({
      {{9, 32, 16, 16, 16, 1}, 2},  // the quick profile's widths
      {{9, 12, 12, 3}, 1},
      {{9, 5, 7, 7, 2}, 3},
      {{9, 3, 11}, 2},
  }));
  const int64_t batch = GENERATE(1, 4);
  INFO("channels " << channels.size() << " widths, order " << order << ", batch " << batch);
  torch::manual_seed(13);
  Fixture f = fixture(small_options().channels(channels).order(order));
  const fs::path dir = scratch_dir("vae_export_convs");
  export_vae(*f.vae, f.min, f.max, f.metadata, dir.string());
  torch::jit::Module encoder = torch::jit::load((dir / "encoder.pt").string());
  const torch::Tensor x = raw_features(f, batch);
  torch::NoGradGuard no_grad;
  const VaeEncoding expected = f.vae->encode(normalise(f, x));
  const auto code = encoder.get_method("encode")({x}).toTuple();
  CHECK(max_difference(code->elements()[0].toTensor(), expected.mean) <= kExportTolerance);
  CHECK(max_difference(code->elements()[1].toTensor(), expected.logvar) <= kExportTolerance);
  // Each sample of a batch is encoded as if alone.
  const torch::Tensor first = encoder.forward({x.narrow(0, batch - 1, 1)}).toTensor();
  CHECK(max_difference(first, expected.mean.narrow(0, batch - 1, 1)) <= kExportTolerance);
  {
    c10::InferenceMode inference;
    CHECK(max_difference(encoder.forward({x}).toTensor(), expected.mean) <= kExportTolerance);
  }
}

TEST_CASE("export_vae: attributes, buffers and metadata.json describe the export", "[vae_export]") {
  torch::manual_seed(12);
  Fixture f = fixture(small_options());
  const fs::path dir = scratch_dir("vae_export_metadata");
  export_vae(*f.vae, f.min, f.max, f.metadata, dir.string());

  for (const std::string part : {"encoder", "decoder"}) {
    INFO(part);
    std::string text;
    torch::jit::Module m = load_with_metadata(dir / (part + ".pt"), text);
    CHECK(m.attr("kind").toStringRef() == "avatar");
    CHECK(m.attr("name").toStringRef() == "rabbit");
    CHECK(m.attr("fingerprint").toStringRef() == "0123456789abcdef");
    CHECK(m.attr("version").toStringRef() == RETARGET_VERSION);
    CHECK(m.attr("created").toStringRef() == "2024-05-01T12:00:00Z");
    CHECK(m.attr("vertices").toInt() == kV);
    CHECK(m.attr("latent").toInt() == 6);
    CHECK(m.attr("features").toInt() == 9);
    CHECK(torch::equal(m.attr("normaliser_min").toTensor(), f.min));
    CHECK(torch::equal(m.attr("normaliser_max").toTensor(), f.max));
    CHECK_FALSE(m.is_training());

    const nlohmann::json json = nlohmann::json::parse(text);
    CHECK(json.at("format") == "retarget-vae");
    CHECK(json.at("part") == part);
    CHECK(json.at("kind") == "avatar");
    CHECK(json.at("name") == "rabbit");
    CHECK(json.at("fingerprint") == "0123456789abcdef");
    CHECK(json.at("software_version") == RETARGET_VERSION);
    CHECK(json.at("vertices") == kV);
    CHECK(json.at("latent") == 6);
    CHECK(json.at("features") == 9);
    CHECK(json.at("architecture").at("channels") == std::vector<int64_t>{9, 16, 8, 1});
    CHECK(parse_vae_metadata_json(text, part) == f.metadata);
  }

  // The encoder stores the operator as dense index and value buffers.
  torch::jit::Module encoder = torch::jit::load((dir / "encoder.pt").string());
  const torch::Tensor l = f.vae->convs[0]->as<ChebyshevConvImpl>()->laplacian;
  CHECK(encoder.attr("laplacian_indices").toTensor().scalar_type() == torch::kInt64);
  CHECK(torch::equal(encoder.attr("laplacian_indices").toTensor(), l.indices()));
  CHECK(torch::equal(encoder.attr("laplacian_values").toTensor(), l.values()));
  // Weight and bias of three graph convs, the hidden layer and the two heads.
  CHECK(encoder.parameters().size() == 12);
  CHECK(torch::jit::load((dir / "decoder.pt").string()).parameters().size() == 4);

  const ExportedVae loaded = load_exported_vae(dir.string(), {kV, "0123456789abcdef"});
  CHECK(loaded.metadata == f.metadata);
  CHECK_FALSE(loaded.encoder.is_training());
  CHECK_FALSE(loaded.decoder.is_training());
  // Re-exporting replaces the files.
  VaeExportMetadata renamed = f.metadata;
  renamed.name = "rabbit2";
  export_vae(*f.vae, f.min, f.max, renamed, dir.string());
  CHECK(load_exported_vae(dir.string()).metadata.name == "rabbit2");
}

TEST_CASE("load_exported_vae checks the mesh topology", "[vae_export]") {
  torch::manual_seed(13);
  Fixture f = fixture(small_options());
  const fs::path dir = scratch_dir("vae_export_topology");
  export_vae(*f.vae, f.min, f.max, f.metadata, dir.string());
  CHECK_NOTHROW(load_exported_vae(dir.string(), {}));
  CHECK_NOTHROW(load_exported_vae(dir.string(), {kV, ""}));
  CHECK_THROWS_WITH(load_exported_vae(dir.string(), {4068, ""}),
                    Catch::Contains("encoder.pt") && Catch::Contains("exported for 180 vertices, the mesh has 4068"));
  CHECK_THROWS_WITH(
      load_exported_vae(dir.string(), {std::nullopt, "fedcba9876543210"}),
      Catch::Contains("encoder.pt") && Catch::Contains("0123456789abcdef") && Catch::Contains("fedcba9876543210"));
  CHECK_THROWS_AS(load_exported_vae(dir.string(), {kV, "fedcba9876543210"}), Error);
}

TEST_CASE("load_exported_vae: missing, truncated, garbage and foreign files", "[vae_export]") {
  torch::manual_seed(14);
  Fixture f = fixture(small_options());
  const fs::path dir = scratch_dir("vae_export_bad_files");
  const fs::path good = dir / "good", bad = dir / "bad";
  export_vae(*f.vae, f.min, f.max, f.metadata, good.string());

  auto fresh_copy = [&] {
    fs::remove_all(bad);
    fs::copy(good, bad);
  };
  CHECK_THROWS_WITH(load_exported_vae((dir / "nowhere").string()),
                    Catch::Contains("nowhere") && Catch::Contains("no such folder"));

  fresh_copy();
  fs::remove(bad / "decoder.pt");
  CHECK_THROWS_WITH(load_exported_vae(bad.string()), Catch::Contains("decoder.pt") && Catch::Contains("missing file"));

  fresh_copy();
  const std::string bytes = read_text(good / "encoder.pt");
  write_text(bad / "encoder.pt", bytes.substr(0, bytes.size() / 2));
  CHECK_THROWS_WITH(load_exported_vae(bad.string()),
                    Catch::Contains("encoder.pt") && Catch::Contains("cannot be read as a TorchScript module"));

  write_text(bad / "encoder.pt", "not a model at all\n");
  CHECK_THROWS_WITH(load_exported_vae(bad.string()),
                    Catch::Contains("encoder.pt") && Catch::Contains("cannot be read as a TorchScript module"));

  // A valid TorchScript file that export_vae did not write.
  torch::jit::Module foreign = make_script_module("__torch__.Foreign");
  foreign.define("def forward(self, x: Tensor) -> Tensor:\n    return x\n");
  foreign.save((bad / "encoder.pt").string());
  CHECK_THROWS_WITH(load_exported_vae(bad.string()),
                    Catch::Contains("encoder.pt") && Catch::Contains("not a retarget VAE export"));
  foreign.save((bad / "encoder.pt").string(), {{"metadata.json", "{\"format\": "}});
  CHECK_THROWS_WITH(load_exported_vae(bad.string()),
                    Catch::Contains("encoder.pt") && Catch::Contains("not valid JSON"));
  foreign.save((bad / "encoder.pt").string(), {{"metadata.json", "{\"format\": \"something-else\"}"}});
  CHECK_THROWS_WITH(load_exported_vae(bad.string()), Catch::Contains("not a retarget VAE export"));

  // The decoder in the encoder's place.
  fresh_copy();
  fs::copy_file(good / "decoder.pt", bad / "encoder.pt", fs::copy_options::overwrite_existing);
  CHECK_THROWS_WITH(load_exported_vae(bad.string()),
                    Catch::Contains("encoder.pt") && Catch::Contains("holds the decoder"));
}

TEST_CASE("load_exported_vae rejects an encoder and a decoder from different exports", "[vae_export]") {
  torch::manual_seed(15);
  const fs::path dir = scratch_dir("vae_export_mixed");
  Fixture rabbit = fixture(small_options(), false, "rabbit");
  Fixture cat = fixture(small_options(), false, "cat");
  export_vae(*rabbit.vae, rabbit.min, rabbit.max, rabbit.metadata, (dir / "rabbit").string());
  export_vae(*cat.vae, cat.min, cat.max, cat.metadata, (dir / "cat").string());
  fs::copy_file(dir / "cat" / "decoder.pt", dir / "rabbit" / "decoder.pt", fs::copy_options::overwrite_existing);
  CHECK_THROWS_WITH(load_exported_vae((dir / "rabbit").string()),
                    Catch::Contains("decoder.pt") && Catch::Contains("different exports") &&
                        Catch::Contains("\"cat\"") && Catch::Contains("\"rabbit\""));
}

TEST_CASE("export_vae rejects inconsistent inputs with a message", "[vae_export]") {
  torch::manual_seed(16);
  Fixture f = fixture(small_options());
  const std::string dir = scratch_dir("vae_export_rejects").string();
  auto export_with = [&](const VaeExportMetadata& metadata, const torch::Tensor& min, const torch::Tensor& max) {
    export_vae(*f.vae, min, max, metadata, dir);
  };
  VaeExportMetadata m = f.metadata;
  m.kind = "robot";
  CHECK_THROWS_WITH(export_with(m, f.min, f.max), Catch::Contains("vae_export.kind") && Catch::Contains("robot"));
  m = f.metadata;
  m.fingerprint.clear();
  CHECK_THROWS_WITH(export_with(m, f.min, f.max), Catch::Contains("vae_export.fingerprint"));
  m = f.metadata;
  m.latent = 25;
  CHECK_THROWS_WITH(export_with(m, f.min, f.max),
                    Catch::Contains("vae_export.latent") && Catch::Contains("25") && Catch::Contains("6"));
  m = f.metadata;
  m.vertices = 181;
  CHECK_THROWS_WITH(export_with(m, f.min, f.max), Catch::Contains("vae_export.vertices") && Catch::Contains("181"));

  CHECK_THROWS_WITH(export_with(f.metadata, f.min.narrow(0, 0, 10), f.max),
                    Catch::Contains("normaliser") && Catch::Contains("[180, 9]"));
  CHECK_THROWS_WITH(export_with(f.metadata, f.min, f.max.narrow(0, 0, 10)), Catch::Contains("normaliser"));
  torch::Tensor flat = f.max.clone();
  flat[3][2] = f.min[3][2];
  CHECK_THROWS_WITH(export_with(f.metadata, f.min, flat),
                    Catch::Contains("normaliser") && Catch::Contains("vertex 3, channel 2"));
  torch::Tensor nan = f.max.clone();
  nan[0][0] = std::nan("");
  CHECK_THROWS_WITH(export_with(f.metadata, f.min, nan), Catch::Contains("finite"));
  CHECK(fs::is_empty(dir));  // nothing written
}

TEST_CASE("export_vae: Python's torch.jit.load runs the exported files", "[vae_export][python]") {
  const std::string python = test::python_with_torch();
  torch::manual_seed(17);
  Fixture f = fixture(small_options());
  const fs::path dir = scratch_dir("vae_export_python");
  export_vae(*f.vae, f.min, f.max, f.metadata, (dir / "vae").string());
  const torch::Tensor x = raw_features(f, 3), z = torch::randn({2, 6});
  {
    torch::NoGradGuard no_grad;
    const VaeEncoding code = f.vae->encode(normalise(f, x));
    save_tensors((dir / "data.pt").string(), {{"x", x},
                                              {"mean", code.mean},
                                              {"logvar", code.logvar},
                                              {"z", z},
                                              {"decoded", denormalise(f, f.vae->decode(z))}});
  }
  write_text(dir / "check.py", R"(import json, sys, torch
folder, data = sys.argv[1], torch.load(sys.argv[2])
extra = {"metadata.json": ""}
encoder = torch.jit.load(folder + "/encoder.pt", _extra_files=extra)
decoder = torch.jit.load(folder + "/decoder.pt")
encoder.eval()
decoder.eval()
metadata = json.loads(extra["metadata.json"])
with torch.no_grad():
    mean, logvar = encoder.encode(data["x"])
    errors = {
        "forward": (encoder(data["x"]) - data["mean"]).abs().max().item(),
        "mean": (mean - data["mean"]).abs().max().item(),
        "logvar": (logvar - data["logvar"]).abs().max().item(),
        "decoded": (decoder(data["z"]) - data["decoded"]).abs().max().item(),
    }
attributes = (encoder.latent, encoder.vertices, encoder.kind, decoder.name, metadata["latent"])
print("errors", errors, "attributes", attributes)
ok = max(errors.values()) <= 1e-5 and attributes == (6, 180, "avatar", "rabbit", 6)
sys.exit(0 if ok else 1)
)");
  const fs::path log = dir / "check.log";
  const std::string command = python + " '" + (dir / "check.py").string() + "' '" + (dir / "vae").string() + "' '" +
                              (dir / "data.pt").string() + "' >'" + log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  INFO(read_text(log));
  CHECK(status == 0);
}

}  // namespace
}  // namespace retarget
