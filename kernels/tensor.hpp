// Small dimension-indexed types for the kernels: plain aggregates of doubles (or ints) with
// inlined loops over axes, no Eigen temporaries and no virtual calls. D is the number of axes
// (kDim for the engine as built). Component order everywhere: x, y (, z); a symmetric tensor
// stores its diagonal first, then the off-diagonal entries (a, b), a < b, in row order:
//   D = 2: xx, yy, xy          D = 3: xx, yy, zz, xy, xz, yz
// which is the order of the particles' stress arrays and of the checkpoint names.
#pragma once
#include "dimension.hpp"
#include <cstddef>

// Everything called per particle inside a vectorized particle loop is forced inline: GCC 12
// kept such calls out of line otherwise (measured with perf), and a call keeps a loop scalar.
#define SMPM_INLINE [[gnu::always_inline]] inline

namespace SMPM_NS::kern {

// The engine's dimension: every array of axis components has kDim entries.
inline constexpr int kDim = SMPM_DIM;

// Names of the axes, for case keys, checkpoints and messages.
inline constexpr const char* kAxisNames[3] = {"x", "y", "z"};

// Number of independent components of a symmetric D x D tensor.
constexpr int sym_size(int D) { return D * (D + 1) / 2; }
// Number of independent components of an antisymmetric (spin) D x D tensor.
constexpr int spin_size(int D) { return D * (D - 1) / 2; }

// Index of entry (a, b) of a symmetric tensor in the order above (a, b < D).
constexpr int sym_index(int D, int a, int b) {
  if (a == b) return a;
  const int lo = a < b ? a : b, hi = a < b ? b : a;
  // off-diagonal entries after the D diagonal ones: (0,1), (0,2), ..., (1,2), ...
  int k = D;
  for (int r = 0; r < lo; ++r) k += D - 1 - r;
  return k + (hi - lo - 1);
}
// Row and column of symmetric component k.
constexpr int sym_row(int D, int k) {
  if (k < D) return k;
  int r = 0, start = D;
  while (k >= start + (D - 1 - r)) start += D - 1 - r++;
  return r;
}
constexpr int sym_col(int D, int k) {
  if (k < D) return k;
  const int r = sym_row(D, k);
  return k - sym_index(D, r, r + 1) + r + 1;
}

template <int D, class T = double>
struct Vec {
  T c[D];
  SMPM_INLINE T& operator[](int d) { return c[d]; }
  SMPM_INLINE const T& operator[](int d) const { return c[d]; }
};
template <int D>
using Idx = Vec<D, int>;

// The vector with every component v.
template <int D, class T>
constexpr Vec<D, T> uniform(T v) {
  Vec<D, T> r{};
  for (int d = 0; d < D; ++d) r.c[d] = v;
  return r;
}

// A general D x D matrix, row-major: (r, c) = c[r][col].
template <int D>
struct Mat {
  double c[D][D];
  SMPM_INLINE double& operator()(int r, int k) { return c[r][k]; }
  SMPM_INLINE double operator()(int r, int k) const { return c[r][k]; }
  SMPM_INLINE double trace() const {
    double t = c[0][0];
#pragma GCC unroll 3
    for (int d = 1; d < D; ++d) t += c[d][d];
    return t;
  }
};

// A symmetric D x D tensor, components in the order above.
template <int D>
struct Sym {
  static constexpr int K = sym_size(D);
  double c[K];
  SMPM_INLINE double& operator[](int k) { return c[k]; }
  SMPM_INLINE double operator[](int k) const { return c[k]; }
  SMPM_INLINE double operator()(int a, int b) const { return c[sym_index(D, a, b)]; }
  SMPM_INLINE double trace() const {
    double t = c[0];
#pragma GCC unroll 3
    for (int d = 1; d < D; ++d) t += c[d];
    return t;
  }
};

// The spin W = (L - L^T) / 2: its components above the diagonal, (0,1), (0,2), (1,2).
template <int D>
struct Spin {
  static constexpr int K = spin_size(D);
  double c[K > 0 ? K : 1];
  SMPM_INLINE double& operator[](int k) { return c[k]; }
  SMPM_INLINE double operator[](int k) const { return c[k]; }
};

// |v|^2 of a kDim-vector, summed in axis order.
SMPM_INLINE double norm2(const double* v) {
  double s = v[0] * v[0];
#pragma GCC unroll 3
  for (int d = 1; d < kDim; ++d) s += v[d] * v[d];
  return s;
}

// sym(L) and the spin of a velocity gradient, each entry formed as 0.5 (L_ab +- L_ba) (the
// diagonal as L_aa itself).
template <int D>
SMPM_INLINE Sym<D> sym_part(const Mat<D>& L) {
  Sym<D> s;
#pragma GCC unroll 3
  for (int d = 0; d < D; ++d) s[d] = L(d, d);
  for (int k = D; k < Sym<D>::K; ++k) {
    const int a = sym_row(D, k), b = sym_col(D, k);
    s[k] = 0.5 * (L(a, b) + L(b, a));
  }
  return s;
}
template <int D>
SMPM_INLINE Spin<D> spin_part(const Mat<D>& L) {
  Spin<D> w;
  for (int k = D; k < Sym<D>::K; ++k) {
    const int a = sym_row(D, k), b = sym_col(D, k);
    w[k - D] = 0.5 * (L(a, b) - L(b, a));
  }
  return w;
}

}  // namespace SMPM_NS::kern
