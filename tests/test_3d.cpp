// The engine built for three axes (SMPM_DIM = 3): an elastic bar's vibration period against the
// exact one, bitwise-identical particle arrays with 1, 2 and 3 threads, a restart from a
// checkpoint bitwise like the uninterrupted run, and the 3D case keys. The shock checks (the dense
// column, the void collapse) are tests/test_3d_shock.cpp.
#include <catch2/catch.hpp>
#include <omp.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "engine/case_reader.hpp"
#include "engine/checkpoint.hpp"
#include "engine/diagnostics.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"
#include "tests/gradient_arrays.hpp"
#include "tests/particle_checks.hpp"
#include "tests/verify_cases.hpp"

using namespace smpm;
static_assert(kern::kDim == 3, "tests/test_3d.cpp is compiled for the 3D engine (SMPM_DIM=3)");

namespace {

using test::verify_scene;

// Every array of the particles, by the checkpoint's names.
const std::initializer_list<const char*> kAllArrays = {"x",   "y",   "z",   "vx",  "vy",  "vz",  "m",   "V",     "sxx",
                                                       "syy", "szz", "sxy", "sxz", "syz", "p",   "curl2", "div", "rate2"};

}  // namespace

// tests/test_elastic.cpp's fixed-free bar (Sulsky/Bardenhagen: L = 25, E = 100, rho = 1, nu = 0,
// v0 = 0.1 sin(pi x / 2L); period 4 L / c = 10), one cell across in y and z between slip walls.
TEST_CASE("3D: axial vibration of an elastic bar, period and amplitude", "[verification][3d]") {
  const double L = 25.0, h = 0.5;
  kern::GridGeom g;
  g.h = h;
  g.n[0] = static_cast<int>(std::lround(30.0 / h));
  g.n[1] = g.n[2] = 1;
  SolverConfig cfg;
  cfg.cfl = 0.2;
  cfg.walls.lo[0] = kern::Wall::Slip;
  for (int a : {1, 2}) cfg.walls.lo[a] = cfg.walls.hi[a] = kern::Wall::Slip;
  Particles P = fill_rectangle(g, 2, Box{{0.0, 0.0, 0.0}, {L, h, h}}, 1.0, Vector{}, 0);
  for (std::size_t i = 0; i < P.size(); ++i) P.v[0][i] = 0.1 * std::sin(M_PI * P.x[0][i] / (2 * L));
  Material m;
  m.name = "elastic";
  m.rho0 = 1.0;
  m.E = 100.0;
  m.nu = 0.0;
  Simulation sim(g, cfg, {m}, {0}, P);
  double M = 0;
  for (double mi : sim.particles().m) M += mi;
  std::vector<double> zeros;  // zero crossings of the centre-of-mass velocity
  double amp = 0, prev_t = 0, prev_v = sim.momentum()[0] / M;
  while (sim.time() < 20.0) {
    sim.step(20.0 - sim.time());
    const double v = sim.momentum()[0] / M;
    if ((prev_v > 0) != (v > 0)) zeros.push_back(prev_t + (sim.time() - prev_t) * prev_v / (prev_v - v));
    if (sim.time() > 15.0) amp = std::max(amp, std::fabs(v));
    prev_t = sim.time();
    prev_v = v;
  }
  REQUIRE(zeros.size() >= 4);
  const double period = (zeros[3] - zeros[0]) / 1.5;
  WARN("3D bar: period " << period << " (exact 10), amplitude " << amp << " (exact " << 0.2 / M_PI << ")");
  CHECK(period == Approx(10.0).epsilon(0.01));
  CHECK(amp == Approx(0.2 / M_PI).epsilon(0.02));
}

