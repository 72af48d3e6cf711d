// Test helpers on the case files of cases/verify/: the scene of one (with "section.key=value"
// overrides), and a dense column's plateau against its exact Rankine-Hugoniot state
// (tests/column_impact.hpp).
#pragma once
#include "kernels/dimension.hpp"
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "engine/case_reader.hpp"
#include "engine/scene.hpp"
#include "tests/column_impact.hpp"

namespace SMPM_NS::test {

inline Scene verify_scene(const std::string& file, const std::vector<std::string>& overrides = {}) {
  auto doc = parse_case_file(std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/" + file);
  apply_overrides(doc, overrides);
  return build_scene(doc, file, std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify");
}

// Shock speed and wall stress within front_tol of the exact state; P within 2 %, rho 1 %, T 5 %.
inline void check_plateau(const verify::ColumnImpact& r, double front_tol) {
  CHECK(r.finite);
  CHECK(r.Us == Approx(r.exact_Us).epsilon(front_tol));
  CHECK(r.wall == Approx(r.exact_P).epsilon(front_tol));
  CHECK(r.P == Approx(r.exact_P).epsilon(0.02));
  CHECK(r.rho == Approx(r.exact_rho).epsilon(0.01));
  CHECK(r.T == Approx(r.exact_T).epsilon(0.05));
}

}  // namespace SMPM_NS::test
