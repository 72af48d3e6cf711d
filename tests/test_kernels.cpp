// Kernel unit tests: binning, conservation of the transfers, colored vs serial scatter.
#include <catch2/catch.hpp>
#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <random>

#include "engine/grid.hpp"
#include "engine/particles.hpp"
#include "kernels/constitutive.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/shape.hpp"
#include "kernels/sort.hpp"
#include "kernels/transfer.hpp"
#include "tests/bins.hpp"
#include "tests/gradient_arrays.hpp"
#include "tests/grid_update_check.hpp"

using namespace smpm;
using namespace smpm::kern;
using smpm::test::GradientArrays;

namespace {

// positions, velocities and velocity gradients the same, bit for bit
void require_same_kinematics(const Particles& A, const GradientArrays& LA, const Particles& B,
                             const GradientArrays& LB) {
  for (int d = 0; d < kDim; ++d) {
    REQUIRE(A.x[d] == B.x[d]);
    REQUIRE(A.v[d] == B.v[d]);
  }
  REQUIRE(LA == LB);
}

// the position arrays of sort_by_cell
std::array<const double*, kDim> xy(const double* x, const double* y) { return {x, y}; }

// sort_by_cell's keys of n points and its result (-1, or the first point outside the grid)
std::ptrdiff_t keys_of(const GridGeom& g, const std::array<const double*, kDim>& x, std::size_t n,
                       std::vector<std::uint32_t>& key) {
  key.assign(n, 0);
  std::vector<std::uint32_t> order(n), start(g.num_keys() + 1),
      hist(static_cast<std::size_t>(omp_get_max_threads()) * g.num_keys());
  return sort_by_cell(g, x.data(), n, key.data(), hist.data(), start.data(), order.data());
}

// Component d of a named grid array (d = 0 for a scalar one).
std::vector<double>& component(Grid& G, NodeArray a, int d) {
  switch (a) {
    case NodeArray::Momentum: return G.p[d];
    case NodeArray::Force: return G.f[d];
    case NodeArray::Velocity: return G.v[d];
    case NodeArray::VelocityChange: return G.dv[d];
    case NodeArray::Volume: return G.vol;
    default: return G.m;
  }
}

GridGeom make_geom(bool periodic) {
  GridGeom g;
  g.h = 0.01;
  g.lo[0] = -0.1;
  g.lo[1] = 0.2;
  g.n[0] = 37;  // not a multiple of the tile width on purpose
  g.n[1] = 29;
  g.wrap[0] = periodic;
  return g;
}

// n random particles inside [x0 + 2h, x1 - 2h] x [y0 + 2h, y1 - 2h] (anywhere when periodic in x),
// random velocity, affine matrix and stress.
Particles random_particles(const GridGeom& g, std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  const double mx = g.wrap[0] ? 0.0 : 2 * g.h;
  std::uniform_real_distribution<double> X(g.lo[0] + mx, g.lo[0] + g.length(0) - mx);
  std::uniform_real_distribution<double> Y(g.lo[1] + 2 * g.h, g.lo[1] + g.length(1) - 2 * g.h);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Particles P;
  P.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    P.x[0][i] = X(rng);
    P.x[1][i] = Y(rng);
    P.v[0][i] = U(rng);
    P.v[1][i] = U(rng);
    P.m[i] = 1.0 + 0.5 * U(rng);
    P.V[i] = 1e-5 * (1.0 + 0.1 * U(rng));
    P.s[0][i] = 1e3 * U(rng);
    P.s[1][i] = 1e3 * U(rng);
    P.s[2][i] = 1e3 * U(rng);
    P.p[i] = 1e3 * U(rng);
    P.id[i] = static_cast<std::uint32_t>(i);
  }
  P.enable_affine(true);
  for (std::size_t i = 0; i < n; ++i) {
    P.C[0][i] = 10 * U(rng);
    P.C[1][i] = 10 * U(rng);
    P.C[2][i] = 10 * U(rng);
    P.C[3][i] = 10 * U(rng);
  }
  return P;
}

using test::Bins;
using test::bin;

// A step's grid for the gather tests: P scattered (APIC or not) and the grid updated with dt
// (FLIP: its increments too), over all nodes
template <class S, bool APIC>
void scatter_and_update(const GridGeom& g, Particles& P, const GridView& G, double dt, bool flip) {
  const Bins b = bin(g, P);
  auto pv = P.view();
  clear_grid(g, g.all_nodes(), G, true);
  p2g_colored<S, APIC, P2GWhat::All>(g, G, pv, b.order.data(), b.start.data(), 0.25);
  GridUpdateParams q;
  q.dt = dt;
  q.flip = flip;
  grid_update(g, g.all_nodes(), G, q, nullptr);
}

}  // namespace

namespace {

void check_sort(const GridGeom& g, const Particles& P) {
  const int threads0 = omp_get_max_threads();
  omp_set_num_threads(1);
  Bins b1 = bin(g, P);
  for (int T : {2, 3, 8, 16, std::max(2, threads0)}) {  // 8, 16: key blocks met by few of many threads
    omp_set_num_threads(T);
    Bins b2 = bin(g, P);
    REQUIRE(b1.order == b2.order);
    REQUIRE(b1.start == b2.start);
  }
  omp_set_num_threads(threads0);
  std::vector<int> seen(P.size(), 0);
  for (std::size_t s = 0; s < P.size(); ++s) ++seen[b1.order[s]];
  REQUIRE(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; }));
  for (std::size_t s = 1; s < P.size(); ++s) {
    const auto ka = b1.key[b1.order[s - 1]], kb = b1.key[b1.order[s]];
    REQUIRE(ka <= kb);
    if (ka == kb) REQUIRE(b1.order[s - 1] < b1.order[s]);  // stable
  }
  // cell_start brackets exactly the particles of each key
  for (std::size_t k = 0; k < g.num_keys(); ++k)
    for (std::uint32_t s = b1.start[k]; s < b1.start[k + 1]; ++s) REQUIRE(b1.key[b1.order[s]] == k);
  REQUIRE(b1.start[g.num_keys()] == P.size());
  // the key maps back to the cell holding the particle (grid units as the transfers compute them)
  for (std::size_t i = 0; i < P.size(); i += 97) {
    const double inv_h = 1.0 / g.h;
    const int cx = static_cast<int>((P.x[0][i] - g.lo[0]) * inv_h), cy = static_cast<int>((P.x[1][i] - g.lo[1]) * inv_h);
    const int t = b1.key[i] / g.cells_per_tile(), l = b1.key[i] % g.cells_per_tile();
    REQUIRE((t % g.tiles(0)) * g.tile + l % g.tile == cx);
    REQUIRE((t / g.tiles(0)) * g.tile + l / g.tile == cy);
  }
}

}  // namespace

