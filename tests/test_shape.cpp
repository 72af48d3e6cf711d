// Shape functions: partition of unity, zero gradient sum, linear reproduction, gradients
// against finite differences, and weights against hand-computed values.
#include <catch2/catch.hpp>

#include <random>

#include "kernels/shape.hpp"
#include "kernels/stencil.hpp"

using namespace smpm::kern;

namespace {

template <class S>
void check_shape(double lp) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> U(2.0, 50.0);
  for (int k = 0; k < 10000; ++k) {
    const double x = U(rng);
    double w[S::N], dw[S::N];
    const int b = S::eval(x, lp, w, dw);
    double sw = 0, sdw = 0, sx = 0, sxdw = 0;
    for (int a = 0; a < S::N; ++a) {
      REQUIRE(w[a] >= -1e-15);
      sw += w[a];
      sdw += dw[a];
      sx += w[a] * (b + a);
      sxdw += dw[a] * (b + a);
    }
    REQUIRE(sw == Approx(1.0).margin(1e-14));
    REQUIRE(sdw == Approx(0.0).margin(1e-13));
    REQUIRE(sx == Approx(x).margin(1e-12));          // linear reproduction
    REQUIRE(sxdw == Approx(1.0).margin(1e-12));      // gradient of x is 1
    // derivative against central differences (away from kinks)
    const double e = 1e-6;
    double wp[S::N], wm[S::N], d[S::N];
    const int bp = S::eval(x + e, lp, wp, d);
    const int bm = S::eval(x - e, lp, wm, d);
    if (bp == b && bm == b) {
      for (int a = 0; a < S::N; ++a) REQUIRE(dw[a] == Approx((wp[a] - wm[a]) / (2 * e)).margin(1e-5));
    }
  }
}

}  // namespace

TEST_CASE("partition of unity and gradients: linear", "[shape]") { check_shape<Linear>(0.0); }
TEST_CASE("partition of unity and gradients: uGIMP", "[shape]") {
  check_shape<UGIMP>(0.25);
  check_shape<UGIMP>(0.5);
  check_shape<UGIMP>(1.0 / 6.0);
}
TEST_CASE("partition of unity and gradients: quadratic B-spline", "[shape]") { check_shape<QuadraticBSpline>(0.0); }
TEST_CASE("partition of unity and gradients: cubic B-spline", "[shape]") { check_shape<CubicBSpline>(0.0); }

TEST_CASE("weights against hand-computed values", "[shape]") {
  double w[4], dw[4];
  // linear at x = 3.25: nodes 3, 4 with weights 0.75, 0.25
  REQUIRE(Linear::eval(3.25, 0, w, dw) == 3);
  CHECK(w[0] == Approx(0.75));
  CHECK(w[1] == Approx(0.25));
  // quadratic midway between nodes 5 and 6 (x = 5.5): N(0.5) = 1/2, N(1.5) = 0
  REQUIRE(QuadraticBSpline::eval(5.5, 0, w, dw) == 5);
  CHECK(w[0] == Approx(0.5));
  CHECK(w[1] == Approx(0.5));
  CHECK(w[2] == Approx(0.0).margin(1e-15));
  CHECK(dw[0] == Approx(-1.0));
  CHECK(dw[1] == Approx(1.0));
  // quadratic on node 4: nodes 3, 4, 5 with 1/8, 3/4, 1/8 and slopes -1/2, 0, 1/2
  REQUIRE(QuadraticBSpline::eval(4.0, 0, w, dw) == 3);
  CHECK(w[0] == Approx(0.125));
  CHECK(w[1] == Approx(0.75));
  CHECK(w[2] == Approx(0.125));
  CHECK(dw[0] == Approx(-0.5));
  CHECK(dw[1] == Approx(0.0).margin(1e-15));
  CHECK(dw[2] == Approx(0.5));
  // cubic on a node x = 7: nodes 6, 7, 8, 9 with 1/6, 2/3, 1/6, 0
  REQUIRE(CubicBSpline::eval(7.0, 0, w, dw) == 6);
  CHECK(w[0] == Approx(1.0 / 6.0));
  CHECK(w[1] == Approx(2.0 / 3.0));
  CHECK(w[2] == Approx(1.0 / 6.0));
  CHECK(w[3] == Approx(0.0).margin(1e-15));
  CHECK(dw[0] == Approx(-0.5));  // the node behind loses weight as the particle moves on
  CHECK(dw[2] == Approx(0.5));
  // cubic at mid-cell x = 7.5: 1/48, 23/48, 23/48, 1/48
  REQUIRE(CubicBSpline::eval(7.5, 0, w, dw) == 6);
  CHECK(w[0] == Approx(1.0 / 48.0));
  CHECK(w[1] == Approx(23.0 / 48.0));
  CHECK(w[2] == Approx(23.0 / 48.0));
  CHECK(w[3] == Approx(1.0 / 48.0));
  // uGIMP, lp = 0.25, particle at x = 2.25 (a quarter cell past node 2):
  // node 2: |d| = 0.25 <= lp -> 1 - (0.0625 + 0.0625)/0.5 = 0.75
  // node 3: |d| = 0.75, 1 - lp < 0.75 -> (1.25 - 0.75)^2 / 1 = 0.25 ; node 1: |d| = 1.25 -> 0
  REQUIRE(UGIMP::eval(2.25, 0.25, w, dw) == 2);
  CHECK(w[0] == Approx(0.75));
  CHECK(w[1] == Approx(0.25));
  CHECK(w[2] == Approx(0.0).margin(1e-15));
}

