// Porous samples: porosity against the target, reproducibility; a 50 % porous block on the
// rigid wall at 1000 m/s runs stably.
#include <catch2/catch.hpp>
#include <omp.h>

#include <array>
#include <cmath>

#include "engine/case_reader.hpp"
#include "engine/diagnostics.hpp"
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
  CHECK((a.particles.x[0] == b.particles.x[0]));  // (parenthesised: no element-wise printing)
  CHECK((a.particles.x[1] == b.particles.x[1]));
  CHECK((a.particles.x[0] != c.particles.x[0]));
}

TEST_CASE("mirror copy: the flyer is the target reflected about the impact plane", "[porous]") {
  Particles P;
  P.resize(3);
  P.x[0] = {1, 2, 3};
  P.x[1] = {0.5, 1.5, 2.5};
  const Particles Q = mirror(P, kImpactAxis, 0.0);
  CHECK(Q.x[0] == P.x[0]);
  CHECK(Q.x[1] == std::vector<double>{-0.5, -1.5, -2.5});
}

TEST_CASE("a 50 % porous block on the wall at 1000 m/s runs stably", "[verification][porous][stability]") {
  auto doc = parse_case_file(std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/porous_impact_1000.toml");
  // half the case's width (100 um, 6 void diameters, periodic): the same 100 ns, half the cost
  apply_overrides(doc, {"grid.x_range_um=[0.0, 100.0]", "bodies.target.x_range_um=[0.0, 100.0]"});
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
    finite = finite && std::isfinite(P.p[i]) && std::isfinite(P.e[i]) && std::isfinite(P.x[0][i]) && P.V[i] > 0;
    Tmax = std::max(Tmax, sim.thermo()[0].temperature(P.m[i] / P.V[i], P.e[i]));
  }
  WARN("energy error (worst) " << worst << ", T max " << Tmax << " K, steps " << sim.steps());
  CHECK(finite);
  // Kinetic + internal energy: the step conserves it (mid-step strain rate, old-stress work;
  // the transfers', the welds' and the wall's losses heat the points: docs/method.md).
  // Measured: 1.4e-10 (7.7e-11 at the full 200 um). Bound at 0.5 %, the figure the porous runs must meet.
  CHECK(sim.midstep());
  CHECK(worst < 0.005);
}

