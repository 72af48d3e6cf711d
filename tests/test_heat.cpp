// Heat conduction on the grid against the exact solution of a 1D temperature step.
#include <catch2/catch.hpp>

#include <cmath>

#include "engine/scene.hpp"
#include "engine/simulation.hpp"

using namespace smpm;

// Two half-spaces at T1 and T2 in contact at y = y0: T(y, t) = (T1 + T2)/2 + (T2 - T1)/2
// erf((y - y0) / (2 sqrt(alpha t))), alpha = k / (rho cv). The material has no e-dependent
// pressure and no strength (linear EOS, strength "none"), so heating moves nothing and the
// check isolates conduction. Dimensionless SI values: rho = cv = k = 1, h = 0.01 m, run to
// sqrt(alpha t) = 10 h; insulated ends 50 h away from the step.
TEST_CASE("heat conduction: 1D temperature step against the erf solution", "[verification][heat]") {
  kern::GridGeom g;
  g.h = 0.01;
  g.n[0] = 4;
  g.n[1] = 100;
  g.wrap[0] = true;
  Material m;
  m.name = "conductor";
  m.eos = LinearEosModel{};
  m.strength = NoStrengthModel{};
  m.rho0 = 1.0;
  m.E = 1.0;
  m.nu = 0.25;
  m.cv = 1.0;
  m.conductivity = 1.0;
  m.T0 = 300.0;
  SolverConfig cfg;
  cfg.heat_conduction = true;
  const double y0 = 0.5, T1 = 400.0, T2 = 300.0;
  for (auto shape : {kern::ShapeKind::Linear, kern::ShapeKind::Quadratic}) {
    cfg.shape = shape;
    Particles P = fill_rectangle(g, 2, Box{{0.0, 0.0}, {0.04, 1.0}}, 1.0, Vector{0.0, 0.0}, 0);
    Simulation sim(g, cfg, {m}, {0}, P);
    auto& Q = sim.particles();
    for (std::size_t i = 0; i < Q.size(); ++i) Q.e[i] = m.cv * ((Q.x[1][i] < y0 ? T1 : T2) - m.T0);
    const double alpha = 1.0, t_end = 100 * g.h * g.h / alpha;  // sqrt(alpha t) = 10 h
    REQUIRE(sim.stable_dt() == Approx(sim.heat_dt()));
    double E0 = 0;
    for (std::size_t i = 0; i < Q.size(); ++i) E0 += Q.m[i] * Q.e[i];
    while (sim.time() < t_end) sim.step(t_end - sim.time());
    double err = 0, E1 = 0;
    for (std::size_t i = 0; i < Q.size(); ++i) {
      const double T = sim.thermo()[0].temperature(Q.m[i] / Q.V[i], Q.e[i]);
      const double exact = 0.5 * (T1 + T2) + 0.5 * (T2 - T1) * std::erf((Q.x[1][i] - y0) / (2 * std::sqrt(alpha * t_end)));
      err = std::max(err, std::fabs(T - exact) / (T1 - T2));
      E1 += Q.m[i] * Q.e[i];
    }
    WARN("shape " << int(shape) << ": max error " << err << " of the jump, " << sim.steps() << " steps");
    CHECK(err < 0.02);
    CHECK(E1 == Approx(E0).epsilon(1e-12));  // conduction moves heat, creates none
  }
}