// Random order: every thread's histogram spans almost all keys. Nearly sorted (as between the
// engine's permutations): each thread's key range is a part of the keys, the ranges overlap
// where moved particles lie (kernels/sort.cpp).
TEST_CASE("sort: every particle exactly once, cells in order, stable, thread-count independent", "[sort]") {
  const GridGeom g = make_geom(false);
  Particles P = random_particles(g, 20000, 7);
  SECTION("random order") { check_sort(g, P); }
  SECTION("nearly sorted") {
    const Bins b = bin(g, P);
    Particles S = P;
    for (std::size_t s = 0; s < P.size(); ++s) {
      S.x[0][s] = P.x[0][b.order[s]];
      S.x[1][s] = P.x[1][b.order[s]];
    }
    std::mt19937_64 rng(5);
    std::uniform_int_distribution<std::size_t> pick(0, P.size() - 1);
    for (int k = 0; k < 200; ++k) {  // 1 % of the points jump elsewhere
      const std::size_t a = pick(rng), c = pick(rng);
      S.x[0][a] = P.x[0][c];
      S.x[1][a] = P.x[1][c];
    }
    check_sort(g, S);
  }
}

// The key's cell must be the transfers' cell, floor((x - x0) * (1 / h)), also for points on a cell
// edge and one ulp either side of it, and for tile widths that are not powers of two (the key
// divides by the tile width in doubles, with a correction).
TEST_CASE("sort: the key's cell is the transfers' cell, on cell edges too, any tile width", "[sort]") {
  for (int tile : {4, 5, 7, 8, 16}) {
    GridGeom g = make_geom(false);
    g.tile = tile;
    g.h = 0.1;  // 1 / 0.1 is inexact: (x - x0) * inv_h and (x - x0) / h differ on some edges
    const double inv_h = 1.0 / g.h;
    std::vector<double> x, y;
    for (int i = 0; i < g.n[0]; ++i) {
      const double e = g.lo[0] + i * g.h;
      for (double xi : {std::nextafter(e, -1e9), e, std::nextafter(e, 1e9), e + 0.5 * g.h}) {
        x.push_back(xi);
        y.push_back(g.lo[1] + (i % g.n[1]) * g.h);  // on a row edge too
      }
    }
    std::vector<std::uint32_t> key;
    const std::ptrdiff_t first = keys_of(g, xy(x.data(), y.data()), x.size(), key);
    // only the point just below x0 is outside
    REQUIRE(first == 0);
    for (std::size_t i = 1; i < x.size(); ++i) {
      const int cx = static_cast<int>(std::floor((x[i] - g.lo[0]) * inv_h));
      const int cy = static_cast<int>(std::floor((y[i] - g.lo[1]) * inv_h));
      const int tx = cx / tile, ty = cy / tile;
      const auto expect = static_cast<std::uint32_t>((ty * g.tiles(0) + tx) * g.cells_per_tile() +
                                                     (cy - ty * tile) * tile + (cx - tx * tile));
      INFO("tile " << tile << ", point " << i << ", x = " << x[i] << ", cell " << cx << ", " << cy);
      REQUIRE(key[i] == expect);
    }
  }
}

TEST_CASE("sort: a particle outside the grid is reported", "[sort]") {
  const GridGeom g = make_geom(false);
  Particles P = random_particles(g, 100, 3);
  P.x[1][42] = g.lo[1] - 1e-9;
  P.x[0][77] = std::nan("");
  std::vector<std::uint32_t> key;
  REQUIRE(keys_of(g, xy(P.x[0].data(), P.x[1].data()), P.size(), key) == 42);
}

namespace {

template <class S>
void check_conservation(bool periodic) {
  const GridGeom g = make_geom(periodic);
  Particles P = random_particles(g, 5000, 11);
  Grid grid(g, true);
  auto G = grid.view();
  auto pv = P.view();
  Bins b = bin(g, P);
  clear_grid(g, g.all_nodes(), G, true);
  p2g_colored<S, true, P2GWhat::All>(g, G, pv, b.order.data(), b.start.data(), 0.25);
  double* arrays[] = {G.m, G.p[0], G.p[1], G.f[0], G.f[1]};
  fold_periodic(g, g.all_nodes(), arrays, 5);

  // particle totals; APIC angular momentum x_p x m v_p + m (C_yx D_xx - C_xy D_yy),
  // D = sum_i w_i (x_i - x_p)^2 per axis
  auto affine_L = [&](std::size_t i) {
    double w[S::N], dw[S::N];
    double D[2] = {0, 0};
    const double xg[2] = {(P.x[0][i] - g.lo[0]) / g.h, (P.x[1][i] - g.lo[1]) / g.h};
    for (int d = 0; d < 2; ++d) {
      const int b = S::eval(xg[d], 0.25, w, dw);
      for (int a = 0; a < S::N; ++a) D[d] += w[a] * (b + a - xg[d]) * (b + a - xg[d]) * g.h * g.h;
    }
    return P.m[i] * (P.x[0][i] * P.v[1][i] - P.x[1][i] * P.v[0][i]) + P.m[i] * (P.C[2][i] * D[0] - P.C[1][i] * D[1]);
  };
  const bool exact_D = true;
  double M = 0, Px = 0, Py = 0, Lz = 0, Fx = 0, Fy = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    M += P.m[i];
    Px += P.m[i] * P.v[0][i];
    Py += P.m[i] * P.v[1][i];
    Lz += affine_L(i);
  }
  double gm = 0, gpx = 0, gpy = 0, gL = 0;
  int i0 = periodic ? 0 : -g.pad, i1 = periodic ? g.n[0] - 1 : g.n[0] + g.pad;
  for (int j = -g.pad; j <= g.n[1] + g.pad; ++j)
    for (int i = i0; i <= i1; ++i) {
      const auto n = g.node(i, j);
      gm += G.m[n];
      gpx += G.p[0][n];
      gpy += G.p[1][n];
      Fx += G.f[0][n];
      Fy += G.f[1][n];
      gL += (g.lo[0] + i * g.h) * G.p[1][n] - (g.lo[1] + j * g.h) * G.p[0][n];
    }
  CHECK(gm == Approx(M).epsilon(1e-13));
  CHECK(gpx == Approx(Px).epsilon(1e-12).margin(1e-10));
  CHECK(gpy == Approx(Py).epsilon(1e-12).margin(1e-10));
  CHECK(Fx == Approx(0.0).margin(1e-9));  // internal forces sum to zero
  CHECK(Fy == Approx(0.0).margin(1e-9));
  if (exact_D && !periodic) CHECK(gL == Approx(Lz).epsilon(1e-12));

