#include "engine/porous.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace smpm {

namespace {

// The points of one body by lattice site: site[(b - b0) na + (a - a0)] is the index of the point
// at site (a, b), centre (ox + (a + 1/2) d, oy + (b + 1/2) d), or -1 for none.
struct SiteIndex {
  long a0 = 0, b0 = 0, na = 0, nb = 0;
  std::vector<std::int64_t> site;
};

SiteIndex index_sites(const Particles& P, double d, double ox, double oy, double x0, double x1, double y0, double y1) {
  SiteIndex S;
  S.a0 = static_cast<long>(std::floor((x0 - ox) / d));
  S.b0 = static_cast<long>(std::floor((y0 - oy) / d));
  S.na = static_cast<long>(std::ceil((x1 - ox) / d)) - S.a0 + 1;
  S.nb = static_cast<long>(std::ceil((y1 - oy) / d)) - S.b0 + 1;
  S.site.assign(static_cast<std::size_t>(S.na * S.nb), -1);
  for (std::size_t i = 0; i < P.size(); ++i) {
    const long a = static_cast<long>(std::floor((P.pos(0)[i] - ox) / d)) - S.a0;
    const long b = static_cast<long>(std::floor((P.pos(1)[i] - oy) / d)) - S.b0;
    if (a < 0 || a >= S.na || b < 0 || b >= S.nb) throw std::logic_error("cut_voids: point outside the body rectangle");
    S.site[static_cast<std::size_t>(b * S.na + a)] = static_cast<std::int64_t>(i);
  }
  return S;
}

// The points removed so far: removed[i] for point i, `count` of them.
struct Removal {
  std::vector<char> removed;
  std::size_t count = 0;
};

// Removes the points within the void v: the void's rows within the body, and in each row its
// columns within the body (or within one period of pa lattice steps, pa > 0: x wraps), so that
// a void far larger than the body costs no more than the body.
void remove_in_void(const SiteIndex& S, double d, double ox, double oy, long pa, const Void& v, Removal& R) {
  const double cx = v.x, cy = v.y, rad = v.r;
  const long a0 = S.a0, b0 = S.b0, na = S.na, nb = S.nb;
  const double cb0 = std::floor((cy - rad - oy) / d), cb1 = std::floor((cy + rad - oy) / d);
  const long bl = static_cast<long>(std::max(cb0, double(b0))), bh = static_cast<long>(std::min(cb1, double(b0 + nb - 1)));
  for (long b = bl; b <= bh; ++b) {
    const double py = oy + (b + 0.5) * d;
    const double half = std::sqrt(std::max(0.0, rad * rad - (py - cy) * (py - cy)));
    double ca0 = std::floor((cx - half - ox) / d), ca1 = std::floor((cx + half - ox) / d);
    const bool whole_row = pa > 0 && 2.0 * half >= double(pa) * d;  // the chord spans the period
    if (whole_row) {
      ca0 = double(a0);
      ca1 = double(a0 + pa - 1);
    } else if (pa == 0) {
      ca0 = std::max(ca0, double(a0));
      ca1 = std::min(ca1, double(a0 + na - 1));
    }
    for (long a = static_cast<long>(ca0); a <= static_cast<long>(ca1); ++a) {
      const double px = ox + (a + 0.5) * d;
      if (!whole_row && (px - cx) * (px - cx) + (py - cy) * (py - cy) >= rad * rad) continue;
      long aa = a;
      if (pa > 0) aa = a0 + (((a - a0) % pa) + pa) % pa;  // wrap into the periodic strip
      if (aa < a0 || aa >= a0 + na) continue;
      const std::int64_t i = S.site[static_cast<std::size_t>((b - b0) * na + (aa - a0))];
      if (i >= 0 && !R.removed[static_cast<std::size_t>(i)]) {
        R.removed[static_cast<std::size_t>(i)] = 1;
        ++R.count;
      }
    }
  }
}

// The points of P not removed, in their order.
Particles keep_unremoved(const Particles& P, const Removal& R) {
  Particles Q;
  Q.resize(P.size() - R.count);
  std::size_t k = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (R.removed[i]) continue;
    Q.pos(0)[k] = P.pos(0)[i]; Q.pos(1)[k] = P.pos(1)[i]; Q.vel(0)[k] = P.vel(0)[i]; Q.vel(1)[k] = P.vel(1)[i];
    Q.m[k] = P.m[i]; Q.V[k] = P.V[i]; Q.body[k] = P.body[i];
    ++k;
  }
  return Q;
}

}  // namespace

