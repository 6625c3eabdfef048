#include "train/run_folder.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/timer.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

constexpr const char* kRunFile = "run.yaml";
constexpr const char* kConfigFile = "config.yaml";
constexpr const char* kJsonl = "metrics.jsonl";
constexpr const char* kCsv = "metrics.csv";
constexpr const char* kCheckpoints = "checkpoints";

std::string in(const std::string& folder, const char* name) { return (fs::path(folder) / name).string(); }

std::string number(double value) { return std::isfinite(value) ? fmt::format("{:.9g}", value) : "nan"; }

// The JSONL rows of a metrics log that parse (a line cut short by a kill does not).
std::vector<nlohmann::ordered_json> read_jsonl_rows(const std::string& path) {
  std::vector<nlohmann::ordered_json> rows;
  std::ifstream jsonl(path);
  std::string line;
  while (std::getline(jsonl, line)) {
    nlohmann::ordered_json row;
    try {
      row = nlohmann::ordered_json::parse(line);
    } catch (const nlohmann::json::exception&) {
      continue;
    }
    if (row.is_object()) rows.push_back(std::move(row));
  }
  return rows;
}

// Rewrites the CSV log from JSONL rows. The header is every key in order of first appearance,
// so a run resumed by a version that logs more columns keeps one header (older rows: nan).
void write_csv(const std::string& path, const std::vector<nlohmann::ordered_json>& rows) {
  std::vector<std::string> keys;
  for (const auto& row : rows)
    for (const auto& [key, value] : row.items())
      if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
  write_file_atomically(path, [&](std::ostream& out) {
    if (rows.empty()) return;
    std::string header;
    for (const std::string& key : keys) header += (header.empty() ? "" : ",") + key;
    out << header << "\n";
    for (const auto& row : rows) {
      std::string csv_row;
      for (size_t i = 0; i < keys.size(); ++i) {
        const auto it = row.find(keys[i]);
        csv_row += (i == 0 ? "" : ",") + number(it != row.end() && it->is_number() ? it->get<double>() : std::nan(""));
      }
      out << csv_row << "\n";
    }
  });
}

}  // namespace

RunStatus RunStatus::load(const std::string& folder) {
  const std::string path = in(folder, kRunFile);
  const ConfigNode root = ConfigNode::load_file(path);
  RunStatus s;
  root.get_required("status", s.status);
  if (s.status != "running" && s.status != "finished")
    root.child("status").fail("expected 'running' or 'finished', got '" + s.status + "'");
  root.get_required("task", s.task);
  root.get_required("epochs_done", s.epochs_done);
  root.get_required("epochs_planned", s.epochs_planned);
  root.get("best_epoch", s.best_epoch);
  root.get("best_validation", s.best_validation);
  if (root.has("fingerprints")) {
    const ConfigNode fingerprints = root.child("fingerprints");
    for (const auto& entry : fingerprints.yaml())
      s.fingerprints[entry.first.as<std::string>()] = entry.second.as<std::string>();
  }
  root.get("software_version", s.software_version);
  root.get("started", s.started);
  root.get("updated", s.updated);
  root.get("finished", s.finished);
  if (root.has("baselines")) {
    const ConfigNode baselines = root.child("baselines");
    if (!baselines.is_null() && !baselines.is_map()) baselines.fail("expected a map of name: loss");
    for (const auto& entry : baselines.yaml()) {
      const std::string name = entry.first.as<std::string>();
      s.baselines[name] = baselines.child(name).as<double>();
    }
  }
  root.get("warnings", s.warnings);
  return s;
}

