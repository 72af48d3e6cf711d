#include "engine/porous.hpp"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace smpm {

PorousResult cut_voids(Particles& P, double d, double ox, double oy, double x0, double x1, double y0, double y1,
                       const VoidSpec& spec, double period) {
  if (spec.radius <= 0.0) throw std::invalid_argument("void radius must be positive");
  if (spec.radius_spread < 0.0 || spec.radius_spread >= spec.radius)
    throw std::invalid_argument("void radius spread must be in [0, radius)");
  if ((spec.porosity < 0.0) == (spec.count < 0))
    throw std::invalid_argument("give either a target porosity or a void count");
  const std::size_t n = P.size();
  // lattice index of every point: points sit at sub-cell centres (a + 1/2) d
  const long a0 = static_cast<long>(std::floor((x0 - ox) / d)), b0 = static_cast<long>(std::floor((y0 - oy) / d));
  const long na = static_cast<long>(std::ceil((x1 - ox) / d)) - a0 + 1;
  const long nb = static_cast<long>(std::ceil((y1 - oy) / d)) - b0 + 1;
  std::vector<std::int64_t> site(static_cast<std::size_t>(na * nb), -1);
  for (std::size_t i = 0; i < n; ++i) {
    const long a = static_cast<long>(std::floor((P.x[i] - ox) / d)) - a0;
    const long b = static_cast<long>(std::floor((P.y[i] - oy) / d)) - b0;
    if (a < 0 || a >= na || b < 0 || b >= nb) throw std::logic_error("cut_voids: point outside the body rectangle");
    site[static_cast<std::size_t>(b * na + a)] = static_cast<std::int64_t>(i);
  }
  std::vector<char> removed(n, 0);
  std::size_t nremoved = 0;
  std::mt19937_64 rng(spec.seed);
  std::uniform_real_distribution<double> ux(x0, x1), uy(y0, y1), ur(spec.radius - spec.radius_spread,
                                                                     spec.radius + spec.radius_spread);
  const long pa = period > 0.0 ? std::lround(period / d) : 0;  // period in lattice steps
  PorousResult r;
  const long max_voids = spec.count >= 0 ? spec.count : std::numeric_limits<long>::max();
  while (r.voids < max_voids) {
    if (spec.porosity >= 0.0 && static_cast<double>(nremoved) >= spec.porosity * static_cast<double>(n)) break;
    if (spec.porosity >= 0.0 && nremoved == n) break;
    const double cx = ux(rng), cy = uy(rng), rad = spec.radius_spread > 0.0 ? ur(rng) : spec.radius;
    ++r.voids;
    const long ca0 = static_cast<long>(std::floor((cx - rad - ox) / d));
    const long ca1 = static_cast<long>(std::floor((cx + rad - ox) / d));
    const long cb0 = static_cast<long>(std::floor((cy - rad - oy) / d));
    const long cb1 = static_cast<long>(std::floor((cy + rad - oy) / d));
    for (long b = std::max(cb0, b0); b <= std::min(cb1, b0 + nb - 1); ++b) {
      const double py = oy + (b + 0.5) * d;
      for (long a = ca0; a <= ca1; ++a) {
        const double px = ox + (a + 0.5) * d;
        if ((px - cx) * (px - cx) + (py - cy) * (py - cy) >= rad * rad) continue;
        long aa = a;
        if (pa > 0) aa = a0 + (((a - a0) % pa) + pa) % pa;  // wrap into the periodic strip
        if (aa < a0 || aa >= a0 + na) continue;
        const std::int64_t i = site[static_cast<std::size_t>((b - b0) * na + (aa - a0))];
        if (i >= 0 && !removed[static_cast<std::size_t>(i)]) {
          removed[static_cast<std::size_t>(i)] = 1;
          ++nremoved;
        }
      }
    }
  }
  r.porosity = n ? static_cast<double>(nremoved) / static_cast<double>(n) : 0.0;
  // compact, keeping order
  Particles Q;
  Q.resize(n - nremoved);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (removed[i]) continue;
    Q.x[k] = P.x[i]; Q.y[k] = P.y[i]; Q.vx[k] = P.vx[i]; Q.vy[k] = P.vy[i];
    Q.m[k] = P.m[i]; Q.V[k] = P.V[i]; Q.body[k] = P.body[i];
    ++k;
  }
  P = std::move(Q);
  return r;
}

Particles mirror_y(const Particles& P, double y_plane) {
  Particles Q = P;
  for (std::size_t i = 0; i < Q.size(); ++i) {
    Q.y[i] = 2.0 * y_plane - P.y[i];
    Q.vy[i] = -P.vy[i];
  }
  return Q;
}

}  // namespace smpm
