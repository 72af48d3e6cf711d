#include "engine/provenance.hpp"

#include <unistd.h>

#include <ctime>

#include "git_info.hpp"  // generated at build time (cmake/git_info.cmake)

namespace smpm {

toml::table provenance(const std::string& command_line, int threads) {
  char host[256] = "unknown";
  if (gethostname(host, sizeof host) != 0) host[0] = '\0';
  host[sizeof host - 1] = '\0';
  char date[32] = "";
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  if (gmtime_r(&now, &utc)) std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return toml::table{{"git_commit", SHOCKMPM_GIT_COMMIT},
                     {"git_dirty", SHOCKMPM_GIT_DIRTY},
                     {"compiler", std::string("g++ ") + __VERSION__},
                     {"build_type", SHOCKMPM_BUILD_TYPE},
                     {"cxx_flags", SHOCKMPM_CXX_FLAGS},
                     {"date_utc", date},
                     {"host", host},
                     {"threads", threads},
                     {"command_line", command_line}};
}

}  // namespace smpm
