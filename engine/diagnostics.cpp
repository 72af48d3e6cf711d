#include "engine/diagnostics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace smpm {

double front_position(const Particles& P, std::uint8_t body, double vy0, double y0, double dy, int rows,
                      bool from_top) {
  std::vector<double> sum(rows, 0.0);
  std::vector<int> count(rows, 0);
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (P.body[i] != body) continue;
    const int r = static_cast<int>(std::floor((P.pos(1)[i] - y0) / dy));
    if (r < 0 || r >= rows) continue;
    sum[r] += P.vel(1)[i];
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
      // the first occupied row from the far end is reached: the wave has arrived at the body's
      // far end (a free top released, ejecta flying): no front left to track
      if (prev < 0) return std::numeric_limits<double>::quiet_NaN();
      const double yc = y0 + (r + 0.5) * dy;
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
  const bool fractured = P.p[i] == 0.0 && P.dev(0)[i] == 0.0 && P.dev(1)[i] == 0.0 && P.dev(2)[i] == 0.0;
  if (!fractured || mat.rho0 <= 0.0) return P.V[i];
  const double rho_zp = mat.eos == EosKind::MieGruneisen && !P.e.empty()
                            ? mat.mie_gruneisen().zero_pressure_density(P.e[i])
                            : mat.rho0;
  // e past C / (Gamma rho0) (about 1.4e7 J/kg for Al) leaves the tension branch no zero-pressure
  // density: such a point holds all its V
  return rho_zp > 0.0 ? std::min(P.V[i], P.m[i] / rho_zp) : P.V[i];
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
      if (P.body[i] != g.body || P.pos(1)[i] < g.y0 || P.pos(1)[i] > g.y1) continue;
      const int k = body_material[P.body[i]];
      p[r].push_back(P.p[i]);
      T[r].push_back(particle_temperature(P, i, thermo[k], materials[k]));
      rho[r].push_back(P.m[i] / P.V[i]);
      uy[r].push_back(P.vel(1)[i]);
      const auto gm = gradient_measures(P.grad(0, 0)[i], P.grad(0, 1)[i], P.grad(1, 0)[i], P.grad(1, 1)[i]);
      out[r].R2 += gm.R2;
      out[r].D2 += gm.D2;
      out[r].S2 += gm.S2;
      out[r].R += gm.R;
      out[r].D += gm.D;
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
    const double area = regions[r].width * (regions[r].y1 - regions[r].y0);
    s.open = area > 0.0 ? 1.0 - s.open / area : std::numeric_limits<double>::quiet_NaN();
    if (!gradient_current) s.R2 = s.D2 = s.S2 = s.R = s.D = std::numeric_limits<double>::quiet_NaN();
    s.P = moments(p[r]);
    s.T = moments(T[r]);
    s.rho = moments(rho[r]);
    s.Uy = moments(uy[r]);
  }
  return out;
}

