// Diagnostics against hand-computed values: regional statistics, velocity-gradient measures,
// front detection.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/diagnostics.hpp"
#include "engine/material.hpp"
#include "engine/thermo.hpp"
#include "tests/gradient_arrays.hpp"

using namespace smpm;

TEST_CASE("moments against hand-computed values", "[diagnostics]") {
  // 1, 2, 3, 4, 10: mean 4, deviations -3 -2 -1 0 6: m2 = 50/5 = 10, m3 = (-27-8-1+216)/5 = 36,
  // m4 = (81+16+1+1296)/5 = 278.8
  const auto m = moments({1, 2, 3, 4, 10});
  CHECK(m.mean == Approx(4.0));
  CHECK(m.std == Approx(std::sqrt(10.0)));
  CHECK(m.skew == Approx(36.0 / std::pow(10.0, 1.5)));
  CHECK(m.kurt == Approx(278.8 / 100.0 - 3.0));
  // a symmetric two-point distribution: skew 0, excess kurtosis -2
  const auto b = moments({-1, 1, -1, 1});
  CHECK(b.skew == Approx(0.0).margin(1e-15));
  CHECK(b.kurt == Approx(-2.0));
  // constant: no spread, no shape
  const auto c = moments({5, 5, 5});
  CHECK(c.std == 0.0);
  CHECK(c.skew == 0.0);
  CHECK(c.kurt == 0.0);
}

TEST_CASE("velocity-gradient measures: rigid rotation and uniform expansion", "[diagnostics]") {
  const auto measures = test::point_with_measures;
  const double w = 3.0;  // rigid rotation v = w (-y, x): L = [[0, -w], [w, 0]]
  const Particles r = measures({0.0, -w, w, 0.0});
  CHECK(std::sqrt(r.curl2[0]) == Approx(2 * w));  // |curl v| = 2 omega
  CHECK(r.div[0] == 0.0);
  CHECK(r.rate2[0] == 0.0);                        // no strain rate in a rigid rotation
  const double a = 0.7;  // uniform expansion v = a (x, y): L = a I
  const Particles e = measures({a, 0.0, 0.0, a});
  CHECK(e.div[0] == Approx(2 * a));                // div v = 2 a in 2D
  CHECK(e.curl2[0] == 0.0);
  CHECK(e.rate2[0] == Approx(2 * a * a));          // D:D = a^2 + a^2
}

TEST_CASE("regional statistics on a synthetic particle set", "[diagnostics]") {
  Particles P;
  P.resize(6);
  P.x[1] = {0.5e-6, 150e-6, 250e-6, 350e-6, 700e-6, 150e-6};
  P.p = {9, 1e9, 2e9, 3e9, 4e9, 5e9};
  P.v[1] = {0, -1, -2, -3, -4, -5};
  P.body = {0, 0, 0, 0, 0, 1};  // the last one belongs to another body
  for (std::size_t i = 0; i < 6; ++i) {
    P.m[i] = 2.7e-9;
    P.V[i] = 1e-12;
  }
  P.div[1] = 1e6;  // div 1e6/s on one particle of region III
  Material m;
  m.rho0 = 2700;
  m.E = 69e9;
  m.nu = 0.33;
  const std::vector<Thermo> th{Thermo(m)};
  const std::vector<Region> regions{{"I", 100e-6, 900e-6, 0}, {"III", 100e-6, 300e-6, 0}};
  const auto s = region_stats(P, regions, th, {m}, {0, 0});
  REQUIRE(s.size() == 2);
  CHECK(s[0].count == 4);  // 150, 250, 350, 700 um of body 0
  CHECK(s[0].P.mean == Approx(2.5e9));
  CHECK(s[0].Uy.mean == Approx(-2.5));
  CHECK(s[0].rho.mean == Approx(2700.0));
  CHECK(s[1].count == 2);  // 150, 250 um
  CHECK(s[1].P.mean == Approx(1.5e9));
  CHECK(s[1].P.std == Approx(0.5e9));
  CHECK(s[1].D2 == Approx(1e12 / 2));  // mean over the region's 2 particles
  CHECK(s[0].T.mean == Approx(300.0));  // no energy field: T0
  // L not current (the last row of an interrupted or failed run): no gradient measures, the rest as before
  const auto stale = region_stats(P, regions, th, {m}, {0, 0}, false);
  CHECK(std::isnan(stale[1].D2));
  CHECK(std::isnan(stale[1].R2));
  CHECK(std::isnan(stale[1].S2));
  CHECK(stale[1].P.mean == s[1].P.mean);
}

