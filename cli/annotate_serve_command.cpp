// retarget annotate serve: the web annotation tool (annotate/annotation_server.h) over a project,
// with turntable pictures rendered from the project's correspondences (AnnotationRenders).
//   retarget annotate serve PROJECT [--port 8080] [--host 127.0.0.1] [--lease 120] [--password P]
//   retarget annotate serve --demo [--folder out/annotate-demo]   (builds a synthetic project once)
#include <fmt/format.h>

#include <cstdlib>
#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>

#include "annotate/annotation_server.h"
#include "cli/command_options.h"
#include "cli/commands.h"
#include "cli/option_names.h"
#include "core/error.h"
#include "core/log.h"
#include "correspond/annotation_project.h"
#include "web/stop_signals.h"

namespace retarget::cli {

namespace fs = std::filesystem;

namespace {

// Runs `retarget <args...>` in this process (one of the subcommands of cli/commands.h).
void run_step(int (*command)(int, char**), std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const int code = command(static_cast<int>(args.size()), argv.data());
  if (code != 0) throw Error("retarget " + args.front(), fmt::format("failed with exit code {}", code));
}

// The synthetic default as an annotation project, built into `folder` on first use: the synthetic
// human and avatars, a small human dataset (8 people x 47 expressions), the first avatar's
// dataset, a briefly trained avatar VAE (3 epochs of configs/train/quick/avatar_vae.yaml; its
// codes only order the candidates), the correspondences and the project. About two minutes on
// two cores; later runs reuse it.
std::string demo_project(const fs::path& folder, const fs::path& configs) {
  const fs::path project = folder / "annotation";
  if (fs::exists(project / "project.yaml")) return project.string();
  for (const char* file : {"expressions/facewarehouse47.yaml", "train/quick/avatar_vae.yaml"})
    if (!fs::exists(configs / file))
      throw Error((configs / file).string(), "is missing: pass --configs with the repository's configs/ folder");
  log::info("building the demo project in {} (once; about two minutes)", folder.string());
  const std::string out = folder.string();
  run_step(synth_command, {"synth", "--out", out + "/synth", "--force"});
  std::string avatar;
  for (const auto& entry : fs::directory_iterator(folder / "synth" / "avatars"))
    if (avatar.empty() || entry.path().filename().string() < avatar) avatar = entry.path().filename().string();
  if (avatar.empty()) throw Error((folder / "synth" / "avatars").string(), "holds no avatar");
  run_step(dataset_command,
           {"dataset", "--rig", out + "/synth/avatars/" + avatar, "--out", out + "/datasets/avatar", "--force"});
  run_step(dataset_command, {"dataset", "--face-model", out + "/synth/human/face_model.yaml", "--recipes",
                             (configs / "expressions/facewarehouse47.yaml").string(), "--people", "8", "--out",
                             out + "/datasets/human", "--force"});
  run_step(train_command, {"train", (configs / "train/quick/avatar_vae.yaml").string(), "--set",
                           "data.dataset=" + out + "/datasets/avatar", "--out", out + "/runs/avatar_vae", "--set",
                           "training.epochs=3", "--force"});
  run_step(correspond_command,
           {"correspond", "--human", out + "/datasets/human", "--avatar", out + "/datasets/avatar", "--avatar-vae",
            out + "/runs/avatar_vae", "--out", out + "/correspondences", "--force"});
  run_step(annotate_command,
           {"annotate", "init", "--correspondences", out + "/correspondences", "--out", project.string(), "--force"});
  return project.string();
}

}  // namespace

int annotate_serve(int argc, char** argv) {
  cxxopts::Options options("retarget annotate serve",
                           "Serve a project's comparisons to people in their browsers: sign in with a name, then for\n"
                           "each human expression pick the avatar expression that looks more alike (keys: left,\n"
                           "right, down = draw, u = undo). Prints the annotators' address and the owner's address\n"
                           "(with the owner token: progress, triplet export, resets). Stop with Ctrl-C; every\n"
                           "answer is already stored.");
  options.add_options()("project", "the project folder (retarget annotate init)", cxxopts::value<std::string>())(
      "demo", "serve the synthetic default, building it into --folder on first use")(
      "folder", "where --demo builds its project", cxxopts::value<std::string>()->default_value("out/annotate-demo"))(
      "configs", "the repository's configs/ folder (for --demo)",
      cxxopts::value<std::string>()->default_value(RETARGET_CONFIGS_DIR))(
      "host", "address to listen on (127.0.0.1: this machine only)",
      cxxopts::value<std::string>()->default_value("127.0.0.1"))("port", "port (0: any free one)",
                                                                 cxxopts::value<int>()->default_value("8080"))(
      "lease", "seconds a shown comparison stays reserved for its annotator before it goes to someone else",
      cxxopts::value<double>()->default_value("120"))(
      "password",
      "the owner's password (>= 8 characters) instead of a random token; also read from "
      "RETARGET_OWNER_PASSWORD",
      cxxopts::value<std::string>())("size", "picture size in pixels (each turntable frame)",
                                     cxxopts::value<int>()->default_value("320"))(
      "frames", "turntable frames per picture", cxxopts::value<int>()->default_value("9"))(
      "yaw", "turntable swing, degrees either side of the front view", cxxopts::value<double>()->default_value("35"))(
      "threads", "request threads (each serves one connection at a time)", cxxopts::value<int>()->default_value("32"))(
      "per-client",
      "connections served at once per client address; more get 429 (0: half the threads; raise it when people "
      "share an address: a NAT, a reverse proxy, an SSH tunnel)",
      cxxopts::value<int>()->default_value("0"))("no-prerender", "render pictures only when first asked for");
  options.parse_positional({"project"});
  options.positional_help("PROJECT | --demo");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  std::string folder;
  if (args.count("demo")) {
    if (args.count("project")) throw Error("retarget annotate serve", "give either PROJECT or --demo, not both");
    folder = demo_project(args["folder"].as<std::string>(), args["configs"].as<std::string>());
  } else {
    if (!args.count("project")) throw Error("retarget annotate serve", "give the PROJECT folder, or --demo");
    folder = args["project"].as<std::string>();
  }
  const AnnotationProject project = load_annotation_project(folder);

  ServerOptions so;
  so.host = args["host"].as<std::string>();
  so.port = args["port"].as<int>();
  so.lease_seconds = args["lease"].as<double>();
  so.threads = args["threads"].as<int>();
  so.connections.per_client = args["per-client"].as<int>();
  so.prerender = args.count("no-prerender") == 0;
  if (args.count("password")) {
    so.owner_token = args["password"].as<std::string>();
  } else if (const char* env = std::getenv("RETARGET_OWNER_PASSWORD"); env && *env) {
    so.owner_token = env;
  }
  const int frames = args["frames"].as<int>();
  const double yaw = args["yaw"].as<double>();
  if (frames < 1 || frames > 64) throw Error("--frames", fmt::format("must be in 1..64, got {}", frames));
  if (!(yaw >= 0 && yaw <= 90)) throw Error("--yaw", fmt::format("must be in 0..90 degrees, got {}", yaw));

  auto renders = std::make_shared<AnnotationRenders>(project, args["size"].as<int>());
  TurntablePictures pictures;
  pictures.frames = frames;
  pictures.anchor = [renders, frames, yaw](const std::string& label) {
    return renders->anchor_turntable(label, frames, yaw);
  };
  pictures.candidate = [renders, frames, yaw](int64_t sample) {
    return renders->candidate_turntable(sample, frames, yaw);
  };

  const StopSignals stop_signals;  // before the server starts its threads

  AnnotationServer server =
      with_option_names("serve", [&] { return AnnotationServer(project.database(), std::move(pictures), so); },
                        {{"lease_seconds", "--lease"}, {"owner_token", "--password"}});
  server.bind();
  {
    AnnotationStore store = AnnotationStore::open(project.database());
    const StoreProgress p = store.progress();
    std::cout << fmt::format("retarget annotate serve: {} ({} groups, {} of {} comparisons decided)\n", project.folder,
                             p.groups.size(), p.done(), p.total())
              << fmt::format("  annotators: {}/\n", server.base_url())
              << fmt::format("  owner:      {}/overview#token={}\n", server.base_url(), server.owner_token())
              << "Stop with Ctrl-C; every answer is stored as it is given." << std::endl;
  }
  stop_signals.serve([&server] { server.run(); }, [&server] { server.stop(); });
  std::cout << "retarget annotate serve: stopped" << std::endl;
  return 0;
}

}  // namespace retarget::cli