namespace {

// open_area's image: nx x ny pixels of px x pixel [m] from (bx0, by0), each 0 (uncovered), 1
// (covered by a point's disk) or 2 (uncovered and connected to the border: outside the body).
// wrap: x is periodic over the nx pixels.
struct Raster {
  double bx0, by0, px, pixel;
  long nx, ny;
  bool wrap;
  std::vector<std::uint8_t> img;
};

// Marks the pixels whose centre lies in a body point's disk, radius * sqrt(V_p) capped at rmax.
void cover_disks(Raster& R, const Particles& P, std::uint8_t body, double radius, double rmax) {
  const double bx0 = R.bx0, by0 = R.by0, px = R.px, pixel = R.pixel;
  const long nx = R.nx, ny = R.ny;
  for (std::size_t p = 0; p < P.size(); ++p) {
    if (P.body[p] != body) continue;
    const double rad = std::min(radius * std::sqrt(std::max(P.V[p], 0.0)), rmax), r2 = rad * rad;
    const long j0 = std::max(0L, static_cast<long>(std::ceil((P.pos(1)[p] - rad - by0) / pixel - 0.5)));
    const long j1 = std::min(ny - 1, static_cast<long>(std::floor((P.pos(1)[p] + rad - by0) / pixel - 0.5)));
    const long i0 = static_cast<long>(std::ceil((P.pos(0)[p] - rad - bx0) / px - 0.5));
    const long i1 = static_cast<long>(std::floor((P.pos(0)[p] + rad - bx0) / px - 0.5));
    for (long j = j0; j <= j1; ++j)
      for (long i = i0; i <= i1; ++i) {
        const double ex = bx0 + (i + 0.5) * px - P.pos(0)[p], ey = by0 + (j + 0.5) * pixel - P.pos(1)[p];
        if (ex * ex + ey * ey > r2) continue;
        long ii = i;
        if (R.wrap) ii = ((ii % nx) + nx) % nx;
        else if (ii < 0 || ii >= nx) continue;
        R.img[static_cast<std::size_t>(j * nx + ii)] = 1;
      }
  }
}

// Floods the outside (2) from the border rows, and columns without wrap.
void flood_outside(Raster& R) {
  const long nx = R.nx, ny = R.ny;
  std::vector<long> stack;
  auto seed = [&](long i, long j) {
    std::uint8_t& v = R.img[static_cast<std::size_t>(j * nx + i)];
    if (v == 0) {
      v = 2;
      stack.push_back(j * nx + i);
    }
  };
  for (long i = 0; i < nx; ++i) {
    seed(i, 0);
    seed(i, ny - 1);
  }
  if (!R.wrap)
    for (long j = 0; j < ny; ++j) {
      seed(0, j);
      seed(nx - 1, j);
    }
  while (!stack.empty()) {
    const long k = stack.back();
    stack.pop_back();
    const long i = k % nx, j = k / nx;
    if (j > 0) seed(i, j - 1);
    if (j < ny - 1) seed(i, j + 1);
    if (R.wrap) {
      seed((i + 1) % nx, j);
      seed((i + nx - 1) % nx, j);
    } else {
      if (i > 0) seed(i - 1, j);
      if (i < nx - 1) seed(i + 1, j);
    }
  }
}

// Adds the area of the void pixels (0) whose centre lies in each window to area[window] [m^2].
void add_void_area(const Raster& R, const std::vector<Window>& windows, std::vector<double>& area) {
  for (long j = 0; j < R.ny; ++j) {
    const double yc = R.by0 + (j + 0.5) * R.pixel;
    for (long i = 0; i < R.nx; ++i) {
      if (R.img[static_cast<std::size_t>(j * R.nx + i)] != 0) continue;
      const double xc = R.bx0 + (i + 0.5) * R.px;
      for (std::size_t w = 0; w < windows.size(); ++w) {
        const Window& W = windows[w];
        if (yc >= W.y0 && yc <= W.y1 && xc >= W.x0 && xc <= W.x1) area[w] += R.px * R.pixel;
      }
    }
  }
}

}  // namespace

std::vector<double> open_area(const Particles& P, std::uint8_t body, const std::vector<Window>& windows,
                              double pixel, double radius, double period, double xp0) {
  std::vector<double> area(windows.size(), 0.0);
  double bx0 = 1e300, bx1 = -1e300, by0 = 1e300, by1 = -1e300, smax = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    if (P.body[p] != body) continue;
    bx0 = std::min(bx0, P.pos(0)[p]); bx1 = std::max(bx1, P.pos(0)[p]);
    by0 = std::min(by0, P.pos(1)[p]); by1 = std::max(by1, P.pos(1)[p]);
    smax = std::max(smax, std::sqrt(P.V[p]));
  }
  if (bx1 < bx0 || !(pixel > 0.0)) return area;
  // a point blown up to a huge volume (a failing run's debris) would make the image huge: disks
  // are capped at 16 pixels of radius, and an image over 4e8 pixels is not drawn (NaN)
  const double rmax = 16.0 * pixel;
  smax = std::min(smax, rmax / std::max(radius, 1e-3));
  const bool wrap = period > 0.0;
  const double pad = 2.0 * pixel + smax;
  if (wrap) {
    bx0 = xp0;
    bx1 = xp0 + period;
  } else {
    bx0 -= pad;
    bx1 += pad;
  }
  by0 -= pad;
  by1 += pad;
  const double nxd = std::max(1.0, std::round((bx1 - bx0) / pixel)), nyd = std::ceil((by1 - by0) / pixel);
  if (!(nxd * nyd <= 4e8)) {
    std::fill(area.begin(), area.end(), std::numeric_limits<double>::quiet_NaN());
    return area;
  }
  const long nx = static_cast<long>(nxd), ny = static_cast<long>(nyd);
  const double px = (bx1 - bx0) / nxd;  // pixel width (wrap: the period tiles exactly)
  Raster R{bx0, by0, px, pixel, nx, ny, wrap, std::vector<std::uint8_t>(static_cast<std::size_t>(nx * ny), 0)};
  cover_disks(R, P, body, radius, rmax);
  flood_outside(R);
  add_void_area(R, windows, area);
  return area;
}

}  // namespace smpm