TEST_CASE("open porosity: a fractured point holds no more solid than m / rho0", "[diagnostics]") {
  // a 2 x 5 um band (area 1e-11 m^2) with three points of m / rho0 = 1e-12 m^2 each
  Particles P;
  P.resize(3);
  P.x[1] = {1e-6, 2e-6, 3e-6};
  P.body = {0, 0, 0};
  for (std::size_t i = 0; i < 3; ++i) P.m[i] = 2.7e-9;
  P.V = {0.9e-12, 1e-6, 1.01e-12};  // compressed; fractured debris blown up; in tension
  P.p = {1e9, 0.0, -1e8};            // the fractured point: zero pressure, zero deviator
  P.s[0] = {1e8, 0.0, 0.0};
  Material m;
  m.rho0 = 2700;
  m.E = 69e9;
  m.nu = 0.33;
  const std::vector<Thermo> th{Thermo(m)};
  const std::vector<Region> regions{{"band", 0.0, 5e-6, 0, 2e-6}};
  const auto s = region_stats(P, regions, th, {m}, {0});
  // solid 0.9 + 1 (the debris capped at m / rho0) + 1.01 (intact tension counts its V) = 2.91e-12
  CHECK(s[0].open == Approx(1.0 - 2.91e-12 / 1e-11));
  // the debris still counts its own density in the mean
  CHECK(s[0].rho.mean == Approx((3000.0 + 2.7e-3 + 2700.0 / 1.01) / 3.0));
}

TEST_CASE("open porosity: a hot fractured point holds its zero-pressure volume, not m / rho0", "[diagnostics]") {
  // Mie-Grueneisen aluminium: a fractured point at e keeps m / rho_zp(e) as solid, where intact
  // material of that energy has zero pressure (its thermal expansion is not void); a cold one
  // (e = 0) keeps m / rho0 as before.
  Material m;
  m.eos = MieGruneisenModel{5350, 1.34, 2.0};
  m.rho0 = 2700;
  m.E = 69e9;
  m.nu = 0.33;
  m.cv = 880;
  const kern::MieGruneisenEos eos = m.gruneisen().value();
  const double e = 6e5;  // [J/kg], about 980 K
  const double rho_zp = eos.zero_pressure_density(e);
  // the definition: zero pressure at (rho_zp, e), and below rho0 (tension branch)
  CHECK(std::fabs(eos.pressure(rho_zp, e)) < 1e-6 * eos.C);
  CHECK(rho_zp < 0.97 * m.rho0);  // 2587 kg/m^3: 4.2 % expansion
  CHECK(eos.zero_pressure_density(0.0) == m.rho0);
  CHECK(eos.zero_pressure_density(-1e5) == m.rho0);
  Particles P;
  P.resize(3);
  Particles::enable(P.e, 3, true);
  P.x[1] = {1e-6, 2e-6, 3e-6};
  P.body = {0, 0, 0};
  for (std::size_t i = 0; i < 3; ++i) P.m[i] = 2.7e-9;  // m / rho0 = 1e-12 m^2
  P.V = {1.2e-12, 1.2e-12, 1.01e-12};  // hot and fractured; cold and fractured; hot, thermally expanded, intact
  P.e = {e, 0.0, e};
  P.p = {0.0, 0.0, 0.0};
  P.s[0] = {0.0, 0.0, 1e6};  // the third carries a deviator: not fractured
  const std::vector<Thermo> th{Thermo(m)};
  const std::vector<Region> regions{{"band", 0.0, 5e-6, 0, 2e-6}};
  const auto s = region_stats(P, regions, th, {m}, {0});
  const double solid = 2.7e-9 / rho_zp + 1e-12 + 1.01e-12;
  CHECK(s[0].open == Approx(1.0 - solid / 1e-11));
  // past e = C / (Gamma rho0) the tension branch has no zero-pressure density: all of V is solid
  const double e_max = eos.C / eos.gamma_rho();
  CHECK(eos.zero_pressure_density(1.5 * e_max) < 0.0);
  P.e[0] = 1.5 * e_max;
  const auto hot = region_stats(P, regions, th, {m}, {0});
  CHECK(hot[0].open == Approx(1.0 - (1.2e-12 + 1e-12 + 1.01e-12) / 1e-11));
}