  // G2P back with dt = 0: mass-weighted momentum and (APIC) angular momentum preserved
  GridUpdateParams q;
  q.dt = 0.0;
  grid_update(g, g.all_nodes(), G, q, nullptr);
  double* vel[] = {G.v[0], G.v[1]};
  fill_periodic_ghosts(g, g.all_nodes(), vel, 2);
  GradientArrays L(P.size());
  g2p<S, false, G2PWhat::Full>(g, G, pv, P.size(), G2PParams{0.0, 0.25, 0.0}, L.view());
  double Px2 = 0, Py2 = 0, Lz2 = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    Px2 += P.m[i] * P.v[0][i];
    Py2 += P.m[i] * P.v[1][i];
    Lz2 += affine_L(i);
  }
  CHECK(Px2 == Approx(gpx).epsilon(1e-12).margin(1e-10));
  CHECK(Py2 == Approx(gpy).epsilon(1e-12).margin(1e-10));
  if (exact_D && !periodic) CHECK(Lz2 == Approx(gL).epsilon(1e-12));
}

}  // namespace

TEST_CASE("P2G then G2P conserve mass and momentum (APIC: angular momentum)", "[transfer]") {
  for (bool periodic : {false, true}) {
    INFO("periodic " << periodic);
    check_conservation<Linear>(periodic);
    check_conservation<UGIMP>(periodic);
    check_conservation<QuadraticBSpline>(periodic);
    check_conservation<CubicBSpline>(periodic);
  }
}

namespace {

template <class S>
void check_colored_vs_serial(bool apic) {
  const GridGeom g = make_geom(true);
  Particles P = random_particles(g, 30000, 5);
  auto pv = P.view();
  Bins b = bin(g, P);
  Grid a(g, false), s(g, false), t(g, false);
  auto A = a.view(), Sg = s.view(), T = t.view();
  for (auto* G : {&A, &Sg, &T}) clear_grid(g, g.all_nodes(), *G, true);
  if (apic) {
    p2g_colored<S, true, P2GWhat::All>(g, A, pv, b.order.data(), b.start.data(), 0.25);
    p2g_serial<S, true, P2GWhat::All>(g, Sg, pv, b.order.data(), P.size(), 0.25);
    p2g_atomic<S, true, P2GWhat::All>(g, T, pv, b.order.data(), P.size(), 0.25);
  } else {
    p2g_colored<S, false, P2GWhat::All>(g, A, pv, b.order.data(), b.start.data(), 0.25);
    p2g_serial<S, false, P2GWhat::All>(g, Sg, pv, b.order.data(), P.size(), 0.25);
    p2g_atomic<S, false, P2GWhat::All>(g, T, pv, b.order.data(), P.size(), 0.25);
  }
  double worst = 0;
  for (auto arr : {NodeArray::Mass, NodeArray::Momentum, NodeArray::Force})
  for (int d = 0; d < (arr == NodeArray::Mass ? 1 : kDim); ++d) {
    const auto& x = component(a, arr, d);
    const auto& y = component(s, arr, d);
    const auto& z = component(t, arr, d);
    double scale = 0;
    for (double v : y) scale = std::max(scale, std::fabs(v));
    for (std::size_t n = 0; n < x.size(); ++n) {
      worst = std::max(worst, std::fabs(x[n] - y[n]) / scale);
      worst = std::max(worst, std::fabs(z[n] - y[n]) / scale);
    }
  }
  CHECK(worst < 1e-13);
}

}  // namespace

TEST_CASE("colored scatter matches a serial scatter to 1e-13 relative", "[transfer]") {
  check_colored_vs_serial<Linear>(false);
  check_colored_vs_serial<UGIMP>(true);
  check_colored_vs_serial<QuadraticBSpline>(true);
  check_colored_vs_serial<CubicBSpline>(true);
}

// Four void-face fields (a weld's scatter: volumes, no normals): the colored scatter, which
// zeroes and flushes only the fields a tile's particles hold, against a serial scatter of every
// particle into its field, for several tile widths (the default is 16) and with fields 1 and 3
// empty (the tiles skip them: they must stay exactly zero).
TEST_CASE("colored scatter into four velocity fields matches a serial scatter, any tile width", "[transfer][contact]") {
  for (int tile : {4, 7, 16}) {
    for (bool sparse : {false, true}) {
      INFO("tile " << tile << ", fields 0 and 2 only " << sparse);
      GridGeom g = make_geom(true);
      g.tile = tile;
      Particles P = random_particles(g, 20000, 13);
      P.field.resize(P.size());
      for (std::size_t i = 0; i < P.size(); ++i) P.field[i] = static_cast<std::uint8_t>(sparse ? 2 * (i % 2) : (i * 7) % 4);
      auto pv = P.view();
      pv.field_of = P.field.data();
      const Bins b = bin(g, P);
      Grid a(g, false, 4, false), s(g, false, 4, false);
      REQUIRE(a.gm[0].empty());
      auto A = a.view(), S = s.view();
      clear_grid(g, g.all_nodes(), A, true);
      clear_grid(g, g.all_nodes(), S, true);
      p2g_colored<QuadraticBSpline, true, P2GWhat::All, true, false>(g, A, pv, b.order.data(), b.start.data(), 0.25);
      p2g_range<QuadraticBSpline, true, P2GWhat::All, GridSink<PlainAdd>, true, false>(
          g, GridSink<PlainAdd>{g, S}, pv, b.order.data(), 0, P.size(), 0.25);
      double worst = 0;
      for (auto arr : {NodeArray::Mass, NodeArray::Momentum, NodeArray::Force, NodeArray::Volume})
      for (int d = 0; d < (arr == NodeArray::Momentum || arr == NodeArray::Force ? kDim : 1); ++d) {
        const auto& x = component(a, arr, d);
        const auto& y = component(s, arr, d);
        double scale = 0;
        for (double v : y) scale = std::max(scale, std::fabs(v));
        for (std::size_t n = 0; n < x.size(); ++n) worst = std::max(worst, std::fabs(x[n] - y[n]) / scale);
      }
      CHECK(worst < 1e-13);
      if (sparse) {
        const std::size_t nn = g.num_nodes();
        bool empty = true;
        for (int f : {1, 3})
          for (std::size_t n = 0; n < nn; ++n) empty &= a.m[n + f * nn] == 0.0 && a.p[0][n + f * nn] == 0.0 && a.vol[n + f * nn] == 0.0;
        CHECK(empty);
      }
    }
  }
}

