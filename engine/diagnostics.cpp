#include "kernels/dimension.hpp"
#include "engine/diagnostics.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>

namespace SMPM_NS {

double front_position(const Particles& P, std::uint8_t body, double u0, double lo, double h, int rows,
                      bool from_top) {
  const std::vector<double>& pos = P.x[kImpactAxis];
  const std::vector<double>& vel = P.v[kImpactAxis];
  std::vector<double> sum(rows, 0.0);
  std::vector<int> count(rows, 0);
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (P.body[i] != body) continue;
    const int r = static_cast<int>(std::floor((pos[i] - lo) / h));
    if (r < 0 || r >= rows) continue;
    sum[r] += vel[i];
    ++count[r];
  }
  const double level = 0.5 * std::fabs(u0);
  auto dev = [&](int r) { return std::fabs(sum[r] / count[r] - u0); };
  int prev = -1;  // previous occupied row in scan order
  for (int k = 0; k < rows; ++k) {
    const int r = from_top ? rows - 1 - k : k;
    if (!count[r]) continue;
    const double d = dev(r);
    if (d > level) {
      // the first occupied row from the far end is reached: the wave has arrived at the body's
      // far end (a free top released, ejecta flying): no front left to track
      if (prev < 0) return std::numeric_limits<double>::quiet_NaN();
      const double at = lo + (r + 0.5) * h;
      const double at_prev = lo + (prev + 0.5) * h, dp = dev(prev);
      return at_prev + (at - at_prev) * (level - dp) / (d - dp);
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
  for (double value : v) s += value;
  m.mean = s / n;
  double m2 = 0, m3 = 0, m4 = 0;
  for (double value : v) {
    const double d = value - m.mean, d2 = d * d;
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

// The volume of solid a point holds [m^2]: V_p, except for a fractured point (the constitutive
// update's zero pressure and zero deviator, kernels/constitutive.hpp), which holds at most the
// volume intact material of its mass and specific internal energy takes at zero pressure,
// m / rho_zp(e) (Mie-Grueneisen: thermal expansion, rho_zp below rho0 for a heated point;
// rho0 without an energy field): its expansion past that is opened crack, i.e. void. (A cap of
// m / rho0 would count the thermal expansion of the hot seams as void too: 0.5 of 3.8 % open
// porosity on the porous strip at h = 4 um.)
// Debris flying alone keeps its APIC affine velocity gradient, so its V grows without bound
// (rho down to 1e-4 kg/m^3 was seen in the study's baseline at h = 2 um), and counted as solid
// it made a band's open porosity -40 instead of +0.02. An unstressed point at rho0 holds V
// either way.
static double solid_volume(const Particles& P, std::size_t i, const Material& mat) {
  bool fractured = P.p[i] == 0.0;
  for (int k = 0; k < kern::sym_size(kern::kDim); ++k) fractured = fractured && P.s[k][i] == 0.0;
  if (!fractured || mat.rho0 <= 0.0) return P.V[i];
  const double rho_zp = !P.e.empty() ? mat.zero_pressure_density(P.e[i]) : mat.rho0;
  // e past C / (Gamma rho0) (about 1.4e7 J/kg for Al) leaves the tension branch no zero-pressure
  // density: such a point holds all its V
  return rho_zp > 0.0 ? std::min(P.V[i], P.m[i] / rho_zp) : P.V[i];
}

void store_gradient_measures(const kern::Gradient& L, std::size_t first, std::size_t last, Particles& P) {
  constexpr int D = kern::kDim;
  for (std::size_t i = first; i < last; ++i) {
    kern::Mat<D> g;
    for (int r = 0; r < D; ++r)
      for (int c = 0; c < D; ++c) g(r, c) = L.at(r, c)[i - first];
    const kern::Sym<D> s = kern::sym_part(g);
    double curl2 = 0.0;  // 0 + c^2 is c^2 exactly
    for (int k = D; k < kern::Sym<D>::K; ++k) {
      const int a = kern::sym_row(D, k), b = kern::sym_col(D, k);
      const double c = g(b, a) - g(a, b);
      curl2 += c * c;
    }
    double S2 = s[0] * s[0];
    for (int k = 1; k < D; ++k) S2 += s[k] * s[k];
    for (int k = D; k < kern::Sym<D>::K; ++k) S2 += 2.0 * s[k] * s[k];
    P.curl2[i] = curl2;
    P.div[i] = g.trace();
    P.rate2[i] = S2;
  }
}

std::vector<RegionStats> region_stats(const Particles& P, const std::vector<Region>& regions,
                                      const std::vector<Thermo>& thermo, const std::vector<Material>& materials,
                                      const std::vector<int>& body_material, bool gradient_current) {
  const std::size_t nr = regions.size();
  std::vector<std::vector<double>> p(nr), T(nr), rho(nr), u(nr);  // u: velocity along the impact axis
  std::vector<RegionStats> out(nr);
  const std::vector<double>& pos = P.x[kImpactAxis];
  const auto inside = [&](std::size_t i, const Region& g) {
    return P.body[i] == g.body && pos[i] >= g.lo && pos[i] <= g.hi;
  };
  // the temperatures first, in parallel (an exponential per point: most of this function's
  // time); the sums below run in point order, the same for any thread count
  std::vector<double> Tp(P.size());
  const auto np = static_cast<std::ptrdiff_t>(P.size());
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < np; ++i)
    for (std::size_t r = 0; r < nr; ++r)
      if (inside(i, regions[r])) {
        const int k = body_material[P.body[i]];
        Tp[i] = particle_temperature(P, i, thermo[k], materials[k]);
        break;
      }
  for (std::size_t i = 0; i < P.size(); ++i) {
    for (std::size_t r = 0; r < nr; ++r) {
      if (!inside(i, regions[r])) continue;
      const int k = body_material[P.body[i]];
      p[r].push_back(P.p[i]);
      T[r].push_back(Tp[i]);
      rho[r].push_back(P.m[i] / P.V[i]);
      u[r].push_back(P.v[kImpactAxis][i]);
      // |curl v| = sqrt(fl(c^2)) is |c| exactly at D = 2 (a correctly rounded square root of a
      // correctly rounded square, no underflow)
      out[r].R2 += P.curl2[i];
      out[r].D2 += P.div[i] * P.div[i];
      out[r].S2 += P.rate2[i];
      out[r].R += std::sqrt(P.curl2[i]);
      out[r].D += std::fabs(P.div[i]);
      out[r].open += solid_volume(P, i, materials[k]);
    }
  }
  for (std::size_t r = 0; r < nr; ++r) {
    RegionStats& s = out[r];
    s.count = p[r].size();
    if (s.count) {
      s.R2 /= s.count;
      s.D2 /= s.count;
      s.S2 /= s.count;
      s.R /= s.count;
      s.D /= s.count;
    }
    const double area = regions[r].width * (regions[r].hi - regions[r].lo);
    s.open = area > 0.0 ? 1.0 - s.open / area : std::numeric_limits<double>::quiet_NaN();
    if (!gradient_current) s.R2 = s.D2 = s.S2 = s.R = s.D = std::numeric_limits<double>::quiet_NaN();
    s.P = moments(p[r]);
    s.T = moments(T[r]);
    s.rho = moments(rho[r]);
    s.Uy = moments(u[r]);
  }
  return out;
}

namespace {

constexpr int kDim = kern::kDim;

// open_area's image: n[d] pixels of size step[d] along each axis d [m] from the corner lo, axis 0
// fastest, each 0 (uncovered), 1 (covered by a point's disk) or 2 (uncovered and connected to the
// border: outside the body). wrap[d]: axis d is periodic over its n[d] pixels.
struct Raster {
  Vector lo, step;
  Index n;
  bool wrap[kDim];
  std::vector<std::uint8_t> img;
  std::size_t at(const Index& i) const { return static_cast<std::size_t>(linear_index(i, n)); }
  Index last() const {
    Index l;
    for (int d = 0; d < kDim; ++d) l[d] = n[d] - 1;
    return l;
  }
};

// Marks the pixels whose centre lies in a body point's disk (ball), radius * point_size(V_p)
// capped at rmax. The points run in parallel: disks overlap, and a pixel two threads mark gets
// the same 1 from both (relaxed atomic byte stores), so the image is the same for any thread
// count. Along a row of pixels (axis 0) the test |e|^2 <= r^2 (e: pixel centre - point, summed
// in axis order) is monotone in |e_0|, every operation rounding monotonically, so a row's
// covered pixels are one run: its two ends are found by that test, starting a pixel outside the
// chord, and the pixels between are marked without it. The image is the one that testing every
// pixel of the disk's bounding box gives.
void cover_disks(Raster& R, const Particles& P, std::uint8_t body, double radius, double rmax) {
  // the raster's geometry in locals: a store into the image (bytes) could alias the members
  const Vector lo = R.lo, step = R.step;
  const Index n = R.n;
  bool wrap[kDim];
  for (int d = 0; d < kDim; ++d) wrap[d] = R.wrap[d];
  std::uint8_t* img = R.img.data();
  const double inv0 = 1.0 / step[0];  // the chord's ends need not be exact: a pixel of margin
  const auto np = static_cast<std::ptrdiff_t>(P.size());
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t p = 0; p < np; ++p) {
    if (P.body[p] != body) continue;
    const double rad = std::min(radius * point_size(P.V[p]), rmax), r2 = rad * rad;
    Vector c;
    Index first, last;  // the pixels of the disk's bounding box (those of a wrapping axis unwrapped)
    for (int d = 0; d < kDim; ++d) {
      c[d] = P.x[d][p];
      first[d] = static_cast<long>(std::ceil((c[d] - rad - lo[d]) / step[d] - 0.5));
      last[d] = static_cast<long>(std::floor((c[d] + rad - lo[d]) / step[d] - 0.5));
      if (!wrap[d]) {
        first[d] = std::max(0L, first[d]);
        last[d] = std::min(n[d] - 1, last[d]);
      }
    }
    Index row_last = last;  // the rows: axis 0 at its first pixel
    row_last[0] = first[0];
    for_each_index(first, row_last, [&](const Index& row) {
      double e[kDim];  // pixel centre - point [m]
      double rest = 0.0;
      for (int d = 1; d < kDim; ++d) {
        e[d] = lo[d] + (row[d] + 0.5) * step[d] - c[d];
        rest += e[d] * e[d];
      }
      const auto covered = [&](long i0) {
        e[0] = lo[0] + (i0 + 0.5) * step[0] - c[0];
        return kern::norm2(e) <= r2;
      };
      const double half = std::sqrt(std::max(0.0, r2 - rest));  // the chord's half length [m]
      long a = std::max(first[0], static_cast<long>(std::ceil((c[0] - half - lo[0]) * inv0 - 0.5)) - 1);
      long b = std::min(last[0], static_cast<long>(std::floor((c[0] + half - lo[0]) * inv0 - 0.5)) + 1);
      while (a <= b && !covered(a)) ++a;
      while (b >= a && !covered(b)) --b;
      if (a > b) return;
      Index w = row;  // the row's first pixel, into the period by steps: no integer division
      w[0] = a;
      for (int d = 0; d < kDim; ++d)
        if (wrap[d]) {
          while (w[d] < 0) w[d] += n[d];
          while (w[d] >= n[d]) w[d] -= n[d];
        }
      std::uint8_t* line = img + (linear_index(w, n) - w[0]);
      for (long i = a, x = w[0]; i <= b; ++i) {
        std::atomic_ref<std::uint8_t>(line[x]).store(1, std::memory_order_relaxed);
        if (++x == n[0]) x = 0;  // a run longer than the row only where axis 0 wraps
      }
    });
  }
}

// Floods the outside (2) from the border, both ends of every axis that does not wrap: every void
// pixel (0) connected to it through faces. Run by run along axis 0: a pixel taken from the stack
// marks the run of void pixels along axis 0 that holds it, and pushes one pixel of each run of
// void pixels beside that run (a step along another axis). The outside does not depend on the
// order in which it is found, so the image is that of a flood pixel by pixel.
void flood_outside(Raster& R) {
  const Index n = R.n;
  std::uint8_t* img = R.img.data();
  std::vector<long> stack;
  auto seed = [&](const Index& i) {
    const long k = linear_index(i, n);
    if (img[k] == 0) stack.push_back(k);
  };
  const Index last = R.last();
  for (int d = 0; d < kDim; ++d) {
    if (R.wrap[d]) continue;
    Index first{}, end = last;
    end[d] = 0;  // the face at index 0 of axis d, then the one at its last index
    for_each_index(first, end, seed);
    first[d] = last[d];
    for_each_index(first, last, seed);
  }
  const long n0 = n[0];
  const bool wrap0 = R.wrap[0];
  while (!stack.empty()) {
    const long k = stack.back();
    stack.pop_back();
    if (img[k] != 0) continue;  // marked since it was pushed
    Index i;
    long q = k;
    for (int d = 0; d < kDim; ++d) {
      i[d] = q % n[d];
      q /= n[d];
    }
    const long base = k - i[0];  // the row's pixel 0
    // the run: from its first pixel s (unwrapped, s <= i[0]) over len pixels
    long s = i[0], len = 1;
    img[k] = 2;
    for (long x = i[0] - 1; len < n0; --x, ++len) {
      if (x < 0) {
        if (!wrap0) break;
        x += n0;
      }
      if (img[base + x] != 0) break;
      img[base + x] = 2;
      --s;
    }
    for (long x = i[0] + 1; len < n0; ++x, ++len) {
      if (x >= n0) {
        if (!wrap0) break;
        x -= n0;
      }
      if (img[base + x] != 0) break;
      img[base + x] = 2;
    }
    // the runs beside it, one step along each other axis
    for (int d = 1; d < kDim; ++d)
      for (int dir = -1; dir <= 1; dir += 2) {
        Index j = i;
        j[d] += dir;
        if (j[d] < 0 || j[d] >= n[d]) {
          if (!R.wrap[d]) continue;
          j[d] = j[d] < 0 ? n[d] - 1 : 0;
        }
        j[0] = 0;
        const long nb = linear_index(j, n);  // that row's pixel 0
        bool in_run = false;
        long x = s;
        while (x < 0) x += n0;
        for (long t = 0; t < len; ++t) {
          const bool open = img[nb + x] == 0;
          if (open && !in_run) stack.push_back(nb + x);
          in_run = open;
          if (++x == n0) x = 0;
        }
      }
  }
}

// Adds the area of the void pixels (0) whose centre lies in each window to area[window] [m^2].
void add_void_area(const Raster& R, const std::vector<Window>& windows, std::vector<double>& area) {
  double pixel_area = R.step[0];
  for (int d = 1; d < kDim; ++d) pixel_area *= R.step[d];
  for_each_index(Index{}, R.last(), [&](const Index& i) {
    if (R.img[R.at(i)] != 0) return;
    Vector c;  // the pixel's centre [m]
    for (int d = 0; d < kDim; ++d) c[d] = R.lo[d] + (i[d] + 0.5) * R.step[d];
    for (std::size_t w = 0; w < windows.size(); ++w)
      if (in_box(windows[w], c)) area[w] += pixel_area;
  });
}

// The image over box b, the body's bounding box padded by `pad` on every side (a wrapping axis:
// the period from `start` instead); nullopt beyond kMaxPixels. Lateral axes hold a whole number of
// pixels of about `pixel` (a period tiles exactly), the impact axis pixels of side `pixel`.
std::optional<Raster> make_raster(Box b, double pixel, double pad, const Vector& period, const Vector& start) {
  Raster R;
  double nd[kDim], total = 1.0;  // pixels per axis, and in all
  for (int d = 0; d < kDim; ++d) {
    R.wrap[d] = period[d] > 0.0;
    if (R.wrap[d]) {
      b.lo[d] = start[d];
      b.hi[d] = start[d] + period[d];
    } else {
      b.lo[d] -= pad;
      b.hi[d] += pad;
    }
  }
  for (int d = 0; d < kDim; ++d) {
    nd[d] = d == kImpactAxis ? std::ceil((b.hi[d] - b.lo[d]) / pixel)
                             : std::max(1.0, std::round((b.hi[d] - b.lo[d]) / pixel));
    total *= nd[d];
  }
  if (!(total <= kMaxPixels)) return std::nullopt;
  long pixels = 1;
  for (int d = 0; d < kDim; ++d) {
    R.lo[d] = b.lo[d];
    R.n[d] = static_cast<long>(nd[d]);
    R.step[d] = d == kImpactAxis ? pixel : (b.hi[d] - b.lo[d]) / nd[d];
    pixels *= R.n[d];
  }
  R.img.assign(static_cast<std::size_t>(pixels), 0);
  return R;
}

}  // namespace

std::vector<double> open_area(const Particles& P, std::uint8_t body, const std::vector<Window>& windows,
                              double pixel, double radius, const Vector& period, const Vector& start) {
  std::vector<double> area(windows.size(), 0.0);
  Box b;  // the body's bounding box [m]
  double smax = 0.0;
  for (int d = 0; d < kDim; ++d) {
    b.lo[d] = 1e300;
    b.hi[d] = -1e300;
  }
  for (std::size_t p = 0; p < P.size(); ++p) {
    if (P.body[p] != body) continue;
    for (int d = 0; d < kDim; ++d) {
      b.lo[d] = std::min(b.lo[d], P.x[d][p]);
      b.hi[d] = std::max(b.hi[d], P.x[d][p]);
    }
    smax = std::max(smax, point_size(P.V[p]));
  }
  if (b.hi[0] < b.lo[0] || !(pixel > 0.0)) return area;
  // a point blown up to a huge volume (a failing run's debris) would make the image huge: disks
  // are capped at 16 pixels of radius, and an image over kMaxPixels is not drawn (NaN)
  const double rmax = 16.0 * pixel;
  smax = std::min(smax, rmax / std::max(radius, 1e-3));
  std::optional<Raster> R = make_raster(b, pixel, 2.0 * pixel + smax, period, start);
  if (!R) {
    std::fill(area.begin(), area.end(), std::numeric_limits<double>::quiet_NaN());
    return area;
  }
  cover_disks(*R, P, body, radius, rmax);
  flood_outside(*R);
  add_void_area(*R, windows, area);
  return area;
}

}  // namespace SMPM_NS
