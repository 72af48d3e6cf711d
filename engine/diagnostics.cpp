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

}  // namespace smpm
