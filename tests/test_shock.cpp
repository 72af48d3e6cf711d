// Dense symmetric impact (rigid-wall half model) against the exact jump conditions of the
// code's own Hugoniot (docs/model.md, "Exact checks"), run from the case files in cases/verify/.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "engine/case_reader.hpp"
#include "engine/diagnostics.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"
#include "engine/thermo.hpp"

using namespace smpm;

namespace {

struct ImpactResult {
  double Us = 0;            // shock speed relative to the material ahead [m/s]
  double wall = 0;          // mean wall stress over the second half [Pa]
  double P = 0, rho = 0, T = 0;  // means behind the shock [Pa, kg/m^3, K]
  double energy_error = 0;  // (E_end - E_0) / E_0
  double precursor_speed = 0, precursor_amplitude = 0;  // [m/s], [Pa]
  HugoniotState exact;
  bool finite = true;
};

// Least-squares slope of y(t).
double slope(const std::vector<double>& t, const std::vector<double>& y) {
  double st = 0, sy = 0, stt = 0, sty = 0;
  const double n = static_cast<double>(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    st += t[i]; sy += y[i]; stt += t[i] * t[i]; sty += t[i] * y[i];
  }
  return (n * sty - st * sy) / (n * stt - st * st);
}

// Mean over rows of -sigma_yy of the body's particles, per row of height h.
std::vector<double> row_mean(const Particles& P, const kern::GridGeom& g, const std::vector<double>& value) {
  std::vector<double> sum(g.n[1], 0.0), cnt(g.n[1], 0.0);
  for (std::size_t i = 0; i < P.size(); ++i) {
    const int r = static_cast<int>((P.x[1][i] - g.lo[1]) / g.h);
    if (r < 0 || r >= g.n[1]) continue;
    sum[r] += value[i];
    cnt[r] += 1;
  }
  for (int r = 0; r < g.n[1]; ++r) sum[r] = cnt[r] > 0 ? sum[r] / cnt[r] : 0.0;
  return sum;
}

ImpactResult run_impact(const std::string& file, const std::vector<std::string>& overrides = {}) {
  auto doc = parse_case_file(std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/" + file);
  apply_overrides(doc, overrides);
  Scene sc = build_scene(doc, file, std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify");
  const double v = -sc.bodies[0].velocity[1];
  const Material mat = sc.materials[0];
  const auto& g = sc.geom;
  Simulation sim(g, sc.solver, sc.materials, sc.body_material, sc.particles);
  ImpactResult r;
  r.exact = hugoniot(mat, v);
  const double E0 = sim.energy().total();
  const double t_end = sc.run.end_time;
  const double G = mat.shear_modulus(), K = mat.bulk_modulus();
  const double hel = std::get<VonMisesModel>(mat.strength).Y0 * (K / (2 * G) + 2.0 / 3.0);
  std::vector<double> tf, yf, tp, yp;
  double wall_sum = 0, wall_n = 0;
  while (sim.time() < t_end) {
    sim.step(t_end - sim.time());
    const double t = sim.time();
    if (t > 0.5 * t_end) {
      wall_sum += sim.wall_forces().lo[kImpactAxis] / g.length(0);
      wall_n += 1;
    }
    if (sim.steps() % 10 == 0 && t > 0.2 * t_end) {
      const double y = front_position(sim.particles(), 0, -v, g.lo[1], g.h, g.n[1], true);
      tf.push_back(t);
      yf.push_back(y);
      // elastic precursor: leading edge where the row mean of -sigma_yy passes HEL / 2
      const auto& P = sim.particles();
      std::vector<double> syy(P.size());
      for (std::size_t i = 0; i < P.size(); ++i) syy[i] = P.p[i] + (P.q.empty() ? 0.0 : P.q[i]) - P.s[1][i];
      const auto row = row_mean(P, g, syy);
      for (int k = g.n[1] - 1; k > 0; --k)
        if (row[k] > 0.5 * hel) {
          const double a = row[k + 1 < g.n[1] ? k + 1 : k], b = row[k];
          tp.push_back(t);
          yp.push_back(g.lo[1] + (k + 0.5) * g.h + g.h * (b - 0.5 * hel) / std::max(b - a, 1e-30));
          break;
        }
    }
  }
  const auto& P = sim.particles();
  r.Us = slope(tf, yf) + v;  // lab-frame speed plus the speed of the material ahead
  r.wall = wall_sum / wall_n;
  r.energy_error = (sim.energy().total() - E0) / E0;
  r.precursor_speed = slope(tp, yp) + v;
  // averages behind the shock, away from the wall's start-up layer and from the front
  const double front = front_position(P, 0, -v, g.lo[1], g.h, g.n[1], true);
  const Thermo th(mat);
  double n = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    r.finite = r.finite && std::isfinite(P.p[i]) && std::isfinite(P.v[1][i]) && P.V[i] > 0;
    if (P.x[1][i] < 100e-6 || P.x[1][i] > front - 20 * g.h) continue;
    const double rho = P.m[i] / P.V[i];
    r.P += P.p[i];
    r.rho += rho;
    r.T += th.temperature(rho, P.e[i]);
    n += 1;
  }
  r.P /= n;
  r.rho /= n;
  r.T /= n;
  // precursor amplitude: -sigma_yy midway between the plastic front and the precursor front
  std::vector<double> syy(P.size());
  for (std::size_t i = 0; i < P.size(); ++i) syy[i] = P.p[i] + P.q[i] - P.s[1][i];
  const auto row = row_mean(P, g, syy);
  const double ymid = 0.5 * (front + yp.back());
  r.precursor_amplitude = row[static_cast<int>((ymid - g.lo[1]) / g.h)];
  return r;
}

void check_plateau(const ImpactResult& r) {
  WARN("Us " << r.Us << " (exact " << r.exact.Us << "), wall " << r.wall << " P " << r.P << " (exact " << r.exact.P
             << "), rho " << r.rho << " (exact " << r.exact.rho << "), T " << r.T << " (exact " << r.exact.T
             << "), energy error " << r.energy_error);
  CHECK(r.finite);
  CHECK(r.Us == Approx(r.exact.Us).epsilon(0.02));
  CHECK(r.wall == Approx(r.exact.P).epsilon(0.02));
  CHECK(r.P == Approx(r.exact.P).epsilon(0.02));
  CHECK(r.rho == Approx(r.exact.rho).epsilon(0.01));
  CHECK(r.T == Approx(r.exact.T).epsilon(0.05));
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
