// Where a run's numbers come from: the build (git commit, compiler, flags) and the run (date,
// host, threads, command line), for run.json.
#pragma once
#include <string>

#include <toml++/toml.h>

namespace smpm {

toml::table provenance(const std::string& command_line, int threads);

}  // namespace smpm
