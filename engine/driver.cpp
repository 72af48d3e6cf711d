// The driver's dimension-independent part (engine/driver.hpp).
#include "engine/driver.hpp"

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "engine/case_reader.hpp"

namespace {
std::atomic<int> g_stop_signal{0};
extern "C" void on_stop_signal(int sig) { g_stop_signal = sig; }
}  // namespace

namespace smpm {

int stop_signal() { return g_stop_signal; }

void watch_stop_signals() {
  g_stop_signal = 0;
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
}

std::filesystem::path output_dir(const RunOptions& opt, const std::string& case_name) {
  return opt.out_dir.empty() ? std::filesystem::path("out") / case_name : opt.out_dir;
}

void check_output_dir(const std::filesystem::path& out, bool overwrite) {
  std::error_code ec;
  if (std::filesystem::exists(out, ec) && !std::filesystem::is_directory(out, ec))
    throw CaseError("output directory '" + out.string() + "' is a file; choose another --out");
  if (!overwrite && std::filesystem::exists(out / "run.json", ec))
    throw CaseError("output directory '" + out.string() + "' holds an earlier run (run.json); pass --overwrite to "
                    "replace its results, or choose another --out");
}

int case_dimension(const toml::table& doc) {
  // read as the scene reads it (the same message for a bad value); the scene records it
  toml::table scratch, grid_scratch;
  CaseReader top(doc, "", scratch);
  const auto* grid = doc.get_as<toml::table>("grid");
  if (!grid) return 2;
  CaseReader g(*grid, "grid", grid_scratch);
  return static_cast<int>(g.integer("dimension", 2, 3, 2));
}

ResumePoint find_resume_point(const std::filesystem::path& out) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(out, ec)) throw CaseError("cannot resume: '" + out.string() + "' is not a directory");
  if (fs::exists(out / "run.json", ec)) {
    std::ifstream j(out / "run.json");
    std::stringstream text;
    text << j.rdbuf();
    std::string t = text.str();
    t.erase(std::remove_if(t.begin(), t.end(), [](unsigned char c) { return std::isspace(c); }), t.end());
    if (t.find("\"status\":\"completed\"") != std::string::npos)
      throw CaseError("cannot resume: the run in '" + out.string() + "' completed (run.json); nothing to continue");
  }
  const auto all = list_checkpoints(out);
  if (all.empty())
    throw CaseError("cannot resume: '" + out.string() + "' holds no checkpoint (checkpoint/ckpt_*.bin); a run writes "
                    "one every run.checkpoint_interval_s of wall time and when SIGINT or SIGTERM stops it");
  ResumePoint p;
  for (auto it = all.rbegin(); it != all.rend() && !p.reader; ++it) {
    try {
      p.reader = std::make_unique<CheckpointReader>(*it);
    } catch (const CheckpointError& e) {
      std::fprintf(stderr, "warning: %s; trying the one before\n", e.what());
    }
  }
  if (!p.reader) throw CaseError("cannot resume: no checkpoint in '" + (out / "checkpoint").string() + "' is whole");
  try {
    p.doc = toml::parse(p.reader->text("run/case_text"));
  } catch (const toml::parse_error& e) {
    throw CheckpointError("checkpoint " + p.reader->file().string() + ": its case does not parse: " +
                          std::string(e.description()));
  }
  p.name = p.reader->text("run/case_name");
  return p;
}

}  // namespace smpm
