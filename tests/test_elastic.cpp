// Verification of the elastic MPM core against exact or published answers
// (docs/model.md, "Exact checks"), and bitwise determinism across thread counts.
#include <catch2/catch.hpp>
#include <omp.h>

#include <cmath>
#include <vector>

#include "engine/scene.hpp"
#include "engine/simulation.hpp"

using namespace smpm;

namespace {

Material elastic(double rho, double E, double nu) {
  Material m;
  m.name = "elastic";
  m.rho0 = rho;
  m.E = E;
  m.nu = nu;
  return m;
}

// Axial vibration of a fixed-free bar (Sulsky/Bardenhagen): L = 25, E = 100, rho = 1, nu = 0,
// v0(x) = 0.1 sin(pi x / 2L). Exact: period 4 L / c = 10.0, centre-of-mass velocity
// amplitude 0.1 * 2 / pi = 0.0637. The bar is one cell high between slip walls (uniaxial strain,
// which with nu = 0 is uniaxial stress); the fixed end is a slip wall at x = 0.
struct BarResult {
  double period, amplitude;
};

BarResult bar(kern::ShapeKind shape, double h, Scheme scheme, Transfer transfer) {
  const double L = 25.0;
  kern::GridGeom g;
  g.h = h;
  g.n[0] = static_cast<int>(std::lround(30.0 / h));
  g.n[1] = 1;
  SolverConfig cfg;
  cfg.shape = shape;
  cfg.scheme = scheme;
  cfg.transfer = transfer;
  cfg.flip_alpha = 1.0;
  cfg.cfl = 0.2;
  cfg.walls.lo[0] = kern::Wall::Slip;
  cfg.walls.lo[1] = cfg.walls.hi[1] = kern::Wall::Slip;
  Particles P = fill_rectangle(g, 2, Box{{0.0, 0.0}, {L, h}}, 1.0, Vector{0.0, 0.0}, 0);
  for (std::size_t i = 0; i < P.size(); ++i) P.v[0][i] = 0.1 * std::sin(M_PI * P.x[0][i] / (2 * L));
  Simulation sim(g, cfg, {elastic(1.0, 100.0, 0.0)}, {0}, P);
  auto vcm = [&] {
    const auto q = sim.momentum();
    double M = 0;
    for (double m : sim.particles().m) M += m;
    return q[0] / M;
  };
  const double v0 = vcm();
  // zero crossings of v_cm (at T/4, 3T/4, 5T/4, 7T/4), linearly interpolated
  std::vector<double> zeros;
  double amp = 0, prev_t = 0, prev_v = v0;
  while (sim.time() < 20.0) {
    sim.step(20.0 - sim.time());
    const double v = vcm();
    if ((prev_v > 0) != (v > 0)) zeros.push_back(prev_t + (sim.time() - prev_t) * prev_v / (prev_v - v));
    if (sim.time() > 15.0) amp = std::max(amp, std::fabs(v));  // the fourth half-period: after damping
    prev_t = sim.time();
    prev_v = v;
  }
  REQUIRE(zeros.size() >= 4);
  // period from the first and fourth crossing: they are 1.5 periods apart
  return {(zeros[3] - zeros[0]) / 1.5, amp};
}

}  // namespace

