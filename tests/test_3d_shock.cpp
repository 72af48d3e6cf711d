// The 3D engine's shock checks (SMPM_DIM = 3): the dense aluminium Hugoniot in a column periodic
// across, against the exact Rankine-Hugoniot state and against the same column in 2D, energy
// closed to round-off; a spherical void that collapses and closes. Numbers, not memory: CI runs
// them in the Release build only (label accuracy; tests/CMakeLists.txt).
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "engine/diagnostics.hpp"
#include "engine/simulation.hpp"
#include "tests/column_impact.hpp"
#include "tests/verify_cases.hpp"

using namespace smpm;
static_assert(kern::kDim == 3, "tests/test_3d_shock.cpp is compiled for the 3D engine (SMPM_DIM=3)");

using test::verify_scene;

TEST_CASE("3D: dense column at 1000 m/s against the exact Hugoniot and the 2D strip", "[verification][shock][3d]") {
  const auto r3 = verify::column_impact<3>("dense_impact_1000_3d.toml");
  const auto r2 = verify::column_impact<2>("dense_impact_1000.toml");
  WARN("3D: Us " << r3.Us << " (exact " << r3.exact_Us << ", 2D " << r2.Us << "), wall " << r3.wall * 1e-9
                 << " GPa (exact " << r3.exact_P * 1e-9 << ", 2D " << r2.wall * 1e-9 << "), P " << r3.P * 1e-9
                 << " rho " << r3.rho << " T " << r3.T << ", energy residual " << r3.energy_residual << ", "
                 << r3.particles << " points, " << r3.steps << " steps");
  // shock speed and wall stress within 0.3 % (P, rho, T as test_shock bounds them in 2D)
  test::check_plateau(r3, 0.003);
  CHECK(r3.Us == Approx(r2.Us).epsilon(0.001));
  CHECK(r3.wall == Approx(r2.wall).epsilon(0.001));
  // energy: kinetic + internal + what the slip wall took, constant to round-off
  CHECK(std::fabs(r3.energy_residual) < 1e-10);
}

// The void's open volume (open_area on voxels, as voids.csv) before and after the shock.
TEST_CASE("3D: a spherical void collapses and closes, energy conserved", "[verification][porous][3d]") {
  Scene sc = verify_scene("void_collapse_3d.toml");
  const auto& g = sc.geom;
  const double pixel = 0.5 * g.h / 3;
  Window all;
  for (int d = 0; d < 3; ++d) {
    all.lo[d] = d == kImpactAxis ? -1e300 : g.lo[d];
    all.hi[d] = d == kImpactAxis ? 1e300 : g.lo[d] + g.length(d);
  }
  const double V0 = open_area(sc.particles, 0, {all}, pixel, kCoverRadius, periods(g), grid_origin(g))[0];
  Simulation sim(g, sc.solver, sc.materials, sc.body_material, sc.particles);
  const double E0 = sim.energy().total();
  while (sim.time() < sc.run.end_time) sim.step(sc.run.end_time - sim.time());
  const double V1 = open_area(sim.particles(), 0, {all}, pixel, kCoverRadius, periods(g), grid_origin(g))[0];
  const double lost = sim.removed_is_heat() ? 0.0 : sim.removed().wall + sim.removed().contact;
  const double residual = (sim.energy().total() + lost - E0) / E0;
  const double sphere = 4.0 / 3.0 * M_PI * std::pow(10e-6, 3);
  WARN("3D void: open volume " << V0 * 1e18 << " um^3 at t = 0 (sphere " << sphere * 1e18 << "), " << V1 * 1e18
                               << " um^3 at " << sim.time() * 1e9 << " ns; energy residual " << residual);
  // at t = 0 the points' balls reach into the void by about a point spacing: most of it is open
  CHECK(V0 > 0.5 * sphere);
  CHECK(V0 < sphere);
  CHECK(V1 < 0.01 * V0);
  CHECK(std::fabs(residual) < 1e-10);
}

