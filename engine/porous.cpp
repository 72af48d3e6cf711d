#include "kernels/dimension.hpp"
#include "engine/porous.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace SMPM_NS {

namespace {

constexpr int kDim = kern::kDim;

// The points of one body by lattice site: site[at(i)] is the index of the point at lattice site
// i (one index per axis), centre origin + (i + 1/2) step, or -1 for none; the sites from `first`,
// n[d] along axis d.
struct SiteIndex {
  Index first{}, n{};
  std::vector<std::int64_t> site;
  std::size_t at(const Index& i) const {
    Index r;
    for (int d = 0; d < kDim; ++d) r[d] = i[d] - first[d];
    return static_cast<std::size_t>(linear_index(r, n));
  }
};

SiteIndex index_sites(const Particles& P, double step, const Vector& origin, const Box& box) {
  SiteIndex S;
  long sites = 1;
  for (int d = 0; d < kDim; ++d) {
    S.first[d] = static_cast<long>(std::floor((box.lo[d] - origin[d]) / step));
    S.n[d] = static_cast<long>(std::ceil((box.hi[d] - origin[d]) / step)) - S.first[d] + 1;
    sites *= S.n[d];
  }
  S.site.assign(static_cast<std::size_t>(sites), -1);
  for (std::size_t i = 0; i < P.size(); ++i) {
    Index a;
    bool out = false;
    for (int d = 0; d < kDim; ++d) {
      a[d] = static_cast<long>(std::floor((P.x[d][i] - origin[d]) / step));
      out = out || a[d] < S.first[d] || a[d] >= S.first[d] + S.n[d];
    }
    if (out) throw std::logic_error("cut_voids: point outside the body rectangle");
    S.site[S.at(a)] = static_cast<std::int64_t>(i);
  }
  return S;
}

// The points removed so far: removed[i] for point i, `count` of them.
struct Removal {
  std::vector<char> removed;
  std::size_t count = 0;
};

// Removes the points within the void v: the lattice sites of its bounding box within the body,
// or, along an axis with a period of p[d] > 0 lattice steps, within one period (the distance to
// the void's nearest periodic image), so that a void far larger than the body costs no more than
// the body.
void remove_in_void(const SiteIndex& S, double step, const Vector& origin, const Index& p, const Void& v,
                    Removal& R) {
  const double rad = v.r;
  Index first{}, last{};
  for (int d = 0; d < kDim; ++d) {
    const double c0 = std::floor((v.c[d] - rad - origin[d]) / step), c1 = std::floor((v.c[d] + rad - origin[d]) / step);
    if (p[d] > 0 && c1 - c0 + 1.0 >= double(p[d])) {  // the void spans the period
      first[d] = S.first[d];
      last[d] = S.first[d] + p[d] - 1;
    } else if (p[d] > 0) {
      first[d] = static_cast<long>(c0);
      last[d] = static_cast<long>(c1);
    } else {
      first[d] = static_cast<long>(std::max(c0, double(S.first[d])));
      last[d] = static_cast<long>(std::min(c1, double(S.first[d] + S.n[d] - 1)));
    }
  }
  for_each_index(first, last, [&](const Index& a) {
    double e[kDim];  // site - centre [m], to the nearest image along a periodic axis
    Index site = a;
    for (int d = 0; d < kDim; ++d) {
      e[d] = origin[d] + (a[d] + 0.5) * step - v.c[d];
      if (p[d] > 0) {
        const double L = double(p[d]) * step;
        e[d] -= L * std::round(e[d] / L);
        site[d] = S.first[d] + (((a[d] - S.first[d]) % p[d]) + p[d]) % p[d];  // wrap into the period
      }
      if (site[d] < S.first[d] || site[d] >= S.first[d] + S.n[d]) return;
    }
    if (kern::norm2(e) >= rad * rad) return;
    const std::int64_t i = S.site[S.at(site)];
    if (i >= 0 && !R.removed[static_cast<std::size_t>(i)]) {
      R.removed[static_cast<std::size_t>(i)] = 1;
      ++R.count;
    }
  });
}

// The points of P not removed, in their order.
Particles keep_unremoved(const Particles& P, const Removal& R) {
  Particles Q;
  Q.resize(P.size() - R.count);
  std::size_t k = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (R.removed[i]) continue;
    for (int d = 0; d < kDim; ++d) {
      Q.x[d][k] = P.x[d][i];
      Q.v[d][k] = P.v[d][i];
    }
    Q.m[k] = P.m[i]; Q.V[k] = P.V[i]; Q.body[k] = P.body[i];
    ++k;
  }
  return Q;
}

}  // namespace