// A porous body in free flight is at rest in its own frame: nothing may grow out of round-off.
// With the mid-step strain rate in the kinematics too, the strip below reaches 4.3e5 Pa at
// 80 ns and 4.8e8 Pa at 160 ns in its thin ligaments, and the study's runs carry 0.5-0.9 GPa
// of noise in the material ahead of the compaction front (docs/method.md). The kinematics
// take the updated L, the energy the mid-step work: measured 1e-4 Pa and 1e-12 m/s.
TEST_CASE("a porous body in free flight keeps its round-off (mid-step energy, updated kinematics)",
          "[verification][porous][stability]") {
  auto doc = parse_case_file(std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/porous_strip.toml");
  apply_overrides(doc, {"walls.bottom=\"none\"", "grid.y_range_um=[-300.0, 520.0]"});
  Scene sc = build_scene(doc, "free", std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify");
  Simulation sim(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
  REQUIRE(sim.midstep());
  REQUIRE(sc.solver.void_faces == VoidFaces::Separate);
  const double E0 = sim.energy().total();
  const double end = 160e-9;
  while (sim.time() < end) sim.step(end - sim.time());
  const auto& P = sim.particles();
  double pmax = 0.0, dvmax = 0.0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    pmax = std::max(pmax, std::fabs(P.p[i]));
    dvmax = std::max(dvmax, std::hypot(P.v[0][i], P.v[1][i] + 1000.0));
  }
  const double dE = sim.energy().total() / E0 - 1.0;
  WARN("free flight, 160 ns (" << sim.steps() << " steps): max |P| " << pmax << " Pa, max |v - v0| " << dvmax
                               << " m/s, energy change " << dE);
  CHECK(pmax < 1e3);
  CHECK(dvmax < 1e-6);
  CHECK(std::fabs(dE) < 1e-10);
}

TEST_CASE("void sides: the faces of a void across the impact direction lie in different fields", "[porous]") {
  Particles P;
  P.resize(4);
  // a void of radius 1 at the origin; points above, below, beside it, and one far away
  const double xs[] = {0.0, 0.0, 1.5, 0.0}, ys[] = {1.2, -1.2, 0.1, 10.0};
  for (int i = 0; i < 4; ++i) {
    P.x[0][i] = xs[i];
    P.x[1][i] = ys[i];
  }
  assign_void_sides(P, {{0.0, 0.0, 1.0}, {0.0, 20.0, 1.0}}, Vector{0.0, 1.0}, 3.0, Vector{});
  CHECK(int(P.field[0]) == 1);  // above: field 1
  CHECK(int(P.field[1]) == 0);  // below
  CHECK(int(P.field[2]) == 1);  // beside, just above the centre
  CHECK(int(P.field[3]) == 0);  // beyond reach of every void
  // periodic x: a void across the seam
  P.x[0][0] = 9.9;
  assign_void_sides(P, {{0.1, 0.0, 1.0}}, Vector{0.0, 1.0}, 3.0, Vector{10.0, 0.0});
  CHECK(int(P.field[0]) == 1);
}

TEST_CASE("void sides, four fields: the faces across and along the impact direction differ", "[porous]") {
  Particles P;
  P.resize(5);
  // a void of radius 1 at the origin: points above-right, above-left, below-right, below-left,
  // and one beyond reach; the impact direction is y, so field = (above) + 2 (right: (x - c) x s > 0)
  const double xs[] = {0.8, -0.8, 0.8, -0.8, 0.0}, ys[] = {0.8, 0.8, -0.8, -0.8, 10.0};
  for (int i = 0; i < 5; ++i) {
    P.x[0][i] = xs[i];
    P.x[1][i] = ys[i];
  }
  assign_void_sides(P, {{0.0, 0.0, 1.0}, {0.0, 20.0, 1.0}}, Vector{0.0, 1.0}, 3.0, Vector{}, 4);
  CHECK(int(P.field[0]) == 3);
  CHECK(int(P.field[1]) == 1);
  CHECK(int(P.field[2]) == 2);
  CHECK(int(P.field[3]) == 0);
  CHECK(int(P.field[4]) == 0);
  // every pair of faces opposite through the centre, and every pair facing each other across or
  // along y, lies in two fields
  CHECK(P.field[0] != P.field[3]);
  CHECK(P.field[1] != P.field[2]);
  CHECK(P.field[0] != P.field[1]);
  CHECK(P.field[0] != P.field[2]);
  CHECK_THROWS_AS(assign_void_sides(P, {{0.0, 0.0, 1.0}}, Vector{0.0, 1.0}, 3.0, Vector{}, 3), std::invalid_argument);
}

// The single-void test: a void of radius 10 um in dense Al shocked at
// 1000 m/s onto the wall, h = 4 um (2 x 2 points per cell), at 20 ns (collapsed by about 13 ns).
// Open area measured here (pixels of a quarter point spacing): one velocity field 17.0 % of the
// initial void (the faces stop a cell apart), two fields welded where they meet 2.8 % (3.4 % with
// the weld at 0.8 instead of the default 0.9). What remains is open space between points
// scattered by the jet, not a cell-wide gap (by volume the void is closed, bench/void_open_area.py);
// 1 % is not reached by this pixel measure (docs/verification.md). Bounds: 8 % and 5 %.
TEST_CASE("single void collapse at h = 4 um: the faces close", "[verification][porous]") {
  auto run = [](const std::string& mode) {
    auto doc = parse_case_file(std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/void_collapse.toml");
    apply_overrides(doc, {"contact.void_faces=\"" + mode + "\""});
    Scene sc = build_scene(doc, "vc", std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify");
    const auto& g = sc.geom;
    const double pixel = 0.5 * g.h / 4;
    const std::vector<Window> all{Window{{g.lo[0], -1e300}, {g.lo[0] + g.length(0), 1e300}}};
    const double A0 = open_area(sc.particles, 0, all, pixel, kCoverRadius, periods(g), grid_origin(g))[0];
    Simulation sim(g, sc.solver, sc.materials, sc.body_material, sc.particles);
    const double E0 = sim.energy().total();
    while (sim.time() < 20e-9) sim.step(20e-9 - sim.time());
    const double A = open_area(sim.particles(), 0, all, pixel, kCoverRadius, periods(g), grid_origin(g))[0];
    const double dE = sim.energy().total() / E0 - 1.0;
    WARN(mode << ": open area " << A / A0 << " of the initial, energy change " << dE);
    CHECK(A0 == Approx(M_PI * 9.5e-6 * 9.5e-6).epsilon(0.05));  // the disks reach 0.5 um into it
    return std::pair{A / A0, dE};
  };
  const auto [single, dE1] = run("single_field");
  const auto [separate, dE2] = run("separate");
  CHECK(single > 0.08);
  CHECK(separate < 0.05);  // 1 % is not reached by this measure, see the comment above
  CHECK(std::fabs(dE1) < 1e-6);
  CHECK(std::fabs(dE2) < 1e-6);
}

// The porous energy balance beyond the quadratic case: kinetic plus internal energy closes
// (mid-step strain rate, heat from transfers, welds and the wall) for the cubic B-spline and
// uGIMP, for voids of radius 2 cells, and for the symmetric two-body collision at +-2000 m/s
// (no wall: the impact plane is a symmetry plane), with APIC and with FLIP (uGIMP and FLIP with
// the mid-step strain rate asked for by key; solver.strain_rate = "auto" picks it too,
// docs/accuracy.md). Measured over the full 100 ns with the driver: 1e-10 relative or better in
// each (docs/verification.md); run here for 10 ns on a quarter of the sample, 100 x 200 um (the
// balance is exact per step, and in 10 ns no wave reaches the top; FLIP cubic measured with the
// driver only).
TEST_CASE("porous energy closes: cubic, uGIMP, small voids, symmetric 2000 m/s, FLIP, viscosity", "[verification][porous]") {
  struct Variant {
    const char* file;
    std::vector<std::string> sets;
  };
  const Variant variants[] = {
      {"porous_impact_1000.toml", {"solver.shape=\"cubic\""}},
      {"porous_impact_1000.toml", {"solver.shape=\"ugimp\"", "solver.strain_rate=\"midstep\""}},
      {"porous_impact_1000.toml", {"bodies.target.voids.radius_um=4.0"}},
      {"porous_impact_1000.toml", {"bodies.target.voids.radius_um=4.0", "contact.void_face_fields=4"}},
      {"porous_symmetric_1000.toml", {"bodies.target.velocity_m_s=[0.0, -2000.0]"}},
      // FLIP (the 0.99 blend): its transfers' loss heats the points too (kern::g2p_particle)
      {"porous_impact_1000.toml", {"solver.transfer=\"flip\"", "solver.strain_rate=\"midstep\""}},
      {"porous_symmetric_1000.toml",
       {"bodies.target.velocity_m_s=[0.0, -2000.0]", "solver.transfer=\"flip\"", "solver.strain_rate=\"midstep\""}},
      // a flow viscosity (Bingham): its dissipation is plastic work, and heats the points
      {"porous_impact_1000.toml", {"materials.al.flow_viscosity_Pa_s=1000.0"}},
  };
  for (const auto& v : variants) {
    auto doc = parse_case_file(std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/" + v.file);
    const bool wall = std::string(v.file) == "porous_impact_1000.toml";
    apply_overrides(doc, {"grid.x_range_um=[0.0, 100.0]", "bodies.target.x_range_um=[0.0, 100.0]",
                          "bodies.target.y_range_um=[0.0, 200.0]",
                          wall ? "grid.y_range_um=[0.0, 240.0]" : "grid.y_range_um=[-240.0, 240.0]"});
    apply_overrides(doc, v.sets);
    Scene sc = build_scene(doc, "e", std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify");
    REQUIRE(sc.solver.void_faces == VoidFaces::Separate);
    Simulation sim(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
    const double E0 = sim.energy().total();
    while (sim.time() < 10e-9) sim.step(10e-9 - sim.time());
    const double dE = sim.energy().total() / E0 - 1.0;
    WARN(v.file << " " << v.sets.back() << ": energy change " << dE << ", wall took " << sim.removed().wall
                << " J/m, welds " << sim.removed().contact << " J/m, all heat");
    CHECK(sim.midstep());
    CHECK(std::fabs(dE) < 1e-6);
  }
}

TEST_CASE("separated void faces: bitwise the same on 1 and 2 threads", "[porous][determinism]") {
  const std::string nf = GENERATE(as<std::string>{}, "2", "4");  // void-face fields
  auto run = [&](int threads) {
    omp_set_num_threads(threads);
    auto doc = parse_case_file(std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/void_collapse.toml");
    apply_overrides(doc, {"contact.void_face_fields=" + nf});
    Scene sc = build_scene(doc, "vc", std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify");
    Simulation sim(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
    while (sim.time() < 15e-9) sim.step(15e-9 - sim.time());
    const auto e = sim.energy();
    return std::array<double, 4>{e.kinetic, e.internal, sim.removed().contact, sim.particles().x[0][17]};
  };
  const int before = omp_get_max_threads();
  const auto a = run(1), b = run(2);
  omp_set_num_threads(before);
  for (int k = 0; k < 4; ++k) CHECK(a[k] == b[k]);
}
