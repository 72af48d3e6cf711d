// The 3D transfer kernels (SMPM_DIM = 3) against their definitions, for the four shape
// functions: the colored scatter (kern::scatter_slots, a node's values as vectors) equals the
// node-by-node scatter into the grid (p2g_serial) to round-off and conserves mass and momentum;
// the line gather (kern::gather_sums_by_line) equals the node-by-node sums (kern::gather_sums)
// to round-off, for every combination of template switches the engine uses.
#include <catch2/catch.hpp>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "engine/grid.hpp"
#include "engine/particles.hpp"
#include "kernels/shape.hpp"
#include "kernels/transfer.hpp"
#include "tests/bins.hpp"
#include "tests/grid_update_check.hpp"
#include "tests/merge_check.hpp"

using namespace smpm;
using namespace smpm::kern;
static_assert(kDim == 3, "tests/test_3d_kernels.cpp is compiled for the 3D engine (SMPM_DIM=3)");

namespace {

// 13 x 11 x 9 cells of 10 um, periodic in x and z (tiles of 8 cells: partial tiles on every axis)
GridGeom make_geom() {
  GridGeom g;
  g.h = 1e-5;
  const int n[3] = {13, 11, 9};
  for (int d = 0; d < 3; ++d) {
    g.lo[d] = -0.3e-4 + 0.1e-4 * d;
    g.n[d] = n[d];
  }
  g.wrap[0] = g.wrap[2] = true;
  g.tile = 8;
  return g;
}

// n random points (2 cells from the non-periodic faces), random velocity, affine matrix, stress;
// field 0 or 1 at random
Particles random_particles(const GridGeom& g, std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0), F(0.0, 1.0);
  Particles P;
  P.field.resize(1);  // allocated: resize sizes it
  P.resize(n);
  P.enable_affine(true);
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      const double m = g.periodic(d) ? 0.0 : 2 * g.h;
      P.x[d][i] = g.origin(d) + m + F(rng) * (g.length(d) - 2 * m);
      P.v[d][i] = 100 * U(rng);
    }
    P.m[i] = 1e-12 * (1.0 + 0.5 * U(rng));
    P.V[i] = 1e-16 * (1.0 + 0.1 * U(rng));
    for (int k = 0; k < 6; ++k) P.s[k][i] = 1e8 * U(rng);
    P.p[i] = 1e9 * U(rng);
    for (int k = 0; k < 9; ++k) P.C[k][i] = 1e7 * U(rng);
    P.field[i] = F(rng) < 0.5 ? 0 : 1;
    P.id[i] = static_cast<std::uint32_t>(i);
  }
  return P;
}

using test::Bins;
using test::bin;

// The largest difference between two node arrays over the largest magnitude of the first.
double rel_diff(const std::vector<double>& ref, const std::vector<double>& x) {
  double scale = 0, worst = 0;
  for (double v : ref) scale = std::max(scale, std::fabs(v));
  for (std::size_t n = 0; n < ref.size(); ++n) worst = std::max(worst, std::fabs(x[n] - ref[n]));
  return scale > 0 ? worst / scale : worst;
}

