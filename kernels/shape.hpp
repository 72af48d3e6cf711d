// Shape functions, evaluated per axis in grid units (t = (x - x0) / h).
// eval() returns the first node of the support and fills w[N] (weights) and dw[N]
// (derivatives dN/dxg, i.e. gradients in grid units: divide by h for 1/m).
// One templated P2G / G2P code path serves all of them (kernels/transfer.hpp).
#pragma once
#include "dimension.hpp"
#include <cmath>

#include "views.hpp"

namespace SMPM_NS::kern {

// apic_gradient: for the linear hat, B D^-1 = sum_i v_i grad w_i^T exactly (D = f (1 - f) h^2
// per axis vanishes on nodes), so APIC takes C from the gradient; the others use C = B D^-1
// with D = sum_i w_i (x_i - x_p)^2 per axis (h^2/4 quadratic, h^2/3 cubic).

// What each shape declares besides its name and eval(): N nodes per axis, whether APIC takes C
// from the gradient, whether D = sum_i w_i (x_i - x_p)^2 is the same everywhere, and whether
// the support's first node is the point's cell plus a fixed offset cell_first (floor(t) +
// cell_first; then every point of a cell has the same nodes, which the one-field scatter sums
// per cell, kern::p2g_cells).
template <int Nodes, bool ApicGradient, bool ConstantD, bool CellStencil = false, int CellFirst = 0>
struct ShapeTraits {
  static constexpr int N = Nodes;
  static constexpr bool apic_gradient = ApicGradient;
  static constexpr bool constant_D = ConstantD;
  static constexpr bool cell_stencil = CellStencil;
  static constexpr int cell_first = CellFirst;
};

// Linear hat (classic MPM, Sulsky 1994). Support 2 nodes.
struct Linear : ShapeTraits<2, true, false, true, 0> {
  static constexpr const char* name = "linear";
  SMPM_INLINE static int eval(double t, double /*lp*/, double* w, double* dw) {
    const double b = std::floor(t);
    const double f = t - b;
    w[0] = 1.0 - f;
    w[1] = f;
    dw[0] = -1.0;
    dw[1] = 1.0;
    return static_cast<int>(b);
  }
};

// Undeformed GIMP (Bardenhagen & Kober 2004). lp = half particle width in grid units
// (0 < lp <= 0.5). Support 1 + lp on each side: up to 3 nodes.
struct UGIMP : ShapeTraits<3, false, false> {
  static constexpr const char* name = "ugimp";
  static inline void one(double d, double lp, double& w, double& dw) {
    const double a = std::fabs(d);
    const double s = d < 0.0 ? -1.0 : 1.0;
    if (a <= lp) {
      w = 1.0 - (d * d + lp * lp) / (2.0 * lp);
      dw = -d / lp;
    } else if (a <= 1.0 - lp) {
      w = 1.0 - a;
      dw = -s;
    } else if (a < 1.0 + lp) {
      const double q = 1.0 + lp - a;
      w = q * q / (4.0 * lp);
      dw = -s * q / (2.0 * lp);
    } else {
      w = 0.0;
      dw = 0.0;
    }
  }
  SMPM_INLINE static int eval(double t, double lp, double* w, double* dw) {
    const int b = static_cast<int>(std::floor(t - lp));
#pragma GCC unroll 4
    for (int a = 0; a < N; ++a) {
      // d = t - x_node; dN/dxg = dS/dd.
      one(t - (b + a), lp, w[a], dw[a]);
    }
    return b;
  }
};

// Quadratic B-spline. Support 3 nodes.
struct QuadraticBSpline : ShapeTraits<3, false, true> {
  static constexpr const char* name = "quadratic";
  SMPM_INLINE static int eval(double t, double /*lp*/, double* w, double* dw) {
    const double b = std::floor(t - 0.5);
    const double f = t - b;  // in [0.5, 1.5)
    const double a0 = 1.5 - f, a1 = f - 1.0, a2 = f - 0.5;
    w[0] = 0.5 * a0 * a0;
    w[1] = 0.75 - a1 * a1;
    w[2] = 0.5 * a2 * a2;
    dw[0] = -a0;
    dw[1] = -2.0 * a1;
    dw[2] = a2;
    return static_cast<int>(b);
  }
};

// Cubic B-spline. Support 4 nodes.
struct CubicBSpline : ShapeTraits<4, false, true, true, -1> {
  static constexpr const char* name = "cubic";
  SMPM_INLINE static int eval(double t, double /*lp*/, double* w, double* dw) {
    const double b = std::floor(t) - 1.0;
    const double f = t - b;  // in [1, 2)
    const double d1 = f - 1.0;  // in [0, 1)
    const double d2 = 2.0 - f;  // |d| for node 2, in (0, 1]
    const double q0 = 2.0 - f;  // 2 - |d0|
    const double q3 = f - 1.0;  // 2 - |d3|
    w[0] = q0 * q0 * q0 / 6.0;
    w[1] = 2.0 / 3.0 - d1 * d1 + 0.5 * d1 * d1 * d1;
    w[2] = 2.0 / 3.0 - d2 * d2 + 0.5 * d2 * d2 * d2;
    w[3] = q3 * q3 * q3 / 6.0;
    dw[0] = -0.5 * q0 * q0;
    dw[1] = -2.0 * d1 + 1.5 * d1 * d1;
    dw[2] = 2.0 * d2 - 1.5 * d2 * d2;
    dw[3] = 0.5 * q3 * q3;
    return static_cast<int>(b);
  }
};

enum class ShapeKind { Linear, UGIMP, Quadratic, Cubic };

// Calls f(Shape{}) with the shape type selected at run time: the one dispatch point
// from a run-time choice to the templated kernels.
template <class F>
decltype(auto) with_shape(ShapeKind k, F&& f) {
  switch (k) {
    case ShapeKind::Linear: return f(Linear{});
    case ShapeKind::UGIMP: return f(UGIMP{});
    case ShapeKind::Quadratic: return f(QuadraticBSpline{});
    case ShapeKind::Cubic: break;
  }
  return f(CubicBSpline{});
}

}  // namespace SMPM_NS::kern