PorousResult cut_voids(Particles& P, double step, const Vector& origin, const Box& box, const VoidSpec& spec,
                       const Vector& period) {
  const bool listed = !spec.centers.empty();
  if (!listed && spec.radius <= 0.0) throw std::invalid_argument("void radius must be positive");
  if (!listed && (spec.radius_spread < 0.0 || spec.radius_spread >= spec.radius))
    throw std::invalid_argument("void radius spread must be in [0, radius)");
  if (!listed && (spec.porosity < 0.0) == (spec.count < 0))
    throw std::invalid_argument("give either a target porosity or a void count");
  const std::size_t n = P.size();
  const SiteIndex S = index_sites(P, step, origin, box);
  Removal R;
  R.removed.assign(n, 0);
  std::mt19937_64 rng(spec.seed);
  std::vector<std::uniform_real_distribution<double>> uc;  // centres, per axis
  for (int d = 0; d < kDim; ++d) uc.emplace_back(box.lo[d], box.hi[d]);
  std::uniform_real_distribution<double> ur(spec.radius - spec.radius_spread, spec.radius + spec.radius_spread);
  Index pa;  // the periods in lattice steps
  for (int d = 0; d < kDim; ++d) pa[d] = period[d] > 0.0 ? std::lround(period[d] / step) : 0;
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
      for (int d = 0; d < kDim; ++d) v.c[d] = uc[d](rng);
      v.r = spec.radius_spread > 0.0 ? ur(rng) : spec.radius;
    }
    ++r.voids;
    r.cut.push_back(v);
    remove_in_void(S, step, origin, pa, v, R);
  }
  r.porosity = n ? static_cast<double>(R.count) / static_cast<double>(n) : 0.0;
  P = keep_unremoved(P, R);
  return r;
}

Particles mirror(const Particles& P, int axis, double plane) {
  Particles Q = P;
  for (std::size_t i = 0; i < Q.size(); ++i) {
    Q.x[axis][i] = 2.0 * plane - P.x[axis][i];
    Q.v[axis][i] = -P.v[axis][i];
  }
  return Q;
}

}  // namespace SMPM_NS

