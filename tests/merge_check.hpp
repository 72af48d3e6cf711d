// kern::merge_closed_faces against its definition, for the engine's dimension: a point of a
// void-face field joins field 0 where every node of nonzero weight in its stencil is full and
// one of them welded (two fields present), each node's state computed here from the grid's
// mass and volume and a periodic axis wrapped node by node. Random grids (1 node in 8 not full
// in 2D, 1 in 25 in 3D; 1 in 3 welded), random points and points on the half-cell positions and
// on nodes, where a weight is zero; axis 0 (and axis 2 in 3D) periodic. The fields must agree
// point by point on 1, 2 and 3 threads.
#pragma once
#include <catch2/catch.hpp>
#include <omp.h>

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "kernels/stencil.hpp"
#include "kernels/void_closure.hpp"

namespace SMPM_NS::test {

// The merge's grid in the tests: `fields` velocity fields of nn nodes each over the arrays m and
// vol, and its parameters: a node is full at 0.9 of a cell, a field absent at 1e-9 kg/m or less.
inline kern::GridView merge_grid(std::vector<double>& m, std::vector<double>& vol, std::size_t nn, int fields) {
  kern::GridView G{};
  G.m = m.data();
  G.vol = vol.data();
  G.fstride = nn;
  G.fields = fields;
  return G;
}
inline kern::MergeParams merge_params() {
  kern::MergeParams q;
  q.fill = 0.9;
  q.mass_eps = 1e-9;
  q.lp = 0.25;
  return q;
}

template <class Shape>
void check_merge_against_nodes(unsigned seed) {
  using namespace kern;
  GridGeom g;
  g.h = 1e-6;
  for (int d = 0; d < kDim; ++d) g.n[d] = 8 + d;
  g.wrap[0] = true;
  if (kDim == 3) g.wrap[kDim - 1] = true;
  const std::size_t nn = g.num_nodes();
  double cell = 1.0;
  for (int d = 0; d < kDim; ++d) cell *= g.h;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<double> m(2 * nn, 0.0), vol(2 * nn, 0.0);
  for (std::size_t k = 0; k < nn; ++k) {
    m[k] = 1.0;
    vol[k] = (U(rng) < (kDim == 2 ? 0.12 : 0.04) ? 0.5 : 0.95) * cell;
    if (U(rng) < 0.35) m[k + nn] = 1e-3;
  }
  const GridView G = merge_grid(m, vol, nn, 2);
  const MergeParams q = merge_params();
  // points: inside every axis's real nodes with room for the stencil on the axes that do not wrap
  const int n = 4000;
  std::array<std::vector<double>, kDim> x;
  std::vector<std::uint8_t> field(n);
  for (int p = 0; p < n; ++p) {
    for (int d = 0; d < kDim; ++d) {
      const double lo = g.periodic(d) ? 0.0 : 2.0, hi = g.periodic(d) ? g.n[d] : g.n[d] - 2.0;
      double u = lo + (hi - lo) * U(rng);
      if (p % 4 == 0) u = std::floor(u) + 0.5;  // a weight exactly zero (quadratic, uGIMP)
      if (p % 8 == 1) u = std::floor(u);        // on a node (linear: a zero weight)
      x[d].push_back(u * g.h);
    }
    field[p] = static_cast<std::uint8_t>(p % 3 != 0);
  }
  // the definition, node by node
  std::vector<std::uint8_t> want = field;
  for (int p = 0; p < n; ++p) {
    if (!want[p]) continue;
    Vec<kDim> u;
    for (int d = 0; d < kDim; ++d) u[d] = x[d][p] / g.h;
    const Stencil<Shape, kDim> st(u, q.lp);
    bool all = true, any = false;
    st.for_each([&](const Idx<kDim>& a, int) {
      Idx<kDim> i;
      for (int d = 0; d < kDim; ++d) {
        if (st.w[d][a[d]] == 0.0) return;
        i[d] = st.base[d] + a[d];
        if (g.periodic(d)) i[d] = (i[d] + g.n[d]) % g.n[d];
      }
      const std::size_t k = g.node(i);
      const double V = vol[k] + vol[k + nn];
      all = all && V >= q.fill * cell;
      any = any || (V >= q.fill * cell && m[k] > q.mass_eps && m[k + nn] > q.mass_eps);
    });
    if (all && any) want[p] = 0;
  }
  std::array<const double*, kDim> xp;
  for (int d = 0; d < kDim; ++d) xp[d] = x[d].data();
  const int threads = omp_get_max_threads();
  std::size_t merged_first = 0;
  for (int t : {1, 2, 3}) {
    omp_set_num_threads(t);
    std::vector<std::uint8_t> got = field, state(3 * nn, 7);
    const std::size_t merged = merge_closed_faces<Shape>(g, g.all_nodes(), G, xp.data(), got.data(), n, q, state.data());
    int wrong = 0;
    for (int p = 0; p < n; ++p) wrong += got[p] != want[p];
    CHECK(wrong == 0);
    if (t == 1) merged_first = merged;
    CHECK(merged == merged_first);
  }
  omp_set_num_threads(threads);
  std::size_t expected = 0;
  for (int p = 0; p < n; ++p) expected += field[p] && !want[p];
  CHECK(merged_first == expected);
  CHECK(expected > 50);                       // merges happen
  CHECK(expected + 50 < std::size_t(2 * n / 3));  // and are refused
}

}  // namespace SMPM_NS::test