// 25 steps of the void collapse: the shock has entered, the void faces move in their own fields.
TEST_CASE("3D velocity-gradient measures: rigid rotation and uniform expansion", "[diagnostics][3d]") {
  const auto measures = test::point_with_measures;
  // rigid rotation v = w x x, w = (1, 2, 3) /s: L = [[0, -3, 2], [3, 0, -1], [-2, 1, 0]]
  const Particles r = measures({0, -3, 2, 3, 0, -1, -2, 1, 0});
  CHECK(r.curl2[0] == Approx(4 * 14.0));  // curl v = 2 w
  CHECK(r.div[0] == 0.0);
  CHECK(r.rate2[0] == 0.0);
  const double a = 0.7;  // uniform expansion v = a x: L = a I
  const Particles e = measures({a, 0, 0, 0, a, 0, 0, 0, a});
  CHECK(e.div[0] == Approx(3 * a));
  CHECK(e.curl2[0] == 0.0);
  CHECK(e.rate2[0] == Approx(3 * a * a));
  // pure shear v = (g y, 0, 0): D_xy = D_yx = g / 2, curl v = (0, 0, -g)
  const Particles s = measures({0, 2.0, 0, 0, 0, 0, 0, 0, 0});
  CHECK(s.rate2[0] == Approx(2.0));
  CHECK(s.curl2[0] == Approx(4.0));
}

TEST_CASE("3D determinism: bitwise-identical particle arrays with 1, 2 and 3 threads", "[determinism][3d]") {
  const int threads0 = omp_get_max_threads();
  std::vector<Particles> out;
  for (int threads : {1, 2, 3}) {
    omp_set_num_threads(threads);
    Scene sc = verify_scene("void_collapse_3d.toml", {"solver.permute_every=7"});
    Simulation sim(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
    for (int s = 0; s < 25; ++s) sim.step();
    out.push_back(sim.particles());
  }
  omp_set_num_threads(threads0);
  for (int k : {1, 2}) {
    INFO("threads " << k + 1 << " against 1");
    REQUIRE(out[0].id == out[k].id);
    test::require_same(out[0], out[k], kAllArrays);
  }
}

TEST_CASE("3D restart: a resumed simulation steps bitwise like the uninterrupted one", "[checkpoint][restart][3d]") {
  Scene sc = verify_scene("void_collapse_3d.toml");
  Simulation a(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
  for (int s = 0; s < 20; ++s) a.step();
  const auto file = std::filesystem::temp_directory_path() / "smpm_test_3d_ckpt.bin";
  {
    CheckpointWriter w(file);
    a.save(w);
    w.commit();
  }
  Simulation b(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
  b.restore(CheckpointReader(file));
  std::filesystem::remove(file);
  for (int s = 0; s < 20; ++s) {
    a.step();
    b.step();
  }
  REQUIRE(a.particles().id == b.particles().id);
  test::require_same(a.particles(), b.particles(), kAllArrays);
  CHECK(a.time() == b.time());
  CHECK(a.energy().total() == b.energy().total());
}

namespace {
// The message of the CaseError that building cases/verify/<file> with `sets` throws ("" if none).
std::string error_of(const std::vector<std::string>& sets) {
  try {
    verify_scene("void_collapse_3d.toml", sets);
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}
bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }
}  // namespace

TEST_CASE("3D case keys: a missing or 2D-only key is refused by name", "[case][3d]") {
  CHECK(error_of({}) == "");
  auto without = [](const char* table, const char* key) {
    auto doc = parse_case_file(std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/void_collapse_3d.toml");
    if (std::string(table) == "grid") doc["grid"].as_table()->erase(key);
    else doc["bodies"].as_array()->get(0)->as_table()->erase(key);
    try {
      build_scene(doc, "t", std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify");
    } catch (const CaseError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(has(without("grid", "z_range_um"), "z_range"));
  CHECK(has(without("bodies", "z_range_um"), "z_range"));
  CHECK(has(error_of({"bodies.0.velocity_m_s=[0.0, -1000.0]"}), "expected 3 numbers"));
  CHECK(has(error_of({"bodies.0.voids.center_um=[32.0, 50.0]"}), "expected 3 numbers"));
  CHECK(has(error_of({"bodies.0.shape=\"disk\""}), "allowed 'box', 'sphere'"));
  CHECK(has(error_of({"grid.dimension=2"}), "this engine is built for 3 axes"));
  CHECK(has(error_of({"grid.tile_cells=16"}), "allowed 4 to 8"));
  CHECK(has(error_of({"walls.front=\"slip\""}), "periodic_z = true has no back or front wall"));
}
