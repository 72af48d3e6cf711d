// Running a scene: the step loop with progress lines, diagnostics files, snapshots and
// run.json. Nothing is lost on failure: a run that stops early (invalid state, interrupt)
// still writes its last snapshot and a run.json that says how and why it ended.
#pragma once
#include "kernels/dimension.hpp"
#include <filesystem>
#include <string>

#include "engine/driver.hpp"
#include "engine/scene.hpp"

namespace SMPM_NS {

RunSummary run_scene(Scene& scene, const RunOptions& opt);

// `shockmpm resume DIR`: continues the run in DIR from `point` (find_resume_point), with the
// case the checkpoint carries. The CSV files are cut back to their length at the checkpoint and
// continue, the snapshot index is that of the checkpoint (later snapshot files are removed),
// run.json's provenance gains an entry under "restarts". The steps are bitwise those of an
// uninterrupted run, at any thread count. opt.out_dir and opt.overwrite are ignored.
RunSummary resume_run(const std::filesystem::path& dir, const ResumePoint& point, const RunOptions& opt);

// OUT/case_resolved.toml: the resolved case (every default filled in), which runs again as it
// is: the materials are written whole, their library entry and file as comments.
std::string resolved_case_text(const Scene& scene);

// The text `shockmpm check` prints: particles, porosity, grid, time step, steps, memory.
std::string describe_scene(const Scene& scene);

}  // namespace SMPM_NS