TEST_CASE("colored scatter is bitwise identical for 1 and 2 threads", "[transfer]") {
  const GridGeom g = make_geom(true);
  Particles P = random_particles(g, 30000, 9);
  auto pv = P.view();
  Bins b = bin(g, P);
  Grid a(g, false), c(g, false);
  const int threads0 = omp_get_max_threads();
  omp_set_num_threads(1);
  auto A = a.view();
  clear_grid(g, g.all_nodes(), A, true);
  p2g_colored<QuadraticBSpline, true, P2GWhat::All>(g, A, pv, b.order.data(), b.start.data(), 0.25);
  omp_set_num_threads(2);
  auto C = c.view();
  clear_grid(g, g.all_nodes(), C, true);
  p2g_colored<QuadraticBSpline, true, P2GWhat::All>(g, C, pv, b.order.data(), b.start.data(), 0.25);
  REQUIRE(a.m == c.m);
  REQUIRE(a.p[0] == c.p[0]);
  REQUIRE(a.f[1] == c.f[1]);
  for (int t : {3, 5}) {  // shares that do not halve the tiles
    omp_set_num_threads(t);
    clear_grid(g, g.all_nodes(), C, true);
    p2g_colored<QuadraticBSpline, true, P2GWhat::All>(g, C, pv, b.order.data(), b.start.data(), 0.25);
    REQUIRE(a.m == c.m);
    REQUIRE(a.p[1] == c.p[1]);
    REQUIRE(a.f[0] == c.f[0]);
  }
  omp_set_num_threads(threads0);
}

// The one-field scatters that sum a cell's points before adding to the tile's block: MUSL's
// momentum scatter for a shape whose stencil is its cell's (linear, cubic; kern::p2g_cells) and
// the full scatter of the linear hat (mass, momentum, force as vectors over the cell's four
// nodes; kern::p2g_cell_vectors). The same values as a serial scatter point by point to rounding,
// the values a momentum scatter does not form untouched, and the same bits on any thread count.
template <class S, bool APIC, P2GWhat What>
void check_cell_scatter() {
  const GridGeom g = make_geom(true);
  Particles P = random_particles(g, 30000, 21);
  auto pv = P.view();
  const Bins b = bin(g, P);
  Grid a(g, false), s(g, false), c(g, false);
  auto A = a.view(), Sg = s.view(), C = c.view();
  const int threads0 = omp_get_max_threads();
  omp_set_num_threads(1);
  clear_grid(g, g.all_nodes(), A, true);
  p2g_colored<S, APIC, What>(g, A, pv, b.order.data(), b.start.data(), 0.25);
  clear_grid(g, g.all_nodes(), Sg, true);
  p2g_serial<S, APIC, What>(g, Sg, pv, b.order.data(), P.size(), 0.25);
  const auto worst = [](const std::vector<double>& x, const std::vector<double>& ref) {
    double scale = 0, w = 0;
    for (double v : ref) scale = std::max(scale, std::fabs(v));
    REQUIRE(scale > 0);
    for (std::size_t n = 0; n < x.size(); ++n) w = std::max(w, std::fabs(x[n] - ref[n]) / scale);
    return w;
  };
  for (int d = 0; d < kDim; ++d) CHECK(worst(a.p[d], s.p[d]) < 1e-13);
  if constexpr (What == P2GWhat::All) {
    CHECK(worst(a.m, s.m) < 1e-13);
    for (int d = 0; d < kDim; ++d) CHECK(worst(a.f[d], s.f[d]) < 1e-13);
  } else {
    CHECK(std::all_of(a.m.begin(), a.m.end(), [](double v) { return v == 0.0; }));
    CHECK(std::all_of(a.f[0].begin(), a.f[0].end(), [](double v) { return v == 0.0; }));
  }
  for (int t : {2, 3, 5}) {
    omp_set_num_threads(t);
    clear_grid(g, g.all_nodes(), C, true);
    p2g_colored<S, APIC, What>(g, C, pv, b.order.data(), b.start.data(), 0.25);
    REQUIRE(a.p[0] == c.p[0]);
    REQUIRE(a.p[1] == c.p[1]);
    REQUIRE(a.m == c.m);
    REQUIRE(a.f[0] == c.f[0]);
    REQUIRE(a.f[1] == c.f[1]);
  }
  omp_set_num_threads(threads0);
}

TEST_CASE("per-cell scatters (linear, cubic) match a serial scatter, any thread count", "[transfer]") {
  check_cell_scatter<Linear, false, P2GWhat::Momentum>();
  check_cell_scatter<Linear, true, P2GWhat::Momentum>();
  check_cell_scatter<CubicBSpline, true, P2GWhat::Momentum>();
  check_cell_scatter<Linear, false, P2GWhat::All>();
  check_cell_scatter<Linear, true, P2GWhat::All>();
}