void RunStatus::save(const std::string& folder) const {
  YAML::Emitter y;
  y.SetDoublePrecision(12);
  y << YAML::BeginMap;
  y << YAML::Key << "status" << YAML::Value << status;
  y << YAML::Key << "task" << YAML::Value << task;
  y << YAML::Key << "epochs_done" << YAML::Value << epochs_done;
  y << YAML::Key << "epochs_planned" << YAML::Value << epochs_planned;
  y << YAML::Key << "best_epoch" << YAML::Value << best_epoch;
  y << YAML::Key << "best_validation" << YAML::Value << best_validation;
  y << YAML::Key << "fingerprints" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, value] : fingerprints) y << YAML::Key << name << YAML::Value << value;
  y << YAML::EndMap;
  y << YAML::Key << "software_version" << YAML::Value << software_version;
  y << YAML::Key << "started" << YAML::Value << started;
  y << YAML::Key << "updated" << YAML::Value << updated;
  y << YAML::Key << "finished" << YAML::Value << finished;
  y << YAML::Key << "baselines" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, value] : baselines)
    if (std::isfinite(value)) y << YAML::Key << name << YAML::Value << value;
  y << YAML::EndMap;
  y << YAML::Key << "warnings" << YAML::Value << YAML::BeginSeq;
  for (const std::string& warning : warnings) y << warning;
  y << YAML::EndSeq;
  y << YAML::EndMap;
  const std::string text = std::string(y.c_str()) + "\n";
  write_file_atomically(in(folder, kRunFile), [&](std::ostream& out) { out << text; });
}

RunFolder::RunFolder(const std::string& folder, const std::string& task, const std::string& config_yaml, RunStart start)
    : folder_(folder) {
  // What a kill during a write left (a half-written checkpoint: checkpoints/last.pt.tmp.<pid>.<n>).
  for (const std::string& place : {folder, in(folder, kCheckpoints)}) {
    remove_stale_temporaries(place);
  }
  const bool has_run = fs::exists(in(folder, kRunFile));
  if (start == RunStart::resume) {
    if (!has_run) throw Error(folder, "no run to resume here (no run.yaml); start it without --resume");
    status_ = RunStatus::load(folder);
    if (status_.task != task)
      throw Error(in(folder, kRunFile), "the run here is a '" + status_.task + "' run, not '" + task + "'");
    if (status_.status == "finished")
      throw Error(folder, fmt::format("the run finished ({} epochs); nothing to resume (use --force to train again)",
                                      status_.epochs_done));
    if (!fs::exists(last_checkpoint())) {
      // Killed before the first checkpoint: nothing to lose, start from scratch.
      status_.epochs_done = 0;
    } else {
      resuming_ = true;
    }
    truncate_metrics(status_.epochs_done);
    return;
  }
  if (has_run && start == RunStart::fresh) {
    const RunStatus existing = RunStatus::load(folder);
    if (existing.status == "finished")
      throw Error(folder, fmt::format("holds a finished run ({} epochs, finished {}); use --force to train again "
                                      "or choose another output folder",
                                      existing.epochs_done, existing.finished));
    throw Error(folder, fmt::format("holds an unfinished run (epoch {} of {}); use --resume to continue it or "
                                    "--force to start again",
                                    existing.epochs_done, existing.epochs_planned));
  }
  for (const char* name : {kRunFile, kConfigFile, kJsonl, kCsv}) fs::remove(in(folder, name));
  fs::remove_all(in(folder, kCheckpoints));
  fs::create_directories(in(folder, kCheckpoints));
  write_file_atomically(config_path(), [&](std::ostream& out) { out << config_yaml; });
  status_.task = task;
  status_.software_version = RETARGET_VERSION;
  status_.started = utc_timestamp();
}

std::string RunFolder::config_path() const { return in(folder_, kConfigFile); }
std::string RunFolder::last_checkpoint() const { return (fs::path(folder_) / kCheckpoints / "last.pt").string(); }
std::string RunFolder::best_checkpoint() const { return checkpoint_path("best"); }
std::string RunFolder::checkpoint_path(const std::string& name) const {
  return (fs::path(folder_) / kCheckpoints / (name + ".pt")).string();
}

