// What the driver (engine/main.cpp) sees of the engine: the run options and summary, and the
// entry points of the engine built for D axes, Engine<D> (D = 2 or 3; engine/run.cpp defines them
// once per dimension, kernels/dimension.hpp). The case's [grid] dimension picks D.
#pragma once
#include <filesystem>
#include <memory>
#include <string>

#include <toml++/toml.h>

#include "engine/checkpoint.hpp"

namespace smpm {

struct RunOptions {
  std::filesystem::path out_dir;  // default out/<case stem>
  int threads = 0;                // 0: OpenMP default
  bool quiet = false;             // no progress lines
  bool overwrite = false;         // replace an earlier run's results in out_dir (check_output_dir)
  std::string command_line;       // for run.json's provenance
};

struct RunSummary {
  std::string status;  // "completed", "failed", "interrupted"
  std::string message;
  long steps = 0;
  double end_time = 0.0;
  double wall_seconds = 0.0;
  double particle_steps_per_s = 0.0;
  double diagnostics_seconds = 0.0;  // energy, front, wall and series rows
  double output_seconds = 0.0;       // snapshots and series.h5
  bool output_failed = false;        // an output could not be written (exit 1; message names it)
};

// The output directory a run writes (opt.out_dir, else out/<case stem>).
std::filesystem::path output_dir(const RunOptions& opt, const std::string& case_name);

// A directory holding run.json holds an earlier run: refused (CaseError, exit 2) unless
// overwrite. Nothing is deleted here; a run clears the earlier run's outputs (and any .tmp
// leftovers) only when it starts writing its own. Called before the scene is built.
void check_output_dir(const std::filesystem::path& out, bool overwrite);

// The number of axes a case asks for: [grid] dimension, 2 (the default) or 3; CaseError naming
// the key and the value otherwise.
int case_dimension(const toml::table& doc);

// The checkpoint a run in `dir` continues from: the newest whole one (a damaged one is named and
// the one before it tried), with the case it carries. CaseError (exit 2) when `dir` has none or
// its run completed.
struct ResumePoint {
  std::unique_ptr<CheckpointReader> reader;
  toml::table doc;   // the case, as the checkpoint holds it
  std::string name;  // the case's name
};
ResumePoint find_resume_point(const std::filesystem::path& dir);

// The signal that asked the run to stop (SIGINT or SIGTERM; 0: none): the run stops after the
// current step and writes its last state, as for a batch scheduler's SIGTERM.
// watch_stop_signals() clears it and installs the handler.
int stop_signal();
void watch_stop_signals();

// The engine for D axes.
template <int D>
struct Engine {
  // `shockmpm run`: builds the scene of the case `doc` (its name, the directory its relative
  // paths start from) and runs it.
  static RunSummary run(const toml::table& doc, const std::string& name, const std::filesystem::path& case_dir,
                        const RunOptions& opt);
  // `shockmpm check`: the text that describes what a run would do.
  static std::string check(const toml::table& doc, const std::string& name, const std::filesystem::path& case_dir);
  // `shockmpm resume DIR`: continues the run in DIR from `point`. The steps are bitwise those of
  // an uninterrupted run, at any thread count. opt.out_dir and opt.overwrite are ignored.
  static RunSummary resume(const std::filesystem::path& dir, const ResumePoint& point, const RunOptions& opt);
};
template <> RunSummary Engine<2>::run(const toml::table&, const std::string&, const std::filesystem::path&,
                                      const RunOptions&);
template <> std::string Engine<2>::check(const toml::table&, const std::string&, const std::filesystem::path&);
template <> RunSummary Engine<2>::resume(const std::filesystem::path&, const ResumePoint&, const RunOptions&);
template <> RunSummary Engine<3>::run(const toml::table&, const std::string&, const std::filesystem::path&,
                                      const RunOptions&);
template <> std::string Engine<3>::check(const toml::table&, const std::string&, const std::filesystem::path&);
template <> RunSummary Engine<3>::resume(const std::filesystem::path&, const ResumePoint&, const RunOptions&);

}  // namespace smpm