// The D-axis stencil: weights sum to one and gradients to zero, it reproduces linear fields
// (sum_i w_i x_i = x_p, sum_i x_i g_i^T = I), and every weight and gradient is bitwise the
// product in axis order of the 1D values, in 2D and 3D.
template <class S, int D>
void check_stencil(double lp) {
  std::mt19937_64 rng(777);
  std::uniform_real_distribution<double> U(2.0, 50.0);
  for (int k = 0; k < 2000; ++k) {
    Vec<D> x;
    for (int d = 0; d < D; ++d) x[d] = U(rng);
    const Stencil<S, D> st(x, lp);
    double sw = 0, sg[D] = {}, sx[D] = {}, sxg[D][D] = {};
    st.for_each([&](const Idx<D>& a, int) {
      const double w = st.weight(a);
      double prod = st.w[0][a[0]];
      for (int d = 1; d < D; ++d) prod = prod * st.w[d][a[d]];
      REQUIRE(w == prod);
      sw += w;
      for (int d = 0; d < D; ++d) {
        const double g = st.grad(a, d);
        double gp = d == 0 ? st.dw[0][a[0]] : st.w[0][a[0]];
        for (int e = 1; e < D; ++e) gp = gp * (e == d ? st.dw[e][a[e]] : st.w[e][a[e]]);
        REQUIRE(g == gp);
        sg[d] += g;
        sx[d] += w * (st.base[d] + a[d]);
        for (int e = 0; e < D; ++e) sxg[d][e] += (st.base[d] + a[d]) * st.grad(a, e);
      }
    });
    REQUIRE(sw == Approx(1.0).margin(1e-13));
    for (int d = 0; d < D; ++d) {
      REQUIRE(sg[d] == Approx(0.0).margin(1e-12));
      REQUIRE(sx[d] == Approx(x[d]).epsilon(1e-13));
      for (int e = 0; e < D; ++e) REQUIRE(sxg[d][e] == Approx(d == e ? 1.0 : 0.0).margin(1e-11));
      REQUIRE(st.offset(Stencil<S, D>::digits(0), d) == (st.base[d] - x[d]));
    }
  }
}

TEST_CASE("stencil: partition of unity, gradients, linear reproduction in 2D and 3D", "[shape]") {
  check_stencil<Linear, 2>(0.0);
  check_stencil<UGIMP, 2>(0.25);
  check_stencil<QuadraticBSpline, 2>(0.0);
  check_stencil<CubicBSpline, 2>(0.0);
  check_stencil<Linear, 3>(0.0);
  check_stencil<UGIMP, 3>(0.25);
  check_stencil<QuadraticBSpline, 3>(0.0);
  check_stencil<CubicBSpline, 3>(0.0);
}

TEST_CASE("symmetric and spin parts: component order and values", "[shape]") {
  STATIC_REQUIRE(sym_index(2, 0, 1) == 2);
  STATIC_REQUIRE(sym_index(3, 0, 1) == 3);
  STATIC_REQUIRE(sym_index(3, 2, 0) == 4);
  STATIC_REQUIRE(sym_index(3, 1, 2) == 5);
  for (int D : {2, 3})
    for (int k = 0; k < sym_size(D); ++k) REQUIRE(sym_index(D, sym_row(D, k), sym_col(D, k)) == k);
  Mat<3> L{{{1, 2, 3}, {4, 5, 6}, {7, 8, 9}}};
  const Sym<3> s = sym_part(L);
  const Spin<3> w = spin_part(L);
  REQUIRE(s[0] == 1);
  REQUIRE(s[2] == 9);
  REQUIRE(s[3] == 3);  // (2 + 4) / 2
  REQUIRE(s[4] == 5);  // (3 + 7) / 2
  REQUIRE(s[5] == 7);  // (6 + 8) / 2
  REQUIRE(w[0] == -1);
  REQUIRE(w[1] == -2);
  REQUIRE(w[2] == -1);
  REQUIRE(s.trace() == 15);
}
