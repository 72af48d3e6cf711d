// The passes after a void has closed (kernels/void_closure.hpp): merge_closed_faces (a void-face
// point whose nodes are all full, one welded, joins field 0) and close_cracks (a fractured point
// among compressed cell-mates: its group shares one density, volume conserved, energy untouched).
#include <catch2/catch.hpp>

#include <array>
#include <omp.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "kernels/constitutive.hpp"
#include "kernels/shape.hpp"
#include "kernels/void_closure.hpp"
#include "tests/merge_check.hpp"

using namespace smpm::kern;

namespace {
// the position arrays of merge_closed_faces
std::array<const double*, kDim> xy(const double* x, const double* y) { return {x, y}; }
}  // namespace

namespace {

const MieGruneisenEos kAl = MieGruneisenEos::make(2700.0, 5350.0, 1.34, 2.0);
constexpr double kPmin = -1e9;  // spall strength 1 GPa

struct Pts {
  std::vector<double> m, V, p, s[3], q, e, v[2];  // s: xx, yy, xy
  std::vector<std::uint8_t> body, field;
  void add(double rho, double e_, std::uint8_t f, double mass = 1e-8) {
    m.push_back(mass);
    V.push_back(mass / rho);
    const double P = kAl.pressure(rho, e_);
    const bool fr = P < kPmin;
    p.push_back(fr ? 0.0 : P);
    s[0].push_back(fr ? 0.0 : 1e7);
    s[1].push_back(fr ? 0.0 : -1e7);
    s[2].push_back(fr ? 0.0 : 2e6);
    q.push_back(fr ? 0.0 : 1e6);
    e.push_back(e_);
    v[0].push_back(1.0);
    v[1].push_back(-2.0);
    body.push_back(0);
    field.push_back(f);
  }
  CrackArrays arrays() {
    return {m.data(), V.data(), p.data(), {s[0].data(), s[1].data(), s[2].data()}, q.data(), e.data(),
            {v[0].data(), v[1].data()}, body.data(), field.data(), nullptr};
  }
};

CrackResult run_close(Pts& P, const std::vector<std::uint32_t>& cell_start) {
  std::vector<std::uint32_t> order(P.m.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
  const CrackParams prm{kPmin, 1350.0};
  return close_cracks(P.arrays(), order.data(), cell_start.data(), cell_start.size() - 1, prm, kAl,
                      [&P](double rho, double, std::uint32_t i) {
                        return std::sqrt(kAl.bulk_modulus(rho, 0.0) / rho) + std::hypot(P.v[0][i], P.v[1][i]);
                      });
}

}  // namespace

TEST_CASE("close_cracks: a fractured point among compressed cell-mates shares their density", "[unit][porous]") {
  Pts P;
  // cell 0: three compressed points and one fractured (expanded, hot), one field
  for (int k = 0; k < 3; ++k) P.add(2760.0, 5e5, 0);
  P.add(2350.0, 6e5, 0);
  // cell 1: a spall plane: a fractured point among points in mild tension, none compressed
  P.add(2350.0, 6e5, 0);
  P.add(2690.0, 0.0, 0);
  // cell 2: compressed points only
  P.add(2760.0, 5e5, 0);
  P.add(2770.0, 5e5, 0);
  // cell 3: the fractured point in field 1, the compressed ones in field 0: different groups
  P.add(2760.0, 5e5, 0);
  P.add(2350.0, 6e5, 1);
  const std::vector<std::uint32_t> cell_start{0, 4, 6, 8, 10};
  REQUIRE(P.p[3] == 0.0);
  const Pts before = P;
  const CrackResult r = run_close(P, cell_start);
  CHECK(r.changed == 4);
  CHECK(r.max_speed > 0.0);
  // cell 0: the group's volume is conserved and every point has its density
  double V0 = 0.0, V1 = 0.0, M = 0.0;
  for (int i = 0; i < 4; ++i) V0 += before.V[i], V1 += P.V[i], M += P.m[i];
  CHECK(V1 == Approx(V0).epsilon(1e-14));
  for (int i = 0; i < 4; ++i) {
    const double rho = P.m[i] / P.V[i];
    CHECK(rho == Approx(M / V0).epsilon(1e-14));
    CHECK(P.e[i] == before.e[i]);  // no work: the energy is untouched
    CHECK(P.p[i] == Approx(kAl.pressure(rho, P.e[i])).epsilon(1e-12));
    CHECK(P.p[i] > 0.0);  // the crack closed: it carries pressure again
  }
  CHECK(P.s[0][3] == 0.0);        // the formerly fractured point starts from zero deviator
  CHECK(P.s[0][0] == before.s[0][0]);  // the others keep theirs
  CHECK(P.q[0] == before.q[0]);
  // cells 1 to 3 untouched
  for (std::size_t i = 4; i < P.m.size(); ++i) {
    CHECK(P.V[i] == before.V[i]);
    CHECK(P.p[i] == before.p[i]);
  }
}

TEST_CASE("close_cracks: a group still in tension past the cutoff stays fractured", "[unit][porous]") {
  Pts P;
  P.add(2710.0, 0.0, 0);  // barely compressed
  P.add(2200.0, 0.0, 0);  // deeply cracked
  P.add(2200.0, 0.0, 0);
  const double sxx0 = P.s[0][0];
  REQUIRE(sxx0 != 0.0);
  const CrackResult r = run_close(P, {0, 3});
  CHECK(r.changed == 3);
  for (int i = 0; i < 3; ++i) {
    CHECK(P.p[i] == 0.0);
    CHECK(P.s[0][i] == 0.0);
    CHECK(P.q[i] == 0.0);
  }
}

TEST_CASE("close_cracks: the same for any thread count", "[unit][porous][determinism]") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> R(2250.0, 2850.0), E(0.0, 8e5);
  std::uniform_int_distribution<int> F(0, 1), C(1, 6);
  Pts P;
  std::vector<std::uint32_t> cell_start{0};
  for (int c = 0; c < 5000; ++c) {
    const int n = C(rng);
    for (int k = 0; k < n; ++k) P.add(R(rng), E(rng), static_cast<std::uint8_t>(F(rng)), 1e-8 * (1.0 + 0.1 * k));
    cell_start.push_back(static_cast<std::uint32_t>(P.m.size()));
  }
  Pts a = P, b = P;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const CrackResult ra = run_close(a, cell_start);
  omp_set_num_threads(2);
  const CrackResult rb = run_close(b, cell_start);
  omp_set_num_threads(threads);
  CHECK(ra.changed > 100);
  CHECK(ra.changed == rb.changed);
  CHECK(ra.max_speed == rb.max_speed);
  CHECK((a.V == b.V));
  CHECK((a.p == b.p));
  CHECK((a.s[0] == b.s[0]));
}

