// Porous samples: porosity against the target, reproducibility; a 50 % porous block on the
// rigid wall at 1000 m/s runs stably.
#include <catch2/catch.hpp>
#include <omp.h>

#include <cmath>

#include "engine/case_reader.hpp"
#include "engine/porous.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"

using namespace smpm;

namespace {

// A study-sized sample: 1000 x 1000 um on a 1 um point lattice (10^6 points), voids of 10 um.
Scene sample(double porosity, std::uint64_t seed) {
  auto doc = toml::parse(R"(
[run]
end_time_ns = 1.0
[grid]
cell_size_um = 2.0
x_range_um = [0.0, 1000.0]
y_range_um = [0.0, 1000.0]
periodic_x = true
[materials.al]
density_kg_m3 = 2700.0
youngs_modulus_GPa = 69.0
poisson_ratio = 0.33
[[bodies]]
name = "target"
material = "al"
x_range_um = [0.0, 1000.0]
y_range_um = [0.0, 1000.0]
[bodies.voids]
radius_um = 10.0
)");
  doc["bodies"][0]["voids"].as_table()->insert("porosity", porosity);
  doc["bodies"][0]["voids"].as_table()->insert("seed", static_cast<int64_t>(seed));
  return build_scene(doc, "t", ".");
}

}  // namespace

TEST_CASE("porosity of a study-sized sample within 0.01 of the target", "[porous]") {
  for (double target : {0.09, 0.41, 0.50}) {
    const Scene s = sample(target, 7);
    const double dense = 1e6;  // points of the dense sample
    const double achieved = 1.0 - s.particles.size() / dense;
    WARN("target " << target << " achieved " << achieved << " with " << s.bodies[0].voids << " voids");
    CHECK(std::fabs(achieved - target) < 0.01);
    CHECK(s.bodies[0].porosity == Approx(achieved).margin(1e-12));  // what run.json reports
    // Boolean model of overlapping discs: porosity 1 - exp(-N pi r^2 / A) for N voids
    const double boolean = 1.0 - std::exp(-s.bodies[0].voids * M_PI * 1e-10 / 1e-6);
    CHECK(achieved == Approx(boolean).margin(0.02));
  }
}

TEST_CASE("same seed, same sample on any thread count; another seed, another sample", "[porous]") {
  const int t0 = omp_get_max_threads();
  omp_set_num_threads(1);
  const Scene a = sample(0.5, 3);
  omp_set_num_threads(2);
  const Scene b = sample(0.5, 3);
  omp_set_num_threads(t0);
  const Scene c = sample(0.5, 4);
  CHECK((a.particles.x == b.particles.x));  // (parenthesised: no element-wise printing)
  CHECK((a.particles.y == b.particles.y));
  CHECK((a.particles.x != c.particles.x));
}

TEST_CASE("mirror copy: the flyer is the target reflected about the impact plane", "[porous]") {
  Particles P;
  P.resize(3);
  P.x = {1, 2, 3};
  P.y = {0.5, 1.5, 2.5};
  const Particles Q = mirror_y(P, 0.0);
  CHECK(Q.x == P.x);
  CHECK(Q.y == std::vector<double>{-0.5, -1.5, -2.5});
}

TEST_CASE("a 50 % porous block on the wall at 1000 m/s runs stably", "[verification][porous][stability]") {
  auto doc = parse_case_file(std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/porous_impact_1000.toml");
  Scene sc = build_scene(doc, "porous", std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify");
  CHECK(sc.bodies[0].porosity == Approx(0.5).margin(0.01));
  Simulation sim(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
  const double E0 = sim.energy().total();
  double worst = 0.0;
  while (sim.time() < sc.run.end_time) {
    sim.step(sc.run.end_time - sim.time());  // throws StepError on an inverted point
    if (sim.steps() % 50 == 0) worst = std::max(worst, std::fabs(sim.energy().total() - E0) / E0);
  }
  const auto& P = sim.particles();
  bool finite = true;
  double Tmax = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    finite = finite && std::isfinite(P.p[i]) && std::isfinite(P.e[i]) && std::isfinite(P.x[i]) && P.V[i] > 0;
    Tmax = std::max(Tmax, sim.thermo()[0].temperature(P.m[i] / P.V[i], P.e[i]));
  }
  WARN("energy error (worst) " << worst << ", T max " << Tmax << " K, steps " << sim.steps());
  CHECK(finite);
  // Kinetic + internal energy drifts down steadily, by 3.2 % over 100 ns here (the dense
  // impact: 0.06 %). It does not change with cfl, so it is not the USL step's O(dt) error; its
  // source is open (docs/verification.md). Bound at 5 %, which the drift stays well inside.
  CHECK(worst < 0.05);
}
