#include "engine/diagnostics.hpp"

#include <cmath>
#include <limits>

namespace smpm {

double front_position(const Particles& P, std::uint8_t body, double vy0, double y0, double dy, int rows,
                      bool from_top) {
  std::vector<double> sum(rows, 0.0);
  std::vector<int> count(rows, 0);
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (P.body[i] != body) continue;
    const int r = static_cast<int>(std::floor((P.y[i] - y0) / dy));
    if (r < 0 || r >= rows) continue;
    sum[r] += P.vy[i];
    ++count[r];
  }
  const double level = 0.5 * std::fabs(vy0);
  auto dev = [&](int r) { return std::fabs(sum[r] / count[r] - vy0); };
  int prev = -1;  // previous occupied row in scan order
  for (int k = 0; k < rows; ++k) {
    const int r = from_top ? rows - 1 - k : k;
    if (!count[r]) continue;
    const double d = dev(r);
    if (d > level) {
      const double yc = y0 + (r + 0.5) * dy;
      if (prev < 0) return yc;
      const double yp = y0 + (prev + 0.5) * dy, dp = dev(prev);
      return yp + (yc - yp) * (level - dp) / (d - dp);
    }
    prev = r;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double particle_temperature(const Particles& P, std::size_t p, const Thermo& th, const Material& m) {
  if (P.e.empty()) return m.T0;
  // plastic work not turned into heat (heat_fraction < 1) is stored, not hot
  const double stored = P.wp.empty() ? 0.0 : (1.0 - m.heat_fraction) * P.wp[p];
  return th.temperature(P.m[p] / P.V[p], P.e[p], stored);
}

Moments moments(const std::vector<double>& v) {
  Moments m;
  if (v.empty()) return m;
  const double n = static_cast<double>(v.size());
  double s = 0;
  for (double x : v) s += x;
  m.mean = s / n;
  double m2 = 0, m3 = 0, m4 = 0;
  for (double x : v) {
    const double d = x - m.mean, d2 = d * d;
    m2 += d2;
    m3 += d2 * d;
    m4 += d2 * d2;
  }
  m2 /= n;
  m3 /= n;
  m4 /= n;
  m.std = std::sqrt(m2);
  // a spread at round-off level has no shape: skew and kurtosis of noise are meaningless
  if (m.std > 1e-12 * std::fabs(m.mean) && m2 > 0) {
    m.skew = m3 / (m2 * m.std);
    m.kurt = m4 / (m2 * m2) - 3.0;
  }
  return m;
}

std::vector<RegionStats> region_stats(const Particles& P, const std::vector<Region>& regions,
                                      const std::vector<Thermo>& thermo, const std::vector<Material>& materials,
                                      const std::vector<int>& body_material, bool gradient_current) {
  const std::size_t nr = regions.size();
  std::vector<std::vector<double>> p(nr), T(nr), rho(nr), uy(nr);
  std::vector<RegionStats> out(nr);
  for (std::size_t i = 0; i < P.size(); ++i) {
    for (std::size_t r = 0; r < nr; ++r) {
      const Region& g = regions[r];
      if (P.body[i] != g.body || P.y[i] < g.y0 || P.y[i] > g.y1) continue;
      const int k = body_material[P.body[i]];
      p[r].push_back(P.p[i]);
      T[r].push_back(particle_temperature(P, i, thermo[k], materials[k]));
      rho[r].push_back(P.m[i] / P.V[i]);
      uy[r].push_back(P.vy[i]);
      const auto gm = gradient_measures(P.Lxx[i], P.Lxy[i], P.Lyx[i], P.Lyy[i]);
      out[r].R2 += gm.R2;
      out[r].D2 += gm.D2;
      out[r].S2 += gm.S2;
    }
  }
  for (std::size_t r = 0; r < nr; ++r) {
    RegionStats& s = out[r];
    s.count = p[r].size();
    if (s.count) {
      s.R2 /= s.count;
      s.D2 /= s.count;
      s.S2 /= s.count;
    }
    if (!gradient_current) s.R2 = s.D2 = s.S2 = std::numeric_limits<double>::quiet_NaN();
    s.P = moments(p[r]);
    s.T = moments(T[r]);
    s.rho = moments(rho[r]);
    s.Uy = moments(uy[r]);
  }
  return out;
}

}  // namespace smpm