// Both with the default USL + APIC. The linear hat runs Sulsky's 25 cells (h = 1), where no point
// crosses a node (they sit 0.25 h from nodes, the end moves 0.16): at h = 0.5 the free-end point
// crosses node x = L, the node gets a sliver of mass under a full-size force and the velocity
// gradient blows up (USL) or the mode fills with cell-crossing noise (MUSL + FLIP: amplitude -6 %
// at h = 0.5, -34 % at h = 0.125). That is the linear hat's known defect, not the transfer's;
// see docs/verification.md.
TEST_CASE("axial vibration of an elastic bar: period and amplitude", "[verification][elastic]") {
  SECTION("linear hat, h = L / 25") {
    const auto r = bar(kern::ShapeKind::Linear, 1.0, Scheme::USL, Transfer::APIC);
    WARN("period " << r.period << " amplitude " << r.amplitude);
    CHECK(r.period == Approx(10.0).epsilon(0.01));
    CHECK(r.amplitude == Approx(0.1 * 2 / M_PI).epsilon(0.02));
  }
  SECTION("quadratic B-spline, h = L / 50") {
    const auto r = bar(kern::ShapeKind::Quadratic, 0.5, Scheme::USL, Transfer::APIC);
    WARN("period " << r.period << " amplitude " << r.amplitude);
    CHECK(r.period == Approx(10.0).epsilon(0.01));
    CHECK(r.amplitude == Approx(0.1 * 2 / M_PI).epsilon(0.02));
  }
}

// Two elastic disks colliding head-on (Sulsky, Chen and Schreyer 1994): unit square, disks of
// radius 0.2 at (0.25, 0.25) and (0.75, 0.75) moving at +-(0.1, 0.1), E = 1000, nu = 0.3,
// rho = 1000, 4 points per cell. Kinetic energy turns into strain energy during the collision
// and back; the total stays constant. Sulsky's scheme (MUSL, FLIP) at h = 0.025, and USL with
// FLIP at h = 0.0125. (APIC, being PIC-like, dissipates: 14 % at h = 0.025, see docs.)
TEST_CASE("two colliding elastic disks conserve energy", "[verification][elastic]") {
  for (auto [scheme, h] : {std::pair{Scheme::MUSL, 0.025}, std::pair{Scheme::USL, 0.0125}}) {
    kern::GridGeom g;
    g.h = h;
    g.n[0] = g.n[1] = static_cast<int>(std::lround(1.0 / h));
    SolverConfig cfg;
    cfg.shape = kern::ShapeKind::Quadratic;
    cfg.transfer = Transfer::FLIP;
    cfg.flip_alpha = 1.0;
    cfg.scheme = scheme;
    cfg.cfl = 0.3;
    Particles P;
    const double d = g.h / 2;
    for (int b = 0; b < 2; ++b) {
      const double cx = b ? 0.75 : 0.25, cy = cx, v = b ? -0.1 : 0.1;
      Particles Q = fill_rectangle(g, 2, Box{{cx - 0.2, cy - 0.2}, {cx + 0.2, cy + 0.2}}, 1000.0, Vector{v, v}, static_cast<std::uint8_t>(b));
      Particles R;
      R.resize(0);
      std::vector<std::size_t> keep;
      for (std::size_t i = 0; i < Q.size(); ++i)
        if ((Q.x[0][i] - cx) * (Q.x[0][i] - cx) + (Q.x[1][i] - cy) * (Q.x[1][i] - cy) < 0.04) keep.push_back(i);
      R.resize(keep.size());
      for (std::size_t k = 0; k < keep.size(); ++k) {
        const auto i = keep[k];
        R.x[0][k] = Q.x[0][i]; R.x[1][k] = Q.x[1][i]; R.v[0][k] = v; R.v[1][k] = v;
        R.m[k] = 1000.0 * d * d; R.V[k] = d * d; R.body[k] = static_cast<std::uint8_t>(b);
      }
      P.append(R);
    }
    Simulation sim(g, cfg, {elastic(1000.0, 1000.0, 0.3)}, {0, 0}, P);
    const double E0 = sim.energy().total();
    double emin = E0, emax = E0, kmin = E0;
    while (sim.time() < 3.0) {
      sim.step(3.0 - sim.time());
      const auto e = sim.energy();
      emin = std::min(emin, e.total());
      emax = std::max(emax, e.total());
      kmin = std::min(kmin, e.kinetic);
    }
    WARN("scheme " << int(scheme) << ", h " << h << ": E0 " << E0 << " min " << emin << " max " << emax << " min kinetic " << kmin);
    CHECK(kmin < 0.5 * E0);  // the disks did collide: most kinetic energy went into strain energy
    CHECK(emin > 0.97 * E0);
    CHECK(emax < 1.03 * E0);
  }
}

