// Dense symmetric impact (rigid-wall half model) against the exact jump conditions of the
// code's own Hugoniot (docs/model.md, "Exact checks"), run from the case files in cases/verify/
// (tests/column_impact.hpp).
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "tests/column_impact.hpp"
#include "tests/verify_cases.hpp"

using namespace smpm;

namespace {

using ImpactResult = verify::ColumnImpact;
ImpactResult run_impact(const std::string& file, const std::vector<std::string>& overrides = {}) {
  return verify::column_impact<2>(file, overrides);
}

void check_plateau(const ImpactResult& r) {
  WARN("Us " << r.Us << " (exact " << r.exact_Us << "), wall " << r.wall << " P " << r.P << " (exact " << r.exact_P
             << "), rho " << r.rho << " (exact " << r.exact_rho << "), T " << r.T << " (exact " << r.exact_T
             << "), energy error " << r.energy_error);
  test::check_plateau(r, 0.02);
}

}  // namespace

TEST_CASE("dense impact at 500 m/s: Hugoniot state and elastic precursor", "[verification][shock]") {
  const auto r = run_impact("dense_impact_500.toml");
  check_plateau(r);
  // precursor: HEL from the model's own moduli, Y0 (K/2G + 2/3) with K = rho0 c0^2 = 259 MPa,
  // at sqrt((rho0 c0^2 + 4G/3) / rho0) = 6437 m/s
  WARN("precursor speed " << r.precursor_speed << " amplitude " << r.precursor_amplitude);
  CHECK(r.precursor_speed == Approx(6437.0).epsilon(0.03));
  CHECK(r.precursor_amplitude == Approx(259e6).epsilon(0.10));
}

TEST_CASE("dense impact at 1000 m/s: Hugoniot state and energy conservation", "[verification][shock]") {
  const auto r = run_impact("dense_impact_1000.toml");
  check_plateau(r);
  CHECK(std::fabs(r.energy_error) < 0.01);
}

TEST_CASE("dense impact at 2000 m/s: stable, Hugoniot state", "[verification][shock][stability]") {
  const auto r = run_impact("dense_impact_2000.toml");
  check_plateau(r);
  CHECK(std::fabs(r.energy_error) < 0.02);
}

// The finer long check (h = 1 um, 160 000 points, about a minute each on 2 cores): hidden from
// the default run; `build/tests/test_shock "[long]" -s` (docs/verification.md).
TEST_CASE("long check: dense impacts at h = 1 um", "[.][long]") {
  const std::vector<std::string> fine{"grid.cell_size_um=1.0"};
  for (const char* f : {"dense_impact_500.toml", "dense_impact_1000.toml", "dense_impact_2000.toml"}) {
    INFO(f);
    const auto r = run_impact(f, fine);
    check_plateau(r);
    WARN("energy error " << r.energy_error << ", precursor speed " << r.precursor_speed << " amplitude "
                         << r.precursor_amplitude);
    CHECK(std::fabs(r.energy_error) < 0.01);
  }
}
