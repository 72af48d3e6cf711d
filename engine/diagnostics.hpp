// Diagnostics computed from the particle state during a run.
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/particles.hpp"
#include "engine/thermo.hpp"

namespace smpm {

// Leading edge of the compression wave in one body, along y. The body's particles are binned
// in rows of height `dy` (the cell size); a row is "reached" when its mean y-velocity differs
// from the body's initial vy0 by more than half of |vy0| (half the particle-velocity jump of an
// impact that brings it to rest). Scanning from the end away from the impact plane (`from_top`:
// the body lies above the plane), the front is where the mean crosses that level, interpolated
// linearly between row centres. Returns NaN when no row is reached, and when the first occupied
// row from the far end is reached already: the wave has arrived there (front.csv then ends
// rather than follow the released top or its ejecta). Needs vy0 != 0.
double front_position(const Particles& P, std::uint8_t body, double vy0, double y0, double dy, int rows,
                      bool from_top);

// Void area left open in one body [m^2] inside the window [x0, x1] x [y0, y1] (current
// configuration) for each window: each of the body's points covers a disk of radius `radius` sqrt(V_p) centred
// on it, rasterized on pixels of side `pixel` over the body's bounding box; uncovered pixels
// connected to the box's border (outside the body: above its free surface, beyond its ends)
// are not voids; the others are, and those whose centre lies in the window count. period > 0:
// x wraps with that period (periodic sides; the box then spans the period from xp0). A radius
// of 0.75 covers a square lattice, sheared or stretched by a third, without gaps: openings
// narrower than about half the point spacing do not count (voids.csv, tests/test_porous.cpp).
// Disks are capped at 16 pixels of radius; an image over 4e8 pixels gives NaN areas.
// One rasterization serves every window: the result holds one area per window.
struct Window {
  double x0, x1, y0, y1;  // [m]
};
std::vector<double> open_area(const Particles& P, std::uint8_t body, const std::vector<Window>& windows,
                              double pixel, double radius, double period = 0.0, double xp0 = 0.0);

// Temperature of particle p [K] (T0 where the particle carries no energy); the stored share
// (1 - heat_fraction) of its plastic work does not count as heat.
double particle_temperature(const Particles& P, std::size_t p, const Thermo& th, const Material& m);

// Mean, standard deviation (population), skewness and excess kurtosis of a sample (two-pass,
// in the given order). std = 0 gives skew = kurt = 0.
struct Moments {
  double mean = 0, std = 0, skew = 0, kurt = 0;
};
Moments moments(const std::vector<double>& v);

// The study's local velocity-gradient measures of one particle, from L = grad v [1/s]:
// R = |curl v| = |L_yx - L_xy|, D = |div v| = |L_xx + L_yy|, S^2 = D:D (strain-rate tensor,
// plane strain: D_zz = 0).
struct GradientMeasures {
  double R2, D2, S2;  // [1/s^2]
  double R, D;        // |curl v|, |div v| [1/s]
};
inline GradientMeasures gradient_measures(double lxx, double lxy, double lyx, double lyy) {
  const double curl = lyx - lxy, div = lxx + lyy, dxy = 0.5 * (lxy + lyx);
  return {curl * curl, div * div, lxx * lxx + lyy * lyy + 2.0 * dxy * dxy, std::fabs(curl), std::fabs(div)};
}

// A band across the full width, y in [y0, y1] [m], in one body.
struct Region {
  std::string name;
  double y0 = 0, y1 = 0;
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
  // 1 - sum V_solid / (width (y1 - y0)): the band's area the points' solid volumes leave open
  // (NaN without a width); V_solid = V_p, at most m_p / rho0 for a fractured point (its
  // expansion is crack, diagnostics.cpp); negative where points overlap
  double open = 0;
};
// gradient_current: the particles' L belongs to their current state (Simulation::gradient_current);
// if not (the last row of an interrupted or failed run), R2, D2 and S2 are NaN, not stale values.
std::vector<RegionStats> region_stats(const Particles& P, const std::vector<Region>& regions,
                                      const std::vector<Thermo>& thermo, const std::vector<Material>& materials,
                                      const std::vector<int>& body_material, bool gradient_current = true);

}  // namespace smpm