// Colored (vector) against node-by-node scatter, one field, APIC or not; mass and momentum
// against the points' (B-splines' and the hat's weights sum to 1, and their first moments
// vanish: the affine momentum adds nothing in all).
template <class S, bool APIC>
void check_scatter(const GridGeom& g, const Particles& P, const Bins& b) {
  INFO("shape with " << S::N << " nodes per axis, APIC " << APIC);
  Particles Q = P;
  auto pv = Q.view();
  Grid a(g, false), s(g, false);
  auto A = a.view(), Sv = s.view();
  clear_grid(g, g.all_nodes(), A, true);
  clear_grid(g, g.all_nodes(), Sv, true);
  p2g_colored<S, APIC, P2GWhat::All>(g, A, pv, b.order.data(), b.start.data(), 0.25);
  p2g_serial<S, APIC, P2GWhat::All>(g, Sv, pv, b.order.data(), Q.size(), 0.25);
  CHECK(rel_diff(s.m, a.m) < 1e-14);
  for (int d = 0; d < 3; ++d) {
    CHECK(rel_diff(s.p[d], a.p[d]) < 1e-13);
    CHECK(rel_diff(s.f[d], a.f[d]) < 1e-13);
  }
  double M = 0, Mg = 0, p[3] = {}, pg[3] = {};
  for (std::size_t i = 0; i < Q.size(); ++i) {
    M += Q.m[i];
    for (int d = 0; d < 3; ++d) p[d] += Q.m[i] * Q.v[d][i];
  }
  for (std::size_t n = 0; n < g.num_nodes(); ++n) {
    Mg += a.m[n];
    for (int d = 0; d < 3; ++d) pg[d] += a.p[d][n];
  }
  CHECK(Mg == Approx(M).epsilon(1e-13));
  for (int d = 0; d < 3; ++d) CHECK(pg[d] == Approx(p[d]).margin(1e-13 * M * 100));
}

// Two velocity fields (a weld of void faces: volumes; two bodies: mass gradients too).
template <class S, bool Normals>
void check_scatter_fields(const GridGeom& g, const Particles& P, const Bins& b) {
  INFO("shape with " << S::N << " nodes per axis, two fields, normals " << Normals);
  Particles Q = P;
  auto pv = Q.view();
  pv.field_of = Q.field.data();
  Grid a(g, false, 2, Normals), s(g, false, 2, Normals);
  auto A = a.view(), Sv = s.view();
  clear_grid(g, g.all_nodes(), A, true);
  clear_grid(g, g.all_nodes(), Sv, true);
  p2g_colored<S, true, P2GWhat::All, true, Normals>(g, A, pv, b.order.data(), b.start.data(), 0.25);
  p2g_range<S, true, P2GWhat::All, GridSink<PlainAdd>, true, Normals>(g, GridSink<PlainAdd>{g, Sv}, pv,
                                                                        b.order.data(), 0, Q.size(), 0.25);
  CHECK(rel_diff(s.m, a.m) < 1e-14);
  CHECK(rel_diff(s.vol, a.vol) < 1e-14);
  for (int d = 0; d < 3; ++d) {
    CHECK(rel_diff(s.p[d], a.p[d]) < 1e-13);
    CHECK(rel_diff(s.f[d], a.f[d]) < 1e-13);
    if (Normals) CHECK(rel_diff(s.gm[d], a.gm[d]) < 1e-13);
  }
}

// Random node values (velocities about 100 m/s) in every array a gather reads.
void random_nodes(Grid& G, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-100.0, 100.0);
  for (int d = 0; d < 3; ++d)
    for (auto* a : {&G.v[d], &G.p[d], &G.dv[d]})
      for (double& x : *a) x = U(rng);
  for (double& x : G.heat) x = std::fabs(U(rng));
}

