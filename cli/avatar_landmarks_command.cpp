// retarget avatar landmarks: the page to check and correct an avatar's landmarks beside the human
// face's (avatar/landmark_editor.h).
//   retarget avatar landmarks RIG_FOLDER --face-model FACE_MODEL_YAML [--host 127.0.0.1] [--port 0]
//                             [--open-browser no]
#include <fmt/format.h>

#include <cstdlib>
#include <cxxopts.hpp>
#include <iostream>

#include "avatar/landmark_editor.h"
#include "cli/command_options.h"
#include "cli/commands.h"
#include "cli/option_names.h"
#include "core/error.h"
#include "web/stop_signals.h"

namespace retarget::cli {

int avatar_landmarks(int argc, char** argv) {
  cxxopts::Options options(
      "retarget avatar landmarks",
      "Serve a page to check and correct an avatar's landmarks: the avatar and the human face side by side,\n"
      "every landmark a dot on both. Select one, click on the avatar where it belongs (or drag its dot);\n"
      "Save writes rig.yaml's landmarks: section (nothing else). RIG_FOLDER: a rig folder, e.g. the one\n"
      "`retarget avatar init` wrote. Stop with Ctrl-C.");
  options.add_options()("rig", "the avatar's rig folder (or its rig.yaml)", cxxopts::value<std::string>())(
      "face-model", "the human face model whose landmarks name the points (face_model.yaml)",
      cxxopts::value<std::string>())("host", "address to listen on (127.0.0.1: this machine only)",
                                     cxxopts::value<std::string>()->default_value("127.0.0.1"))(
      "port", "port (0: any free one)", cxxopts::value<int>()->default_value("0"))(
      "open-browser", "yes: open the page with xdg-open", cxxopts::value<std::string>()->default_value("no"))(
      "size", "picture size in pixels", cxxopts::value<int>()->default_value("560"));
  options.parse_positional({"rig"});
  options.positional_help("RIG_FOLDER --face-model FACE_MODEL_YAML");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("rig")) throw Error("retarget avatar landmarks", "missing the RIG_FOLDER (see --help)");
  if (!args.count("face-model"))
    throw Error("retarget avatar landmarks",
                "missing --face-model FACE_MODEL_YAML (the human face, e.g. the synthetic default's "
                "human/face_model.yaml)");
  const std::string open_browser = args["open-browser"].as<std::string>();
  if (open_browser != "yes" && open_browser != "no")
    throw Error("--open-browser", fmt::format("must be yes or no, got \"{}\"", open_browser));

  LandmarkEditorOptions so;
  so.host = args["host"].as<std::string>();
  so.port = args["port"].as<int>();
  so.view_size = args["size"].as<int>();

  const StopSignals stop_signals;  // before the server starts its threads

  LandmarkEditorServer server = with_option_names(
      "landmarks",
      [&] { return LandmarkEditorServer(args["rig"].as<std::string>(), args["face-model"].as<std::string>(), so); },
      {{"view_size", "--size"}});
  server.bind();
  std::cout << fmt::format("retarget avatar landmarks: {}\n", args["rig"].as<std::string>())
            << fmt::format("  open: {}\n", server.page_url())
            << "Select a landmark, click on the avatar where it belongs, then Save. Stop with Ctrl-C "
               "(unsaved changes are lost)."
            << std::endl;
  if (so.host != "127.0.0.1" && so.host != "localhost" && so.host != "::1")
    std::cerr << "[warn] listening beyond this machine: the address's token crosses the network in the clear\n";
  if (open_browser == "yes") {
    const std::string command = fmt::format("xdg-open '{}' >/dev/null 2>&1 &", server.page_url());
    if (std::system(command.c_str()) != 0) std::cerr << "[warn] could not start xdg-open; open the address above\n";
  }
  stop_signals.serve([&server] { server.run(); }, [&server] { server.stop(); });
  std::cout << "retarget avatar landmarks: stopped" << std::endl;
  return 0;
}

}  // namespace retarget::cli