// A square lattice of points (spacing s, periodic along x over 40 s, 30 s high) with a slot of
// 10 x 2 points taken out: in the middle, across the periodic seam, and across the seam with a
// channel 2 points wide from the slot to the free top on the other side of the seam. The slot
// across the seam is the middle one moved by 20 spacings (60 pixels): the same image, so the
// same open area; the neighbours' disks (0.75 s) reach 0.25 s into the slot on each side, so its
// open area lies between 9.5 x 1.5 s^2 and the slot's 10 x 2 s^2 (15.8 s^2). Through the channel the slot is outside the body, however the
// flood has to cross the seam: no open area.
TEST_CASE("open area: a slot across the periodic seam, closed and open to the free top", "[diagnostics]") {
  const double s = 1e-6, W = 40 * s;
  const auto lattice = [&](auto removed) {
    Particles P;
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 40; ++i) {
        if (removed(i, j)) continue;
        const std::size_t k = P.size();
        P.resize(k + 1);
        P.x[0][k] = (i + 0.5) * s;
        P.x[1][k] = (j + 0.5) * s;
        P.V[k] = s * s;
        P.body[k] = 0;
      }
    return P;
  };
  const auto area = [&](const Particles& P) {
    const std::vector<Window> all{Window{{0.0, -1e300}, {W, 1e300}}};
    return open_area(P, 0, all, s / 3, kCoverRadius, Vector{W, 0.0}, Vector{0.0, 0.0})[0];
  };
  const auto in_slot = [](int i, int j, int i0) { return (j == 14 || j == 15) && (i - i0 + 40) % 40 < 10; };
  const double middle = area(lattice([&](int i, int j) { return in_slot(i, j, 15); }));
  const double seam = area(lattice([&](int i, int j) { return in_slot(i, j, 35); }));
  const double open = area(lattice([&](int i, int j) { return in_slot(i, j, 35) || (j >= 16 && (i == 2 || i == 3)); }));
  const double none = area(lattice([](int, int) { return false; }));
  WARN("open area [s^2]: middle " << middle / (s * s) << ", across the seam " << seam / (s * s) << ", with the channel " << open / (s * s));
  CHECK(none == 0.0);
  CHECK(middle > 9.5 * 1.5 * s * s);  // the scallops between the disks are open too
  CHECK(middle < 10 * 2 * s * s);
  CHECK(seam == Approx(middle).epsilon(1e-12));
  CHECK(open == 0.0);
}

TEST_CASE("front detection on a synthetic profile", "[diagnostics]") {
  // a body moving at -1000 m/s, stopped below y = 412.5 um (rows of 5 um): the half-jump level is
  // crossed between the last stopped row centre and the first moving one
  Particles P;
  const int rows = 200;
  P.resize(rows);
  for (int r = 0; r < rows; ++r) {
    P.x[1][r] = (r + 0.5) * 5e-6;
    P.v[1][r] = P.x[1][r] < 412.5e-6 ? 0.0 : -1000.0;
    P.body[r] = 0;
  }
  const double y = front_position(P, 0, -1000.0, 0.0, 5e-6, rows, true);
  // rows 81 (centre 407.5 um, stopped) and 82 (412.5, moving): level 500 m/s is midway
  CHECK(y * 1e6 == Approx(410.0));
  // a linear ramp over 10 rows: the 50 % point
  for (int r = 0; r < rows; ++r) P.v[1][r] = -1000.0 * std::clamp((r - 100) / 10.0, 0.0, 1.0);
  const double y2 = front_position(P, 0, -1000.0, 0.0, 5e-6, rows, true);
  CHECK(y2 * 1e6 == Approx((105 + 0.5) * 5.0));
  // the wave has reached the far end (the top rows move up, released): no front
  for (int r = 0; r < rows; ++r) P.v[1][r] = r < 190 ? 0.0 : 300.0;
  CHECK(std::isnan(front_position(P, 0, -1000.0, 0.0, 5e-6, rows, true)));
}