// A rigidly translating block crosses the periodic boundary and comes back to its start.
TEST_CASE("periodic sides: a translating block returns to its start", "[verification][elastic]") {
  kern::GridGeom g;
  g.h = 0.05;
  g.n[0] = 20;  // L = 1
  g.n[1] = 12;
  g.wrap[0] = true;
  // (the linear hat is left out: a uniform translation crosses cells, see the bar test)
  for (auto shape : {kern::ShapeKind::UGIMP, kern::ShapeKind::Quadratic, kern::ShapeKind::Cubic}) {
    SolverConfig cfg;
    cfg.shape = shape;
    cfg.fixed_dt = 1.0 / 400;  // 400 steps for one period at v = 1
    Particles P = fill_rectangle(g, 2, Box{{0.55, 0.2}, {0.95, 0.4}}, 10.0, Vector{1.0, 0.0}, 0);
    const auto x0 = P.x[0], y0 = P.x[1];
    Simulation sim(g, cfg, {elastic(10.0, 1e3, 0.3)}, {0}, P);
    while (sim.time() < 1.0 - 1e-12) sim.step(1.0 - sim.time());
    const auto& Q = sim.particles();
    double err = 0;
    for (std::size_t i = 0; i < Q.size(); ++i) {
      const auto k = Q.id[i];
      err = std::max(err, std::fabs(Q.x[0][i] - x0[k]) + std::fabs(Q.x[1][i] - y0[k]));
    }
    INFO("shape " << int(shape));
    CHECK(sim.steps() == 400);
    CHECK(err < 1e-9);
  }
}

// 200 steps of an elastic impact on a wall give bitwise-identical particle arrays with 1 and 2
// threads, for both transfers and both schemes.
TEST_CASE("determinism: bitwise-identical particle arrays with 1 and 2 threads", "[determinism]") {
  kern::GridGeom g;
  g.h = 1e-3;
  g.n[0] = 48;
  g.n[1] = 40;
  g.wrap[0] = true;
  const int threads0 = omp_get_max_threads();
  for (auto transfer : {Transfer::APIC, Transfer::FLIP})
    for (auto scheme : {Scheme::USL, Scheme::MUSL}) {
      SolverConfig cfg;
      cfg.transfer = transfer;
      cfg.scheme = scheme;
      cfg.permute_every = 7;
      cfg.walls.lo[1] = kern::Wall::Slip;
      std::vector<Particles> out;
      for (int threads : {1, 2}) {
        omp_set_num_threads(threads);
        Particles P = fill_rectangle(g, 2, Box{{0.0, 0.0}, {0.048, 0.03}}, 2700.0, Vector{0.0, -200.0}, 0);
        for (std::size_t i = 0; i < P.size(); ++i) P.v[0][i] = 20.0 * std::sin(200.0 * P.x[1][i]);
        Simulation sim(g, cfg, {elastic(2700.0, 69e9, 0.33)}, {0}, P);
        for (int s = 0; s < 200; ++s) sim.step();
        out.push_back(sim.particles());
      }
      omp_set_num_threads(threads0);
      INFO("transfer " << int(transfer) << " scheme " << int(scheme));
      REQUIRE(out[0].id == out[1].id);
      REQUIRE(out[0].x[0] == out[1].x[0]);
      REQUIRE(out[0].x[1] == out[1].x[1]);
      REQUIRE(out[0].v[0] == out[1].v[0]);
      REQUIRE(out[0].v[1] == out[1].v[1]);
      REQUIRE(out[0].s[0] == out[1].s[0]);
      REQUIRE(out[0].p == out[1].p);
      REQUIRE(out[0].V == out[1].V);
    }
}