TEST_CASE("thread shares by weight: contiguous, in thread order, every item once, balanced", "[transfer]") {
  std::mt19937 rng(5);
  for (std::size_t n : {0, 1, 7, 200}) {
    std::vector<std::uint64_t> w(n);
    for (auto& x : w) x = rng() % 4 == 0 ? 0 : rng() % 1000;  // a quarter empty, as tiles at an edge
    std::uint64_t total = 0, wmax = 0;
    for (auto x : w) total += x, wmax = std::max(wmax, x);
    for (int T : {1, 2, 3, 16}) {
      std::vector<std::pair<std::size_t, std::size_t>> share(T);
#pragma omp parallel num_threads(T)
      share[omp_get_thread_num()] = thread_share(n, [&](std::size_t k) { return w[k]; });
      CAPTURE(n, T);
      std::size_t next = 0;
      for (int t = 0; t < T; ++t) {
        REQUIRE(share[t].first == next);
        REQUIRE(share[t].second >= share[t].first);
        std::uint64_t sum = 0;
        for (std::size_t k = share[t].first; k < share[t].second; ++k) sum += w[k];
        REQUIRE(sum <= total / T + wmax + 1);  // within one item of an equal share
        next = share[t].second;
      }
      REQUIRE(next == n);
      for (int p = 0; 2 * p + 1 < T; ++p) {  // a pair's run: its two threads' shares together
        const auto run = weighted_parts(n, [&](std::size_t k) { return w[k]; }, 2 * p, 2 * p + 2, T);
        REQUIRE(run.first == share[2 * p].first);
        REQUIRE(run.second == share[2 * p + 1].second);
      }
    }
  }
}

// Two threads split a run from its two ends: each takes one contiguous run, together every item
// once. A thread held up (here: until the other has finished) keeps only its first chunk, at
// most a quarter of the items.
TEST_CASE("pair split: two contiguous runs that cover the items once, the held-up thread one chunk", "[transfer]") {
  for (std::uint32_t n : {0u, 1u, 2u, 5u, 97u, 1000u}) {
    for (int held : {-1, 0, 1}) {
      PairSplit split;
      std::vector<int> owner(n, -1);
      std::atomic<bool> other_done{false};
#pragma omp parallel num_threads(2)
      {
        const int t = omp_get_thread_num();
        split.init(3, 3 + n);
        std::uint32_t c0, c1;
        while (split.claim(t == 0, c0, c1)) {
          if (t == held && omp_get_num_threads() == 2)
            while (!other_done.load()) {
            }
          for (std::uint32_t k = c0; k < c1; ++k) owner[k - 3] = t;
        }
        if (t != held) other_done.store(true);
      }
      CAPTURE(n, held);
      REQUIRE(std::all_of(owner.begin(), owner.end(), [](int o) { return o >= 0; }));
      std::uint32_t k = 0;  // the front thread's items [0, k), the back thread's [k, n)
      while (k < n && owner[k] == 0) ++k;
      for (std::uint32_t i = k; i < n; ++i) REQUIRE(owner[i] == 1);
      if (held >= 0) REQUIRE((held == 0 ? k : n - k) <= std::max<std::uint32_t>(1, n / 4));
    }
  }
}

namespace {

// One USL and one MUSL transfer (FLIP, slip walls) of particles that occupy part of the grid,
// once over the whole grid (A, zeroed) and once over occupied_nodes only (B, every node first
// set to NaN): a read outside the box would put a NaN into the particles.
template <class S>
void check_occupied_box(bool periodic) {
  GridGeom g = make_geom(periodic);
  g.n[0] = 61;
  g.n[1] = 45;
  g.tile = 8;  // the boxes below are in tiles of 8 cells
  Particles P = random_particles(g, 4000, 21);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> X(g.lo[0] + 17.3 * g.h, g.lo[0] + 40.6 * g.h), Y(g.lo[1] + 9.5 * g.h, g.lo[1] + 25.2 * g.h);
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (!periodic) P.x[0][i] = X(rng);
    P.x[1][i] = Y(rng);
  }
  // the stencils' extremes: a point on the lower edge of a tile's first cell (it reaches the
  // node below that cell) and one at the top of a tile's last cell (two nodes above it)
  P.x[0][0] = g.lo[0] + 16 * g.h;
  P.x[1][0] = g.lo[1] + 24 * g.h;
  P.x[0][1] = g.lo[0] + 47.999 * g.h;
  P.x[1][1] = g.lo[1] + 31.999 * g.h;
  Bins b = bin(g, P);
  const NodeBox box = occupied_nodes(g, b.start.data());
  // the box is the occupied tiles' node blocks, not the grid
  REQUIRE(box.lo[1] == 8 - 1);
  REQUIRE(box.hi[1] == 31 + 2);
  if (periodic) {
    REQUIRE(box.lo[0] == -g.pad);
    REQUIRE(box.hi[0] == g.n[0] + g.pad);
  } else {
    REQUIRE(box.lo[0] == 16 - 1);
    REQUIRE(box.hi[0] == 47 + 2);
  }
  GridUpdateParams q;
  q.dt = 1e-4;
  q.gravity[1] = -9.81;
  q.walls = Walls{{Wall::Slip, Wall::Slip}, {Wall::Slip, Wall::Slip}};
  q.flip = true;
  const G2PParams gq{q.dt, 0.25, 0.95};
  auto transfer = [&](Grid& grid, const NodeBox& nb, Particles& Q, GradientArrays& L, bool musl,
                      std::vector<double>& rf) {
    auto G = grid.view();
    auto pv = Q.view();
    clear_grid(g, nb, G, true);
    p2g_colored<S, false, P2GWhat::All>(g, G, pv, b.order.data(), b.start.data(), 0.25);
    double* sums[] = {G.m, G.p[0], G.p[1], G.f[0], G.f[1]};
    fold_periodic(g, nb, sums, 5);
    grid_update(g, nb, G, q, rf.data());
    double* vel[] = {G.v[0], G.v[1], G.dv[0], G.dv[1]};
    fill_periodic_ghosts(g, nb, vel, 4);
    if (!musl) {
      g2p<S, true, G2PWhat::Full>(g, G, pv, Q.size(), gq, L.view());
      return;
    }
    g2p<S, true, G2PWhat::Velocity>(g, G, pv, Q.size(), gq);
    clear_grid(g, nb, G, false);
    p2g_colored<S, false, P2GWhat::Momentum>(g, G, pv, b.order.data(), b.start.data(), 0.25);
    fold_periodic(g, nb, sums + 1, 2);
    grid_velocity_from_momentum(g, nb, G, q);
    fill_periodic_ghosts(g, nb, vel, 2);
    g2p<S, false, G2PWhat::PositionGradient>(g, G, pv, Q.size(), gq, L.view());
  };
  for (bool musl : {false, true}) {
    INFO("musl " << musl);
    Particles PA = P, PB = P;
    Grid a(g, true), c(g, true);
    for (auto arr : {NodeArray::Mass, NodeArray::Momentum, NodeArray::Force, NodeArray::Velocity, NodeArray::VelocityChange})
      for (int d = 0; d < (arr == NodeArray::Mass ? 1 : kDim); ++d) {
        auto& v = component(c, arr, d);
        std::fill(v.begin(), v.end(), std::nan(""));
      }
    std::vector<double> rfa(kRowSlots * static_cast<std::size_t>(g.num_lines()), 1.0), rfb = rfa;
    GradientArrays LA(P.size()), LB(P.size());
    transfer(a, g.all_nodes(), PA, LA, musl, rfa);
    transfer(c, box, PB, LB, musl, rfb);
    require_same_kinematics(PA, LA, PB, LB);
    REQUIRE(rfa == rfb);  // wall reactions, 0 on the rows outside the box
    // inside the box the grids agree; outside, the box pass wrote nothing
    std::size_t outside = 0;
    for (int j = -g.pad; j <= g.n[1] + g.pad; ++j)
      for (int i = -g.pad; i <= g.n[0] + g.pad; ++i) {
        const auto n = g.node(i, j);
        const bool in = i >= box.lo[0] && i <= box.hi[0] && j >= box.lo[1] && j <= box.hi[1];
        outside += !in;
        for (auto arr : {NodeArray::Mass, NodeArray::Momentum, NodeArray::Velocity})
          for (int d = 0; d < (arr == NodeArray::Mass ? 1 : kDim); ++d) {
            if (in) REQUIRE(component(a, arr, d)[n] == component(c, arr, d)[n]);
            else REQUIRE(std::isnan(component(c, arr, d)[n]));
          }
      }
    REQUIRE(outside > 0);
  }
}

}  // namespace

