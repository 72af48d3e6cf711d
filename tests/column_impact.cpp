// tests/column_impact.hpp for the engine built for SMPM_DIM axes.
#include "kernels/dimension.hpp"
#include "tests/column_impact.hpp"

#include <algorithm>
#include <cmath>
#include <variant>

#include "engine/case_reader.hpp"
#include "engine/diagnostics.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"
#include "engine/thermo.hpp"

namespace SMPM_NS {
namespace {

// Least-squares slope of y(t).
double slope(const std::vector<double>& t, const std::vector<double>& y) {
  double st = 0, sy = 0, stt = 0, sty = 0;
  const double n = static_cast<double>(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    st += t[i]; sy += y[i]; stt += t[i] * t[i]; sty += t[i] * y[i];
  }
  return (n * sty - st * sy) / (n * stt - st * st);
}

// Mean of `value` over the body's particles per layer of height h along the impact axis.
std::vector<double> layer_mean(const Particles& P, const kern::GridGeom& g, const std::vector<double>& value) {
  const int n = g.n[kImpactAxis];
  std::vector<double> sum(n, 0.0), cnt(n, 0.0);
  for (std::size_t i = 0; i < P.size(); ++i) {
    const int r = static_cast<int>((P.x[kImpactAxis][i] - g.lo[kImpactAxis]) / g.h);
    if (r < 0 || r >= n) continue;
    sum[r] += value[i];
    cnt[r] += 1;
  }
  for (int r = 0; r < n; ++r) sum[r] = cnt[r] > 0 ? sum[r] / cnt[r] : 0.0;
  return sum;
}

// -sigma along the impact axis with the viscous pressure: P + q - s_yy
std::vector<double> normal_stress(const Particles& P) {
  std::vector<double> s(P.size());
  const int yy = kern::sym_index(kern::kDim, kImpactAxis, kImpactAxis);
  for (std::size_t i = 0; i < P.size(); ++i) s[i] = P.p[i] + (P.q.empty() ? 0.0 : P.q[i]) - P.s[yy][i];
  return s;
}

}  // namespace
}  // namespace SMPM_NS

namespace smpm::verify {

template <>
ColumnImpact column_impact<kern::kDim>(const std::string& file, const std::vector<std::string>& overrides) {
  auto doc = parse_case_file(std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/" + file);
  apply_overrides(doc, overrides);
  Scene sc = build_scene(doc, file, std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify");
  const int y = kImpactAxis;
  const double v = -sc.bodies[0].velocity[y];
  const Material mat = sc.materials[0];
  const auto& g = sc.geom;
  Simulation sim(g, sc.solver, sc.materials, sc.body_material, sc.particles);
  ColumnImpact r;
  const HugoniotState exact = hugoniot(mat, v);
  r.exact_Us = exact.Us;
  r.exact_P = exact.P;
  r.exact_rho = exact.rho;
  r.exact_T = exact.T;
  r.particles = static_cast<long>(sc.particles.size());
  double area = 1.0;  // the wall's (per unit depth at D = 2)
  for (int a = 0; a < kern::kDim; ++a)
    if (a != y) area *= g.length(a);
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
      wall_sum += sim.wall_forces().lo[y] / area;
      wall_n += 1;
    }
    if (sim.steps() % 10 == 0 && t > 0.2 * t_end) {
      tf.push_back(t);
      yf.push_back(front_position(sim.particles(), 0, -v, g.lo[y], g.h, g.n[y], true));
      // elastic precursor: leading edge where the layer mean of -sigma_yy passes HEL / 2
      const auto layer = layer_mean(sim.particles(), g, normal_stress(sim.particles()));
      for (int k = g.n[y] - 1; k > 0; --k)
        if (layer[k] > 0.5 * hel) {
          const double a = layer[k + 1 < g.n[y] ? k + 1 : k], b = layer[k];
          tp.push_back(t);
          yp.push_back(g.lo[y] + (k + 0.5) * g.h + g.h * (b - 0.5 * hel) / std::max(b - a, 1e-30));
          break;
        }
    }
  }
  const auto& P = sim.particles();
  r.steps = sim.steps();
  r.Us = slope(tf, yf) + v;  // lab-frame speed plus the speed of the material ahead
  r.wall = wall_sum / wall_n;
  const double E1 = sim.energy().total();
  r.energy_error = (E1 - E0) / E0;
  // energy removed at walls and contacts, unless the run turns it into heat (then it is in E1)
  const double lost = sim.removed_is_heat() ? 0.0 : sim.removed().wall + sim.removed().contact;
  r.energy_residual = (E1 + lost - E0) / E0;
  r.precursor_speed = tp.size() > 1 ? slope(tp, yp) + v : 0.0;
  // averages behind the shock, away from the wall's start-up layer and from the front
  const double front = front_position(P, 0, -v, g.lo[y], g.h, g.n[y], true);
  const Thermo th(mat);
  double n = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    r.finite = r.finite && std::isfinite(P.p[i]) && std::isfinite(P.v[y][i]) && P.V[i] > 0;
    if (P.x[y][i] < 100e-6 || P.x[y][i] > front - 20 * g.h) continue;
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
  if (!yp.empty()) {
    const auto layer = layer_mean(P, g, normal_stress(P));
    r.precursor_amplitude = layer[static_cast<int>((0.5 * (front + yp.back()) - g.lo[y]) / g.h)];
  }
  return r;
}

}  // namespace smpm::verify
