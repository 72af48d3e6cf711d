// The shockmpm driver: parse the case file, build the scene, run, write output.
#include <CLI/CLI.hpp>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "engine/case_reader.hpp"
#include "engine/driver.hpp"

namespace {

// OpenMP threads that wait at a barrier spin before they sleep (libgomp: 300 000 spins by
// default). On a machine whose cores another process also uses, a spinning thread burns the
// time slice that the thread it waits for needs: with one `yes > /dev/null` beside it, a 2-thread
// quick start ran at a third of its 1-thread speed. libgomp reads its settings when it is loaded,
// before main, so when the user has set neither OMP_WAIT_POLICY nor GOMP_SPINCOUNT the driver sets
// GOMP_SPINCOUNT=1000 and starts itself again, once (the variable is then set). Measured on the
// 2-vCPU machine (docs/performance.md; bench/shared_machine.sh and
// bench/wait_policy_ab.sh): under that load 1000 spins ran 1.8-2.25x libgomp's default (passive
// 2.2x, 10 000 spins 1.2x); idle, 1000 spins kept 96-99 % of its speed, passive 85-92 %.
constexpr const char* kSpinCount = "1000";

void default_wait_policy(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT")) return;
  if (setenv("GOMP_SPINCOUNT", kSpinCount, 1) != 0) return;
  execv("/proc/self/exe", argv);  // returns only on failure: then run with libgomp's default
  unsetenv("GOMP_SPINCOUNT");
}

// The command line as typed, each argument shell-quoted where it needs it (run.json).
std::string command_line(int argc, char** argv) {
  std::string s;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    const bool plain = !a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                         "0123456789-_./=:,+@%") == std::string::npos;
    if (i) s += ' ';
    if (plain) {
      s += a;
    } else {
      s += '\'';
      for (char c : a) s += c == '\'' ? std::string("'\\''") : std::string(1, c);
      s += '\'';
    }
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  default_wait_policy(argv);
  CLI::App app{"shockmpm: Material Point Method for shock waves in porous metals"};
  app.set_version_flag("--version", std::string("shockmpm ") + SHOCKMPM_VERSION);
  app.require_subcommand(1);
  std::string case_file, out_dir;
  int threads = 0;
  bool quiet = false, overwrite = false;
  std::vector<std::string> sets;
  auto* run = app.add_subcommand("run", "run a case");
  run->add_option("case", case_file, "case file (TOML)")->required();
  run->add_option("--out", out_dir, "output directory (default out/<case stem>)");
  run->add_option("--threads", threads, "OpenMP threads (default: OMP_NUM_THREADS or all cores)")->check(CLI::Range(1, 1024));
  run->add_option("--set", sets, "override a case value: section.key=value (TOML syntax)");
  run->add_flag("--quiet", quiet, "no progress lines");
  run->add_flag("--overwrite", overwrite,
                "replace the results of an earlier run in the output directory (refused without it)");
  std::string resume_dir;
  auto* resume = app.add_subcommand("resume", "continue an interrupted run from its last checkpoint");
  resume->add_option("dir", resume_dir, "the run's output directory")->required();
  resume->add_option("--threads", threads, "OpenMP threads (default: OMP_NUM_THREADS or all cores)")->check(CLI::Range(1, 1024));
  resume->add_flag("--quiet", quiet, "no progress lines");
  auto* check = app.add_subcommand("check", "validate a case and print what a run would do");
  check->add_option("case", case_file, "case file (TOML)")->required();
  check->add_option("--set", sets, "override a case value: section.key=value (TOML syntax)");
  CLI11_PARSE(app, argc, argv);

  try {
    smpm::RunSummary s;
    if (resume->parsed()) {
      const smpm::RunOptions opt{resume_dir, threads, quiet, false, command_line(argc, argv)};
      const smpm::ResumePoint point = smpm::find_resume_point(resume_dir);
      s = smpm::case_dimension(point.doc) == 3 ? smpm::Engine<3>::resume(resume_dir, point, opt)
                                                : smpm::Engine<2>::resume(resume_dir, point, opt);
    } else {
      auto doc = smpm::parse_case_file(case_file);
      smpm::apply_overrides(doc, sets);
      const std::filesystem::path path(case_file);
      const std::string name = path.stem().string();
      const int dim = smpm::case_dimension(doc);
      if (check->parsed()) {
        std::cout << (dim == 3 ? smpm::Engine<3>::check(doc, name, path.parent_path())
                               : smpm::Engine<2>::check(doc, name, path.parent_path()));
        return 0;
      }
      const smpm::RunOptions opt{out_dir, threads, quiet, overwrite, command_line(argc, argv)};
      smpm::check_output_dir(smpm::output_dir(opt, name), overwrite);
      s = dim == 3 ? smpm::Engine<3>::run(doc, name, path.parent_path(), opt)
                   : smpm::Engine<2>::run(doc, name, path.parent_path(), opt);
    }
    if (s.output_failed) return 1;
    return s.status == "completed" ? 0 : 3;
  } catch (const smpm::CaseError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