RunFolder RunFolder::follower(const std::string& folder, const std::string& task, RunStart start) {
  RunFolder run;
  run.folder_ = folder;
  run.follower_ = true;
  if (!fs::exists(in(folder, kConfigFile)))
    throw Error(folder, "rank 0 has not opened the run folder (no config.yaml); do the ranks share one folder?");
  if (fs::exists(in(folder, kRunFile))) run.status_ = RunStatus::load(folder);
  if (!run.status_.task.empty() && run.status_.task != task)
    throw Error(in(folder, kRunFile), "the run here is a '" + run.status_.task + "' run, not '" + task + "'");
  run.status_.task = task;
  run.resuming_ = start == RunStart::resume && fs::exists(run.last_checkpoint());
  return run;
}

void RunFolder::save_status() {
  if (follower_) return;
  status_.updated = utc_timestamp();
  status_.save(folder_);
}

void RunFolder::append_metrics(const std::vector<std::pair<std::string, double>>& row) {
  if (follower_) return;
  const std::string csv_path = in(folder_, kCsv);
  std::string json = "{", csv_header, csv_row;
  for (size_t i = 0; i < row.size(); ++i) {
    const char* sep = i == 0 ? "" : ",";
    json += fmt::format("{}\"{}\": {}", i == 0 ? "" : ", ", row[i].first,
                        std::isfinite(row[i].second) ? number(row[i].second) : "null");
    csv_header += sep + row[i].first;
    csv_row += sep + number(row[i].second);
  }
  json += "}\n";
  std::string existing_header;
  {
    std::ifstream csv(csv_path);
    std::getline(csv, existing_header);
  }
  std::ofstream jsonl(in(folder_, kJsonl), std::ios::app);
  jsonl << json;
  jsonl.close();
  if (!jsonl) throw Error(folder_, "cannot append to the metrics logs");
  if (!existing_header.empty() && existing_header != csv_header) {
    // Rows with other columns (a run started by another version): one header for all rows.
    write_csv(csv_path, read_jsonl_rows(in(folder_, kJsonl)));
    return;
  }
  std::ofstream csv(csv_path, std::ios::app);
  if (existing_header.empty()) csv << csv_header << "\n";
  csv << csv_row << "\n";
  if (!csv) throw Error(folder_, "cannot append to the metrics logs");
}

void RunFolder::truncate_metrics(int epochs) {
  if (follower_) return;
  // The JSONL log is the record; the CSV is rewritten from the rows kept, so the two agree
  // even if a kill fell between the two appends.
  std::vector<nlohmann::ordered_json> kept;
  for (auto& row : read_jsonl_rows(in(folder_, kJsonl)))
    if (row.contains("epoch") && row["epoch"].is_number() && row["epoch"].get<double>() <= epochs)
      kept.push_back(std::move(row));
  write_file_atomically(in(folder_, kJsonl), [&](std::ostream& out) {
    for (const auto& row : kept) out << row.dump() << "\n";
  });
  write_csv(in(folder_, kCsv), kept);
}

std::vector<std::map<std::string, double>> read_metrics(const std::string& folder) {
  std::vector<std::map<std::string, double>> rows;
  const std::string path = in(folder, kJsonl);
  std::ifstream jsonl(path);
  if (!jsonl) throw Error(path, "cannot read the metrics log");
  std::string line;
  int number_of_line = 0;
  while (std::getline(jsonl, line)) {
    ++number_of_line;
    if (line.empty()) continue;
    nlohmann::json row;
    try {
      row = nlohmann::json::parse(line);
    } catch (const nlohmann::json::exception& e) {
      throw Error(fmt::format("{}:{}", path, number_of_line), std::string("not JSON: ") + e.what());
    }
    std::map<std::string, double> values;
    for (const auto& [key, value] : row.items()) values[key] = value.is_number() ? value.get<double>() : std::nan("");
    rows.push_back(std::move(values));
  }
  return rows;
}

}  // namespace retarget