PorousResult cut_voids(Particles& P, double d, double ox, double oy, double x0, double x1, double y0, double y1,
                       const VoidSpec& spec, double period) {
  const bool listed = !spec.centers.empty();
  if (!listed && spec.radius <= 0.0) throw std::invalid_argument("void radius must be positive");
  if (!listed && (spec.radius_spread < 0.0 || spec.radius_spread >= spec.radius))
    throw std::invalid_argument("void radius spread must be in [0, radius)");
  if (!listed && (spec.porosity < 0.0) == (spec.count < 0))
    throw std::invalid_argument("give either a target porosity or a void count");
  const std::size_t n = P.size();
  const SiteIndex S = index_sites(P, d, ox, oy, x0, x1, y0, y1);
  Removal R;
  R.removed.assign(n, 0);
  std::mt19937_64 rng(spec.seed);
  std::uniform_real_distribution<double> ux(x0, x1), uy(y0, y1), ur(spec.radius - spec.radius_spread,
                                                                     spec.radius + spec.radius_spread);
  const long pa = period > 0.0 ? std::lround(period / d) : 0;  // period in lattice steps
  PorousResult r;
  const long max_voids = listed ? static_cast<long>(spec.centers.size())
                                : std::min(spec.count >= 0 ? spec.count : spec.max_voids, spec.max_voids);
  while (r.voids < max_voids) {
    if (!listed && spec.porosity >= 0.0 && static_cast<double>(R.count) >= spec.porosity * static_cast<double>(n)) break;
    if (!listed && spec.porosity >= 0.0 && R.count == n) break;
    Void v;
    if (listed) {
      v = spec.centers[static_cast<std::size_t>(r.voids)];
    } else {
      v.x = ux(rng); v.y = uy(rng); v.r = spec.radius_spread > 0.0 ? ur(rng) : spec.radius;
    }
    ++r.voids;
    r.cut.push_back(v);
    remove_in_void(S, d, ox, oy, pa, v, R);
  }
  r.porosity = n ? static_cast<double>(R.count) / static_cast<double>(n) : 0.0;
  P = keep_unremoved(P, R);
  return r;
}

Particles mirror_y(const Particles& P, double y_plane) {
  Particles Q = P;
  for (std::size_t i = 0; i < Q.size(); ++i) {
    Q.pos(1)[i] = 2.0 * y_plane - P.pos(1)[i];
    Q.vel(1)[i] = -P.vel(1)[i];
  }
  return Q;
}

}  // namespace smpm

namespace smpm {

void assign_void_sides(Particles& P, const std::vector<Void>& voids, double sx, double sy, double reach,
                       double period, int nfields) {
  if (nfields != 2 && nfields != 4)
    throw std::invalid_argument("assign_void_sides: nfields must be 2 or 4, got " + std::to_string(nfields));
  const bool across = nfields == 4;
  const std::size_t n = P.size();
  P.field.assign(n, 0);
  if (voids.empty() || n == 0) return;
  // voids binned into square buckets of side B >= r_max + reach: a point's candidates lie in
  // its own and the 8 neighbouring buckets
  double rmax = 0.0, xmin = 1e300, ymin = 1e300, xmax = -1e300, ymax = -1e300;  // [m]
  for (const Void& v : voids) {
    rmax = std::max(rmax, v.r);
    xmin = std::min(xmin, v.x); xmax = std::max(xmax, v.x);
    ymin = std::min(ymin, v.y); ymax = std::max(ymax, v.y);
  }
  const double B = rmax + reach;
  // periodic x: the buckets tile the period (origin xmin) and their neighbours wrap
  const bool wrap = period > 0.0;
  const long nbx = wrap ? std::max(1L, static_cast<long>(period / B)) : static_cast<long>((xmax - xmin) / B) + 1;
  const double Bx = wrap ? period / static_cast<double>(nbx) : B;
  const long nby = static_cast<long>((ymax - ymin) / B) + 1;
  auto column = [&](double x) {
    const double u = wrap ? x - xmin - period * std::floor((x - xmin) / period) : x - xmin;
    return std::min(static_cast<long>(std::floor(u / Bx)), wrap ? nbx - 1 : std::numeric_limits<long>::max());
  };
  std::vector<std::vector<std::uint32_t>> bucket(static_cast<std::size_t>(nbx * nby));
  for (std::size_t k = 0; k < voids.size(); ++k) {
    const long bx = column(voids[k].x), by = static_cast<long>((voids[k].y - ymin) / B);
    bucket[static_cast<std::size_t>(by * nbx + bx)].push_back(static_cast<std::uint32_t>(k));
  }
#pragma omp parallel for schedule(static)
  for (std::size_t p = 0; p < n; ++p) {
    const double x = P.pos(0)[p], y = P.pos(1)[p];
    const long by = static_cast<long>(std::floor((y - ymin) / B)), bx = column(x);
    double best = reach;
    double side = 0.0, lat = 0.0;  // (x - c) . s and (x - c) x s of the nearest void
    for (long j = std::max(by - 1, 0L); j <= std::min(by + 1, nby - 1); ++j) {
      for (long di = -1; di <= 1; ++di) {
        long i = bx + di;
        if (wrap) {
          if (nbx < 3 && di != 0 && (nbx == 1 || di == 1)) continue;  // each column once
          i = (i + nbx) % nbx;
        } else if (i < 0 || i >= nbx) {
          continue;
        }
        for (std::uint32_t k : bucket[static_cast<std::size_t>(j * nbx + i)]) {
          const Void& v = voids[k];
          double dx = x - v.x;
          if (wrap) dx -= period * std::round(dx / period);
          const double dy = y - v.y;
          const double d = std::sqrt(dx * dx + dy * dy) - v.r;
          if (d < best) {
            best = d;
            side = dx * sx + dy * sy;
            lat = dx * sy - dy * sx;
          }
        }
      }
    }
    P.field[p] = static_cast<std::uint8_t>((side > 0.0 ? 1 : 0) + (across && lat > 0.0 ? 2 : 0));
  }
}

}  // namespace smpm
