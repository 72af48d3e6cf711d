// The stencil of one point: the tensor product of a 1D shape function (kernels/shape.hpp) over
// D axes. Built once per point from its position in grid units; every transfer, the heat
// scatter and gather, the void closure and the energy's affine term read their weights,
// gradients and node offsets from it, node by node in storage order (x fastest).
//   weight    w_i   = prod_d w_d[a_d]                       (products in axis order)
//   gradient  g_i,d = prod_e (e == d ? dw_e[a_e] : w_e[a_e])  (grid units: divide by h for 1/m)
//   offset    x_i,d - x_p,d = base_d + a_d - xg_d          (grid units)
// Products run in axis order: at D = 2, w = wx[a] wy[b], gx = dwx[a] wy[b], gy = wx[a] dwy[b],
// the order the results depend on bit for bit (scripts/bitwise_check.sh).
#pragma once
#include "dimension.hpp"
#include "shape.hpp"
#include "tensor.hpp"

namespace SMPM_NS::kern {

constexpr int ipow(int b, int e) { return e == 0 ? 1 : b * ipow(b, e - 1); }

template <class Shape, int D>
struct Stencil {
  static constexpr int N = Shape::N;           // nodes per axis
  static constexpr int Nodes = ipow(N, D);     // nodes in all
  double xg[D];                                // position in grid units
  int base[D];                                 // first node per axis
  double w[D][N], dw[D][N];                    // 1D weights and derivatives per axis

  SMPM_INLINE Stencil(const Vec<D>& pos, double lp) {
#pragma GCC unroll 3
    for (int d = 0; d < D; ++d) {
      xg[d] = pos[d];
      base[d] = Shape::eval(pos[d], lp, w[d], dw[d]);
    }
  }
  // node offsets a[d] of the k-th node in storage order (x fastest)
  SMPM_INLINE static Idx<D> digits(int k) {
    Idx<D> a;
#pragma GCC unroll 3
    for (int d = 0; d < D; ++d) {
      a[d] = k % N;
      k /= N;
    }
    return a;
  }
  SMPM_INLINE double weight(const Idx<D>& a) const {
    double v = w[0][a[0]];
#pragma GCC unroll 3
    for (int d = 1; d < D; ++d) v *= w[d][a[d]];
    return v;
  }
  SMPM_INLINE double grad(const Idx<D>& a, int d) const {
    double v = d == 0 ? dw[0][a[0]] : w[0][a[0]];
#pragma GCC unroll 3
    for (int e = 1; e < D; ++e) v *= e == d ? dw[e][a[e]] : w[e][a[e]];
    return v;
  }
  SMPM_INLINE Vec<D> gradient(const Idx<D>& a) const {
    Vec<D> g;
#pragma GCC unroll 3
    for (int d = 0; d < D; ++d) g[d] = grad(a, d);
    return g;
  }
  SMPM_INLINE double offset(const Idx<D>& a, int d) const { return (base[d] + a[d]) - xg[d]; }
  // D = sum_i w_i (x_i - x_p)^2 along axis d (the APIC inertia, grid units), summed node by node
  SMPM_INLINE double inertia(int d) const {
    double s = 0.0;
#pragma GCC unroll 4
    for (int a = 0; a < N; ++a) {
      const double e = (base[d] + a) - xg[d];
      s += w[d][a] * e * e;
    }
    return s;
  }
  // What a line of nodes along axis 0 shares (offsets a, a[0] = 0), for e >= 1 (entry 0 unused):
  // the product c of the other axes' weights, that product with axis e's derivative in place of
  // its weight ce[e], and the offsets off[e] = x_i,e - x_p,e.
  struct LineWeights {
    double c, ce[D], off[D];
  };
  // f(a, lw) for every line along axis 0, in storage order, not unrolled: the 3D transfers
  // (kern::scatter_slots, kern::gather_sums_by_line) take a line's nodes as one vector.
  template <class F>
  SMPM_INLINE void for_each_line(F&& f) const {
#pragma GCC unroll 1
    for (int l = 0; l < Nodes / N; ++l) {
      const Idx<D> a = digits(l * N);
      LineWeights lw;
      lw.c = 1.0;
#pragma GCC unroll 3
      for (int e = 1; e < D; ++e) {
        lw.c *= w[e][a[e]];
        lw.off[e] = (base[e] + a[e]) - xg[e];
      }
#pragma GCC unroll 3
      for (int e = 1; e < D; ++e) {
        lw.ce[e] = 1.0;
#pragma GCC unroll 3
        for (int f = 1; f < D; ++f) lw.ce[e] *= f == e ? dw[f][a[f]] : w[f][a[f]];
      }
      f(a, static_cast<const LineWeights&>(lw));
    }
  }
  // f(a, k) for every node, k its index in storage order
  template <class F>
  SMPM_INLINE void for_each(F&& f) const {
#pragma GCC unroll 64
    for (int k = 0; k < Nodes; ++k) f(digits(k), k);
  }
  // The same calls in the same order, as a loop over the lines of nodes along axis 0 with the
  // line unrolled: for the one-field scatter, one point at a time, where for_each's full unroll
  // spends more instructions on node addresses than on the sums (the gathers, vectorized across
  // points, and the several-field scatter measure faster fully unrolled).
  template <class F>
  SMPM_INLINE void for_each_by_line(F&& f) const {
#pragma GCC unroll 1
    for (int l = 0; l < Nodes / N; ++l) {
      Idx<D> a = digits(l * N);
#pragma GCC unroll 8
      for (int a0 = 0; a0 < N; ++a0) {
        a[0] = a0;
        f(static_cast<const Idx<D>&>(a), l * N + a0);
      }
    }
  }
};

}  // namespace SMPM_NS::kern