TEST_CASE("grid passes over the occupied nodes only: the same transfer, nothing outside read or written",
          "[transfer][grid]") {
  for (bool periodic : {false, true}) {
    INFO("periodic " << periodic);
    check_occupied_box<Linear>(periodic);
    check_occupied_box<UGIMP>(periodic);
    check_occupied_box<QuadraticBSpline>(periodic);
    check_occupied_box<CubicBSpline>(periodic);
  }
}

// tests/grid_update_check.hpp: the walls on both faces of y and, not periodic, of x; lines of
// 150 cells too (runs of several 64-node chunks)
TEST_CASE("grid update: vectorized runs off the walls give the node-by-node update bit for bit", "[grid]") {
  for (bool periodic : {false, true})
    for (int nx : {37, 150}) {
      INFO("periodic " << periodic << ", " << nx << " cells along x");
      GridGeom g = make_geom(periodic);
      g.n[0] = nx;
      test::check_grid_update(g);
    }
}

TEST_CASE("pure FLIP velocity pass (flip_alpha = 1) gives the blend's velocities without the PIC sum",
          "[transfer]") {
  const GridGeom g = make_geom(false);
  Particles P = random_particles(g, 3000, 17);
  Grid grid(g, true);
  auto G = grid.view();
  scatter_and_update<Linear, false>(g, P, G, 1e-4, true);
  const G2PParams gq{1e-4, 0.25, 1.0};
  Particles A = P, B = P;
  auto pa = A.view(), pb = B.view();
  g2p<Linear, true, G2PWhat::Velocity>(g, G, pa, A.size(), gq);                      // pure FLIP body
  g2p_loop<Linear, true, G2PWhat::Velocity, false, false, false>(g, G, pb, B.size(), gq, {});  // the blend
  REQUIRE(A.v[0] == B.v[0]);
  REQUIRE(A.v[1] == B.v[1]);
  REQUIRE(A.v[0] != P.v[0]);
}

namespace {

// A scene without an energy field runs the heating gather too, heating a scratch array
// (Simulation::transfer_args): its velocities, positions, L and C must be the plain gather's.
// USL's pass (APIC and FLIP, Full) and MUSL's APIC velocity pass, the grid updated as for such a
// scene (no scatter velocity in px, mid = 0). std::vector's == compares doubles with ==, so a
// zero's sign may differ.
template <class S, bool FLIP, G2PWhat What>
void check_heat_sink() {
  const GridGeom g = make_geom(false);
  Particles P = random_particles(g, 3000, 29);
  Grid grid(g, FLIP);
  auto G = grid.view();
  scatter_and_update<S, !FLIP>(g, P, G, 1e-4, FLIP);
  const G2PParams gq{1e-4, 0.25, 0.95, 0.0};
  Particles A = P, B = P;
  std::vector<double> sink(P.size(), 0.0);
  auto pa = A.view(), pb = B.view();
  pb.e = sink.data();
  GradientArrays LA(P.size()), LB(P.size());
  g2p<S, FLIP, What>(g, G, pa, A.size(), gq, LA.view());
  g2p<S, FLIP, What, true>(g, G, pb, B.size(), gq, LB.view());
  require_same_kinematics(A, LA, B, LB);
  if constexpr (!FLIP)
    for (int k = 0; k < kDim * kDim; ++k) REQUIRE(A.C[k] == B.C[k]);
  REQUIRE(A.v[0] != P.v[0]);
  REQUIRE(std::any_of(sink.begin(), sink.end(), [](double e) { return e != 0.0; }));  // it did heat
}

}  // namespace

TEST_CASE("the heating gather without an energy field moves the points as the plain gather", "[transfer]") {
  SECTION("USL, APIC, linear hat") { check_heat_sink<Linear, false, G2PWhat::Full>(); }
  SECTION("USL, APIC, quadratic B-spline") { check_heat_sink<QuadraticBSpline, false, G2PWhat::Full>(); }
  SECTION("USL, FLIP 0.95, quadratic B-spline") { check_heat_sink<QuadraticBSpline, true, G2PWhat::Full>(); }
  SECTION("MUSL velocity pass, APIC, quadratic B-spline") {
    check_heat_sink<QuadraticBSpline, false, G2PWhat::Velocity>();
  }
}