namespace SMPM_NS {

namespace {

// Voids binned into buckets: n[d] along axis d, of size size[d] from lo[d] (the voids' lowest
// centre); wrap[d]: axis d is periodic with period[d] and its buckets tile the period.
struct VoidBuckets {
  Vector lo, size;
  Index n;
  bool wrap[kDim];
  Vector period;
  std::vector<std::vector<std::uint32_t>> voids;  // void indices per bucket, axis 0 fastest
  // the bucket index along axis d of coordinate q
  long along(int d, double q) const {
    const double u = wrap[d] ? q - lo[d] - period[d] * std::floor((q - lo[d]) / period[d]) : q - lo[d];
    const long b = static_cast<long>(std::floor(u / size[d]));
    return wrap[d] ? std::min(b, n[d] - 1) : b;
  }
};

// Square buckets of side B >= r_max + reach (a period's whole number of them along a periodic
// axis): a point's candidates lie in its own bucket and its neighbours.
VoidBuckets bucket_voids(const std::vector<Void>& voids, double reach, const Vector& period) {
  double rmax = 0.0;
  Vector hi;  // the highest centre [m]
  VoidBuckets K;
  for (int d = 0; d < kDim; ++d) {
    K.lo[d] = 1e300;
    hi[d] = -1e300;
  }
  for (const Void& v : voids) {
    rmax = std::max(rmax, v.r);
    for (int d = 0; d < kDim; ++d) {
      K.lo[d] = std::min(K.lo[d], v.c[d]);
      hi[d] = std::max(hi[d], v.c[d]);
    }
  }
  const double B = rmax + reach;
  K.period = period;
  long buckets = 1;
  for (int d = 0; d < kDim; ++d) {
    K.wrap[d] = period[d] > 0.0;
    K.n[d] = K.wrap[d] ? std::max(1L, static_cast<long>(period[d] / B)) : static_cast<long>((hi[d] - K.lo[d]) / B) + 1;
    K.size[d] = K.wrap[d] ? period[d] / static_cast<double>(K.n[d]) : B;
    buckets *= K.n[d];
  }
  K.voids.resize(static_cast<std::size_t>(buckets));
  for (std::size_t k = 0; k < voids.size(); ++k) {
    Index b;
    for (int d = 0; d < kDim; ++d) b[d] = K.along(d, voids[k].c[d]);
    K.voids[static_cast<std::size_t>(linear_index(b, K.n))].push_back(static_cast<std::uint32_t>(k));
  }
  return K;
}

// a . b over the axes, summed in axis order
double dot(const double* a, const Vector& b) {
  double s = a[0] * b[0];
  for (int d = 1; d < kDim; ++d) s += a[d] * b[d];
  return s;
}

}  // namespace

void assign_void_sides(Particles& P, const std::vector<Void>& voids, const Vector& s, double reach,
                       const Vector& period, int nfields) {
  if (nfields != 2 && nfields != 4)
    throw std::invalid_argument("assign_void_sides: nfields must be 2 or 4, got " + std::to_string(nfields));
  const bool across = nfields == 4;
  const std::size_t n = P.size();
  P.field.assign(n, 0);
  if (voids.empty() || n == 0) return;
  const VoidBuckets K = bucket_voids(voids, reach, period);
  Vector t{};  // the direction across s: s turned by -90 degrees in the plane of axes 0 and 1
  t[0] = s[1];
  t[1] = -s[0];
  Index lo, hi;  // neighbour offsets
  for (int d = 0; d < kDim; ++d) {
    lo[d] = -1;
    hi[d] = 1;
  }
#pragma omp parallel for schedule(static)
  for (std::size_t p = 0; p < n; ++p) {
    double x[kDim];
    Index home;
    for (int d = 0; d < kDim; ++d) {
      x[d] = P.x[d][p];
      home[d] = K.along(d, x[d]);
    }
    double best = reach;
    double side = 0.0, lat = 0.0;  // (x - c) . s and (x - c) . t of the nearest void
    for_each_index(lo, hi, [&](const Index& off) {
      Index b;
      for (int d = 0; d < kDim; ++d) {
        b[d] = home[d] + off[d];
        if (K.wrap[d]) {
          if (K.n[d] < 3 && off[d] != 0 && (K.n[d] == 1 || off[d] == 1)) return;  // each bucket once
          b[d] = (b[d] + K.n[d]) % K.n[d];
        } else if (b[d] < 0 || b[d] >= K.n[d]) {
          return;
        }
      }
      for (std::uint32_t k : K.voids[static_cast<std::size_t>(linear_index(b, K.n))]) {
        const Void& v = voids[k];
        double e[kDim];  // x - c [m]
        for (int d = 0; d < kDim; ++d) {
          e[d] = x[d] - v.c[d];
          if (K.wrap[d]) e[d] -= period[d] * std::round(e[d] / period[d]);
        }
        const double dist = std::sqrt(kern::norm2(e)) - v.r;
        if (dist < best) {
          best = dist;
          side = dot(e, s);
          lat = dot(e, t);
        }
      }
    });
    P.field[p] = static_cast<std::uint8_t>((side > 0.0 ? 1 : 0) + (across && lat > 0.0 ? 2 : 0));
  }
}

}  // namespace SMPM_NS