TEST_CASE("merge_closed_faces: a point joins field 0 where all its nodes are full and one is welded", "[unit][porous]") {
  GridGeom g;
  g.h = 1e-6;
  g.n[0] = 8;
  g.n[1] = 8;
  g.wrap[0] = true;
  const std::size_t nn = g.num_nodes();
  std::vector<double> m(2 * nn, 0.0), vol(2 * nn, 0.0);
  // field 0 fills the grid, field 1 has a sliver of mass everywhere: every node full and welded
  for (std::size_t k = 0; k < nn; ++k) {
    m[k] = 1.0, vol[k] = 0.95 * g.h * g.h;
    m[k + nn] = 1e-3, vol[k + nn] = 0.0;
  }
  const GridView G = smpm::test::merge_grid(m, vol, nn, 2);
  const MergeParams q = smpm::test::merge_params();
  std::vector<std::uint8_t> state(3 * nn, 7);  // node states, three images: every real node is written
  // points (in cells): 0 anywhere -> merges; 1 next to an unfilled node -> stays; 2 in field 0;
  // 3 where field 1 is absent from every node of its support -> stays; 4 across the periodic seam
  const std::vector<double> x{3.5e-6, 5.5e-6, 3.5e-6, 1.5e-6, 0.1e-6};
  const std::vector<double> y{3.5e-6, 3.5e-6, 5.5e-6, 6.5e-6, 1.5e-6};
  vol[g.node(6, 3)] = 0.5 * g.h * g.h;  // in point 1's quadratic support, not in point 0's
  for (int j = 5; j <= 8; ++j)
    for (int i = 0; i <= 3; ++i) m[g.node(i, j) + nn] = 0.0;  // no field 1 near point 3
  std::vector<std::uint8_t> field{1, 1, 0, 1, 1};
  const std::size_t merged = merge_closed_faces<QuadraticBSpline>(g, g.all_nodes(), G, xy(x.data(), y.data()).data(), field.data(), 5, q, state.data());
  CHECK(merged == 2);
  CHECK(int(field[0]) == 0);
  CHECK(int(field[1]) == 1);
  CHECK(int(field[2]) == 0);
  CHECK(int(field[3]) == 1);
  CHECK(int(field[4]) == 0);
  // an unfilled node across the periodic seam keeps point 4 in field 1
  std::vector<std::uint8_t> f2{1};
  vol[g.node(g.n[0] - 1, 1)] = 0.0;
  CHECK(merge_closed_faces<QuadraticBSpline>(g, g.all_nodes(), G, xy(&x[4], &y[4]).data(), f2.data(), 1, q, state.data()) == 0);
  CHECK(int(f2[0]) == 1);
}

