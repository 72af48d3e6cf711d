// The shockmpm driver: parse the case file, build the scene, run, write output.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>

#include "engine/case_reader.hpp"
#include "engine/run.hpp"
#include "engine/scene.hpp"

int main(int argc, char** argv) {
  CLI::App app{"shockmpm: Material Point Method for shock waves in porous metals"};
  app.require_subcommand(1);
  std::string case_file, out_dir;
  int threads = 0;
  bool quiet = false;
  std::vector<std::string> sets;
  auto* run = app.add_subcommand("run", "run a case");
  run->add_option("case", case_file, "case file (TOML)")->required();
  run->add_option("--out", out_dir, "output directory (default out/<case stem>)");
  run->add_option("--threads", threads, "OpenMP threads (default: OMP_NUM_THREADS or all cores)")->check(CLI::Range(1, 1024));
  run->add_option("--set", sets, "override a case value: section.key=value (TOML syntax)");
  run->add_flag("--quiet", quiet, "no progress lines");
  auto* check = app.add_subcommand("check", "validate a case and print what a run would do");
  check->add_option("case", case_file, "case file (TOML)")->required();
  check->add_option("--set", sets, "override a case value: section.key=value (TOML syntax)");
  CLI11_PARSE(app, argc, argv);

  try {
    auto doc = smpm::parse_case_file(case_file);
    smpm::apply_overrides(doc, sets);
    const std::filesystem::path path(case_file);
    smpm::Scene scene = smpm::build_scene(doc, path.stem().string(), path.parent_path());
    if (check->parsed()) {
      std::cout << smpm::describe_scene(scene);
      return 0;
    }
    const auto s = smpm::run_scene(scene, {out_dir, threads, quiet});
    return s.status == "completed" ? 0 : 3;
  } catch (const smpm::CaseError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
