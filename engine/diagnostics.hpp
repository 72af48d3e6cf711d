// Diagnostics computed from the particle state during a run.
#pragma once
#include "kernels/dimension.hpp"
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/geometry.hpp"
#include "engine/particles.hpp"
#include "engine/thermo.hpp"
#include "kernels/tensor.hpp"

namespace SMPM_NS {

// Leading edge of the compression wave in one body, along the impact axis. The body's particles
// are binned in `rows` rows of height `h` (the cell size) from `lo` along that axis; a row is
// "reached" when its mean velocity along the axis differs from the body's initial u0 by more
// than half of |u0| (half the particle-velocity jump of an impact that brings it to rest).
// Scanning from the end away from the impact plane (`from_top`: the body lies above the plane),
// the front is where the mean crosses that level, interpolated linearly between row centres.
// Returns NaN when no row is reached, and when the first occupied row from the far end is
// reached already: the wave has arrived there (front.csv then ends rather than follow the
// released top or its ejecta). Needs u0 != 0.
double front_position(const Particles& P, std::uint8_t body, double u0, double lo, double h, int rows,
                      bool from_top);

// Void area (D = 2) or volume (D = 3) left open in one body [m^2 per unit thickness, m^3] inside
// each window [lo, hi] (current configuration): each of the body's points covers a disk (ball)
// of radius `radius` point_size(V_p) centred on it, rasterized on pixels (voxels) of side about
// `pixel` over the body's bounding box; uncovered pixels connected to the box's border (outside
// the body: above its free surface, beyond its ends) are not voids; the others are, and those
// whose centre lies in the window count. Along an axis with period[d] > 0 the image wraps with
// that period (periodic sides; the box then spans the period from start[d]). kCoverRadius covers
// a square (cubic) lattice, sheared or stretched by a third, without gaps: openings narrower
// than about half the point spacing do not count (voids.csv, tests/test_porous.cpp). Disks are
// capped at 16 pixels of radius; an image over kMaxPixels (one byte each: at most 400 MB) gives
// NaN areas. One rasterization serves every window: the result holds one area per window.
using Window = Box;
inline constexpr double kMaxPixels = 4e8;
// 0.75 in 2D, where a square's corner is 0.71 spacings from its point; in 3D a cube's corner
// is 0.87 from it, and 0.92 keeps the same margin
inline constexpr double kCoverRadius = kern::kDim == 2 ? 0.75 : 0.92;
std::vector<double> open_area(const Particles& P, std::uint8_t body, const std::vector<Window>& windows,
                              double pixel, double radius, const Vector& period = {}, const Vector& start = {});

// The side of a point's cell of volume V, V^(1/D) [m] (0 for V <= 0).
inline double point_size(double V) {
  if constexpr (kern::kDim == 2) return std::sqrt(std::max(V, 0.0));
  else return std::cbrt(std::max(V, 0.0));
}

// Temperature of particle p [K] (T0 where the particle carries no energy); the stored share
// (1 - heat_fraction) of its plastic work does not count as heat.
double particle_temperature(const Particles& P, std::size_t p, const Thermo& th, const Material& m);

// Mean, standard deviation (population), skewness and excess kurtosis of a sample (two-pass,
// in the given order). std = 0 gives skew = kurt = 0.
struct Moments {
  double mean = 0, std = 0, skew = 0, kurt = 0;
};
Moments moments(const std::vector<double>& v);

// The study's local velocity-gradient measures of one particle, from the D x D gradient
// L = grad v [1/s]: |curl v|^2, the sum of the squares of the components L_ba - L_ab (a < b) of
// curl v (D = 2: its one component L_yx - L_xy); div v = tr L; S^2 = D:D with D = sym(L) the
// strain-rate tensor (plane strain at D = 2: D_zz = 0). Stored on points first + i of P
// (Particles::curl2, div, rate2) for the gradient of a block of points, L.at(r, c)[i] (the
// last gather pass's block buffer, kern::g2p_blocks), i < last - first.
void store_gradient_measures(const kern::Gradient& L, std::size_t first, std::size_t last, Particles& P);

// A band across the full width, from lo to hi along the impact axis [m], in one body.
struct Region {
  std::string name;
  double lo = 0, hi = 0;
  std::uint8_t body = 0;
  double width = 0;  // [m] the band's width for its open porosity (0: not defined)
};

// Statistics of a region's particles (per particle: all points of a body carry the same mass,
// so per-particle and mass-weighted means coincide).
struct RegionStats {
  std::size_t count = 0;
  Moments P, T, rho, Uy;        // [Pa], [K], [kg/m^3], [m/s]
  double R2 = 0, D2 = 0, S2 = 0;  // means [1/s^2]
  // Mean |curl v| and |div v| [1/s]. Across a captured shock or a one-cell shear layer the mean
  // squares grow as 1/h (the jump over a width of a few cells), the means of the magnitudes do
  // not (the jump itself): docs/verification.md, porous strip.
  double R = 0, D = 0;
  // 1 - sum V_solid / (width (hi - lo)): the band's area the points' solid volumes leave open
  // (NaN without a width); V_solid = V_p, at most m_p / rho0 for a fractured point (its
  // expansion is crack, diagnostics.cpp); negative where points overlap
  double open = 0;
};
// gradient_current: the particles' gradient measures belong to their current state
// (Simulation::gradient_current);
// if not (the last row of an interrupted or failed run), R2, D2 and S2 are NaN, not stale values.
std::vector<RegionStats> region_stats(const Particles& P, const std::vector<Region>& regions,
                                      const std::vector<Thermo>& thermo, const std::vector<Material>& materials,
                                      const std::vector<int>& body_material, bool gradient_current = true);

}  // namespace SMPM_NS