TEST_CASE("merge_closed_faces: the blocks' states give each point what its nodes one by one give", "[unit][porous]") {
  smpm::test::check_merge_against_nodes<Linear>(1);
  smpm::test::check_merge_against_nodes<UGIMP>(2);
  smpm::test::check_merge_against_nodes<QuadraticBSpline>(3);
  smpm::test::check_merge_against_nodes<CubicBSpline>(4);
}

TEST_CASE("merge_closed_faces, four fields: any field but 0 joins field 0; full counts all fields", "[unit][porous]") {
  GridGeom g;
  g.h = 1e-6;
  g.n[0] = 8;
  g.n[1] = 8;
  const std::size_t nn = g.num_nodes();
  std::vector<double> m(4 * nn, 0.0), vol(4 * nn, 0.0);
  // fields 2 and 3 fill the grid between them (0.5 + 0.45 of a cell), field 0 and 1 absent
  for (std::size_t k = 0; k < nn; ++k) {
    m[k + 2 * nn] = 1.0, vol[k + 2 * nn] = 0.5 * g.h * g.h;
    m[k + 3 * nn] = 1.0, vol[k + 3 * nn] = 0.45 * g.h * g.h;
  }
  const GridView G = smpm::test::merge_grid(m, vol, nn, 4);
  const MergeParams q = smpm::test::merge_params();
  std::vector<std::uint8_t> state(3 * nn, 7);
  const std::vector<double> x{3.5e-6, 3.5e-6, 3.5e-6}, y{3.5e-6, 3.5e-6, 3.5e-6};
  std::vector<std::uint8_t> field{3, 2, 1};
  CHECK(merge_closed_faces<QuadraticBSpline>(g, g.all_nodes(), G, xy(x.data(), y.data()).data(), field.data(), 3, q, state.data()) == 3);
  CHECK(int(field[0]) == 0);
  CHECK(int(field[1]) == 0);
  CHECK(int(field[2]) == 0);
  // field 3 alone fills no node (0.45 of a cell): the merge needs the fields together
  for (std::size_t k = 0; k < nn; ++k) vol[k + 2 * nn] = 0.4 * g.h * g.h;
  std::vector<std::uint8_t> f3{3};
  CHECK(merge_closed_faces<QuadraticBSpline>(g, g.all_nodes(), G, xy(x.data(), y.data()).data(), f3.data(), 1, q, state.data()) == 0);
  CHECK(int(f3[0]) == 3);
}