namespace {

// The last gather pass with the constitutive update behind it, block by block (g2p_blocks), against
// the two passes one after the other (g2p, then constitutive_update over all points): for USL
// (APIC, quadratic B-spline; Mie-Grueneisen, J2, energy, viscosity) and MUSL's position pass
// (linear hat; linear EOS, elastic), 1 to 3 threads, whose shares split into blocks and vector
// remainders differently; the L that each block hands to the update is the separate gather's.
template <class S, G2PWhat What, class Eos, class Strength>
void check_fused_pass(const Eos& eos, const Strength& str, bool energy) {
  const GridGeom g = make_geom(false);
  // every thread count splits these into several blocks and a partial one
  Particles P = random_particles(g, 6 * kGatherBlock + 1001, 23);
  if (energy) {
    for (auto f : {&Particles::e, &Particles::epsp, &Particles::q}) Particles::enable(P.*f, P.size(), true);
    for (std::size_t i = 0; i < P.size(); ++i) P.e[i] = 1e3 * (1 + i % 7);
  }
  // volumes that the update makes non-positive (V <= 0 stays so): the lowest index is reported
  P.V[2100] = -1e-5;
  P.V[1700] = -1e-5;
  Grid grid(g, true);
  auto G = grid.view();
  scatter_and_update<S, What == G2PWhat::Full>(g, P, G, 1e-4, false);
  const G2PParams gq{1e-4, 0.25, 0.0};
  ConstitutiveParams cq;
  cq.dt = 1e-4;
  cq.av_length = g.h;
  cq.av_linear = 0.2;
  cq.av_quadratic = 2.0;
  auto state = [](Particles& Q) {
    auto opt = [](std::vector<double>& v) { return v.empty() ? nullptr : v.data(); };
    return ConstitutiveState{opt(Q.e), opt(Q.epsp), opt(Q.q), nullptr};
  };
  constexpr bool APIC = What == G2PWhat::Full;
  Particles R = P;  // reference: the unfused passes
  auto rv = R.view();
  GradientArrays LR(R.size());
  g2p<S, false, What>(g, G, rv, R.size(), gq, LR.view());
  const auto ref = constitutive_update(rv, state(R), LR.view(), R.size(), cq, eos, str);
  REQUIRE(ref.bad == 1700);
  const int threads0 = omp_get_max_threads();
  for (int threads : {1, 2, 3}) {
    INFO("threads " << threads);
    omp_set_num_threads(threads);
    Particles F = P;
    auto fv = F.view();
    const auto st = state(F);
    GradientArrays LF(F.size(), std::nan(""));
    auto after = [&](std::size_t first, std::size_t last, const Gradient& L, ConstitutiveResult& acc) {
      for (std::size_t i = first; i < last; ++i)
        for (int k = 0; k < kDim * kDim; ++k) LF.L[k][i] = L.L[k][i - first];
      acc.merge(constitutive_block(fv, st, L, first, last, cq, eos, str));
    };
    std::vector<double> scratch(kGatherScratch * static_cast<std::size_t>(threads), std::nan(""));
    const auto r = g2p_blocks<S, false, What, false, false, ConstitutiveResult>(g, G, fv, F.size(), gq,
                                                                               scratch.data(), after);
    REQUIRE(r.bad == ref.bad);
    REQUIRE(r.max_speed == ref.max_speed);
    require_same_kinematics(F, LF, R, LR);
    for (int k = 0; k < kSym; ++k) REQUIRE(F.s[k] == R.s[k]);
    for (auto f : {&Particles::V, &Particles::p, &Particles::e, &Particles::epsp, &Particles::q}) REQUIRE(F.*f == R.*f);
    if constexpr (APIC)
      for (int k = 0; k < kDim * kDim; ++k) REQUIRE(F.C[k] == R.C[k]);
  }
  omp_set_num_threads(threads0);
}

}  // namespace

TEST_CASE("last gather pass with the constitutive update block by block: bitwise the separate passes",
          "[transfer][constitutive]") {
  SECTION("USL, APIC, quadratic B-spline, Mie-Grueneisen + J2 + energy + viscosity") {
    check_fused_pass<QuadraticBSpline, G2PWhat::Full>(MieGruneisenEos::make(2700.0, 5350.0, 1.34, 2.0),
                                                      VonMisesStrength{26e9, 1e8, 1e8}, true);
  }
  SECTION("MUSL position pass, linear hat, linear elastic") {
    check_fused_pass<Linear, G2PWhat::PositionGradient>(LinearEos{1000.0, 1e6}, ElasticStrength{4e5}, false);
  }
}

// Void faces under APIC without an energy field weld by Coulomb contact (no scatter velocity in
// p), on a grid without the contact-heat array that no gather reads there (engine/grid.hpp):
// the same velocities and row losses as on a grid that has it.
TEST_CASE("void faces without a scatter velocity: contact on a grid without contact heat", "[contact]") {
  const GridGeom g = make_geom(false);
  Grid with(g, false, 2, true), without(g, false, 2, false);
  REQUIRE(without.heat.empty());
  const std::size_t n = g.node(3, 4), fs = g.num_nodes();
  for (Grid* gr : {&with, &without}) {
    gr->m[n] = 2; gr->m[n + fs] = 1;
    gr->v[0][n] = 1.5; gr->v[1][n] = 0; gr->v[0][n + fs] = -1; gr->v[1][n + fs] = 1;
    gr->vol[n] = 0.5 * g.h * g.h; gr->vol[n + fs] = 0.45 * g.h * g.h;
  }
  GridUpdateParams q;  // scatter_velocity false
  ContactParams c;
  c.weld = true;
  c.volume_fraction = 0.8;
  std::vector<double> la(static_cast<std::size_t>(g.num_lines()), 0.0), lb = la;
  grid_contact(g, g.all_nodes(), with.view(), q, c, la.data());
  grid_contact(g, g.all_nodes(), without.view(), q, c, lb.data());
  CHECK(with.v[0][n] == Approx((2 * 1.5 - 1.0) / 3));  // merged: the centre-of-mass velocity
  CHECK(with.v[0][n + fs] == Approx(with.v[0][n]));
  for (int d = 0; d < kDim; ++d) CHECK(with.v[d] == without.v[d]);
  CHECK(la == lb);
}