// sums by lines against node by node, each relative to the sum of the magnitudes of its terms'
// scale (velocities of 100 m/s)
template <class S, bool FLIP, G2PWhat What, bool Heat, int Contact, bool PureFlip, bool WorkRate>
void check_gather(const GridGeom& g, const GridView& G, const Particles& P) {
  INFO("shape with " << S::N << " nodes per axis, FLIP " << FLIP << ", what " << static_cast<int>(What) << ", heat "
                     << Heat << ", contact " << Contact << ", pure FLIP " << PureFlip << ", work rate " << WorkRate);
  double worst = 0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    Vec<3> pos, u;
    Mat<3> uC;
    for (int d = 0; d < 3; ++d) {
      pos[d] = (P.x[d][p] - g.origin(d)) / g.h;
      u[d] = P.v[d][p];
      for (int c = 0; c < 3; ++c) uC(d, c) = P.C[d * 3 + c][p] * g.h;
    }
    const Stencil<S, 3> st(pos, 0.25);
    const std::size_t foff = Contact ? P.field[p] * G.fstride : 0;
    const GatherSums a = gather_sums<S, FLIP, What, Heat, Contact, PureFlip, WorkRate>(g, G, st, foff, 0.5, u, uC);
    const GatherSums b = gather_sums_by_line<S, FLIP, What, Heat, Contact, PureFlip, WorkRate>(g, G, st, foff, 0.5, u, uC);
    const auto diff = [&](double x, double y, double scale) { worst = std::max(worst, std::fabs(x - y) / scale); };
    const double V = 100.0, E = 3 * V * V * 10;  // velocity and squared-velocity scales
    for (int r = 0; r < 3; ++r) {
      diff(a.v[r], b.v[r], V);
      diff(a.dv[r], b.dv[r], V);
      for (int c = 0; c < 3; ++c) {
        diff(a.L[r][c], b.L[r][c], V);
        diff(a.W[r][c], b.W[r][c], V);
        diff(a.B[r][c], b.B[r][c], V);
      }
    }
    diff(a.v2 + a.r2, b.v2 + b.r2, E);
    diff(a.d2, b.d2, E);
    diff(a.qc, b.qc, V);
  }
  CHECK(worst < 1e-13);
}

template <class S>
void check_shape() {
  const GridGeom g = make_geom();
  const Particles P = random_particles(g, 6000, 11);
  const Bins b = bin(g, P);
  check_scatter<S, true>(g, P, b);
  check_scatter<S, false>(g, P, b);
  check_scatter_fields<S, false>(g, P, b);
  check_scatter_fields<S, true>(g, P, b);
  Grid G(g, true, 2, false);
  random_nodes(G, 3);
  const GridView V = G.view();
  check_gather<S, false, G2PWhat::Full, true, 0, false, true>(g, V, P);             // USL APIC, heating
  check_gather<S, false, G2PWhat::Full, true, 1, false, true>(g, V, P);             // ... with void faces
  check_gather<S, false, G2PWhat::Full, true, 2, false, true>(g, V, P);             // ... two bodies
  check_gather<S, false, G2PWhat::Full, false, 0, false, false>(g, V, P);           // USL APIC
  check_gather<S, false, G2PWhat::Velocity, true, 0, false, false>(g, V, P);        // MUSL APIC velocity
  check_gather<S, false, G2PWhat::PositionGradient, false, 1, false, false>(g, V, P);
  check_gather<S, true, G2PWhat::Full, true, 1, false, true>(g, V, P);              // USL FLIP, heating
  check_gather<S, true, G2PWhat::Velocity, false, 0, true, false>(g, V, P);         // MUSL pure FLIP
  check_gather<S, true, G2PWhat::Velocity, false, 0, false, false>(g, V, P);        // MUSL FLIP blend
}

}  // namespace

TEST_CASE("3D transfers: vector scatter and line gather match the node-by-node sums", "[transfer][3d]") {
  check_shape<Linear>();
  check_shape<UGIMP>();
  check_shape<QuadraticBSpline>();
  check_shape<CubicBSpline>();
}

TEST_CASE("3D merge_closed_faces: the blocks' states give each point what its nodes one by one give", "[unit][porous]") {
  smpm::test::check_merge_against_nodes<kern::Linear>(11);
  smpm::test::check_merge_against_nodes<kern::UGIMP>(12);
  smpm::test::check_merge_against_nodes<kern::QuadraticBSpline>(13);
  smpm::test::check_merge_against_nodes<kern::CubicBSpline>(14);
}

// tests/grid_update_check.hpp: the walls on both faces of y (x and z periodic), then on all six
// faces
TEST_CASE("3D grid update: vectorized runs off the walls give the node-by-node update bit for bit", "[grid]") {
  GridGeom g = make_geom();
  test::check_grid_update(g);
  g.wrap[0] = g.wrap[2] = false;
  test::check_grid_update(g);
}
