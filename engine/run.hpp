// Running a scene: the step loop with progress lines, diagnostics files, snapshots and
// run.json. Nothing is lost on failure: a run that stops early (invalid state, interrupt)
// still writes its last snapshot and a run.json that says how and why it ended.
#pragma once
#include <filesystem>
#include <string>

#include "engine/scene.hpp"

namespace smpm {

struct RunOptions {
  std::filesystem::path out_dir;  // default out/<case stem>
  int threads = 0;                // 0: OpenMP default
  bool quiet = false;             // no progress lines
  bool overwrite = false;         // replace an earlier run's results in out_dir (check_output_dir)
  std::string command_line;       // for run.json's provenance
};

// The output directory a run writes (opt.out_dir, else out/<case stem>).
std::filesystem::path output_dir(const RunOptions& opt, const std::string& case_name);

// A directory holding run.json holds an earlier run: refused (CaseError, exit 2) unless
// overwrite. Nothing is deleted here; run_scene clears the earlier run's outputs (and any
// .tmp leftovers) only when it starts writing its own. Called before the scene is built.
void check_output_dir(const std::filesystem::path& out, bool overwrite);

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

RunSummary run_scene(Scene& scene, const RunOptions& opt);

// `shockmpm resume DIR`: continues the run in DIR from its newest whole checkpoint
// (DIR/checkpoint/ckpt_<step>.bin; the one before if the newest is damaged), with the case the
// checkpoint carries. The CSV files are cut back to their length at the checkpoint and continue,
// the snapshot index is that of the checkpoint (later snapshot files are removed), run.json's
// provenance gains an entry under "restarts". The steps are bitwise those of an uninterrupted
// run, at any thread count. opt.out_dir and opt.overwrite are ignored. Throws CaseError (exit 2)
// when DIR has no checkpoint or its run completed.
RunSummary resume_run(const std::filesystem::path& dir, const RunOptions& opt);

// OUT/case_resolved.toml: the resolved case (every default filled in), which runs again as it
// is: the materials are written whole, their library entry and file as comments.
std::string resolved_case_text(const Scene& scene);

// The text `shockmpm check` prints: particles, porosity, grid, time step, steps, memory.
std::string describe_scene(const Scene& scene);

}  // namespace smpm