// The weld of separated void faces (grid_contact, weld): at a node the two fields fill, both
// take the centre-of-mass velocity and the merged scatter velocity; momentum is conserved, the
// row loss is 1/2 mu |u_0 - u_1|^2 of the scatter velocities, and a node the fields do not fill
// is left alone.
TEST_CASE("weld of void faces: centre of mass, merged scatter velocity, loss 1/2 mu du^2", "[contact]") {
  const GridGeom g = make_geom(false);
  Grid grid(g, false, 2);
  auto G = grid.view();
  const std::size_t full = g.node(3, 4), part = g.node(6, 4), fs = G.fstride;
  const double h2 = g.h * g.h;
  // full node: field 0 (m 2, u (1, 0), v (1.5, 0)), field 1 (m 1, u (-2, 1), v (-1, 1)), volume 0.9 h^2
  G.m[full] = 2; G.m[full + fs] = 1;
  G.p[0][full] = 1; G.p[1][full] = 0; G.p[0][full + fs] = -2; G.p[1][full + fs] = 1;  // scatter velocities
  G.v[0][full] = 1.5; G.v[1][full] = 0; G.v[0][full + fs] = -1; G.v[1][full + fs] = 1;
  G.vol[full] = 0.5 * h2; G.vol[full + fs] = 0.4 * h2;
  // partly filled node: volume 0.5 h^2, below the threshold
  G.m[part] = 1; G.m[part + fs] = 1;
  G.v[0][part] = 3; G.v[0][part + fs] = -3;
  G.vol[part] = 0.25 * h2; G.vol[part + fs] = 0.25 * h2;
  GridUpdateParams q;
  q.scatter_velocity = true;
  ContactParams c;
  c.weld = true;
  c.volume_fraction = 0.8;
  c.midstep = true;
  std::vector<double> loss(static_cast<std::size_t>(g.size(1)), 0.0);
  grid_contact(g, g.all_nodes(), G, q, c, loss.data());
  CHECK(G.v[0][full] == Approx((2 * 1.5 + 1 * -1.0) / 3));
  CHECK(G.v[0][full + fs] == G.v[0][full]);
  CHECK(G.v[1][full] == Approx(1.0 / 3));
  CHECK(G.p[0][full] == Approx((2 * 1.0 - 2.0) / 3));  // merged scatter velocity
  CHECK(G.p[0][full + fs] == G.p[0][full]);
  CHECK(G.p[1][full] == Approx(1.0 / 3));
  double total = 0;
  for (double l : loss) total += l;
  const double mu = 2.0 * 1.0 / 3.0;
  CHECK(total == Approx(0.5 * mu * (3.0 * 3.0 + 1.0 * 1.0)));
  CHECK(G.heat[full] == 0.0);
  CHECK(G.v[0][part] == 3.0);
  CHECK(G.v[0][part + fs] == -3.0);
}

// Four void-face fields (contact.void_face_fields = 4): the weld takes every field present at a
// full node to the centre of mass; its loss is sum_f 1/2 m_f |u_f - u_cm|^2 of the scatter
// velocities; a node with one field, or below the fill, is left alone.
TEST_CASE("weld of four void-face fields: centre of mass of the fields present, loss, momentum", "[contact]") {
  const GridGeom g = make_geom(false);
  Grid grid(g, false, 4);
  auto G = grid.view();
  REQUIRE(G.fields == 4);
  const std::size_t full = g.node(3, 4), lone = g.node(5, 4), part = g.node(6, 4), fs = G.fstride;
  const double h2 = g.h * g.h;
  // full node: fields 0, 1 and 3 hold mass (field 2 none), together 0.95 h^2
  const double m[4] = {2.0, 1.0, 0.0, 1.0}, u[4] = {1.0, -2.0, 0.0, 4.0}, w[4] = {0.0, 1.0, 0.0, -1.0};
  const double v[4] = {1.5, -1.0, 0.0, 2.0};
  for (int f = 0; f < 4; ++f) {
    const std::size_t k = full + f * fs;
    G.m[k] = m[f];
    G.p[0][k] = u[f];
    G.p[1][k] = w[f];
    G.v[0][k] = v[f];
    G.v[1][k] = 0.5 * v[f];
    G.vol[k] = m[f] > 0 ? 0.95 * h2 * m[f] / 4.0 : 0.0;
  }
  // a full node with one field only, and a node of two fields below the fill
  G.m[lone + 2 * fs] = 1.0;
  G.v[0][lone + 2 * fs] = 7.0;
  G.vol[lone + 2 * fs] = h2;
  G.m[part] = G.m[part + 3 * fs] = 1.0;
  G.v[0][part] = 3.0;
  G.v[0][part + 3 * fs] = -3.0;
  G.vol[part] = G.vol[part + 3 * fs] = 0.25 * h2;
  GridUpdateParams q;
  q.scatter_velocity = true;
  ContactParams c;
  c.weld = true;
  c.volume_fraction = 0.9;
  c.midstep = true;
  std::vector<double> loss(static_cast<std::size_t>(g.size(1)), 0.0);
  grid_contact(g, g.all_nodes(), G, q, c, loss.data());
  const double M = 4.0, cx = (2 * 1.5 - 1.0 + 2.0) / M, ux = (2 * 1.0 - 2.0 + 4.0) / M, uy = (0.0 + 1.0 - 1.0) / M;
  double expected = 0.0, mom = 0.0;
  for (int f = 0; f < 4; ++f) {
    const std::size_t k = full + f * fs;
    if (m[f] == 0.0) {
      CHECK(G.v[0][k] == 0.0);  // an absent field keeps its (zero) velocity
      continue;
    }
    CHECK(G.v[0][k] == Approx(cx));
    CHECK(G.v[1][k] == Approx(0.5 * cx));
    CHECK(G.p[0][k] == Approx(ux));
    CHECK(G.p[1][k] == Approx(uy).margin(1e-15));
    CHECK(G.heat[k] == 0.0);
    mom += m[f] * G.v[0][k];
    expected += 0.5 * m[f] * ((u[f] - ux) * (u[f] - ux) + (w[f] - uy) * (w[f] - uy));
  }
  CHECK(mom == Approx(2 * 1.5 - 1.0 + 2.0));
  double total = 0;
  for (double l : loss) total += l;
  CHECK(total == Approx(expected));
  CHECK(G.v[0][lone + 2 * fs] == 7.0);
  CHECK(G.v[0][part] == 3.0);
  CHECK(G.v[0][part + 3 * fs] == -3.0);
}
