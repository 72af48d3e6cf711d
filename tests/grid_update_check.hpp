// kern::grid_update and kern::grid_velocity_from_momentum against the update written out node by
// node (kernels/grid_update.hpp), for the engine's dimension: empty nodes, nodes at or below
// mass_eps (no forces), a wall of another kind on each face of every axis that is not periodic
// (the ghosts beyond a wall included; a periodic axis's ghosts are not updated). The kernels
// take the nodes off the walls as vectorized runs, the others one by one; the results must be
// those of the plain loop bit for bit: velocities, FLIP increments, the scatter velocity, and
// the walls' reactions and removed energy summed along each line in node order.
#pragma once
#include <catch2/catch.hpp>

#include <random>
#include <vector>

#include "engine/grid.hpp"
#include "kernels/grid_update.hpp"

namespace SMPM_NS::test {

// The walls of check_grid_update, and the velocity w of node i with them applied in the kernel's
// order (axis by axis, the low wall first); dv[2 d + s] takes the change of w[d] at wall s of axis d.
inline void apply_walls(const kern::GridGeom& g, const kern::Walls& W, const kern::Idx<kern::kDim>& i, double* w,
                        double* dv) {
  using kern::Wall;
  for (int d = 0; d < kern::kDim; ++d)
    for (int s = 0; s < 2 && !g.periodic(d); ++s) {
      const Wall wall = s ? W.hi[d] : W.lo[d];
      if (wall == Wall::None || (s ? i[d] < g.cells(d) : i[d] > 0)) continue;
      const double before = w[d];
      for (int e = 0; e < kern::kDim; ++e)
        if (e == d || wall == Wall::NoSlip) w[e] = 0.0;
      dv[2 * d + s] += w[d] - before;
    }
}

inline void check_grid_update(const kern::GridGeom& g) {
  using namespace kern;
  constexpr int D = kDim;
  Grid A(g, true);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (std::size_t n = 0; n < g.num_nodes(); ++n) {
    const int kind = static_cast<int>(n % 7);
    A.m[n] = kind == 0 ? 0.0 : kind == 1 ? 0.01 * (1.0 + U(rng)) : 1.0 + 0.5 * U(rng);
    for (int d = 0; d < D; ++d) {
      A.p[d][n] = U(rng);
      A.f[d][n] = 100.0 * U(rng);
    }
  }
  const Grid A0 = A;
  GridUpdateParams q;
  q.dt = 1e-3;
  for (int d = 0; d < D; ++d) {
    q.gravity[d] = d == 1 ? -9.81 : 0.3 * (d + 1);
    q.walls.lo[d] = d % 2 ? Wall::Slip : Wall::NoSlip;
    q.walls.hi[d] = d % 2 ? Wall::NoSlip : Wall::Slip;
  }
  q.mass_eps = 0.02;  // the nodes of kind 1 at or below it
  q.flip = true;
  q.scatter_velocity = true;
  std::vector<double> rf(kRowSlots * static_cast<std::size_t>(g.num_lines()), 7.0);
  grid_update(g, g.all_nodes(), A.view(), q, rf.data());
  Grid B = A0;
  grid_velocity_from_momentum(g, g.all_nodes(), B.view(), q);
  const double inv_dt = 1.0 / q.dt;
  const NodeBox box = real_nodes(g, g.all_nodes());
  for (int r = 0; r < box.lines(); ++r) {
    Idx<D> i = box.line_start(r);
    double row[kRowSlots] = {};
    for (i[0] = box.lo[0]; i[0] <= box.hi[0]; ++i[0]) {
      const std::size_t n = g.node(i);
      const double m = A0.m[n];
      double u[D] = {}, v[D] = {}, du[D] = {}, vm[D] = {};
      if (m > 0.0) {
        const double inv_m = 1.0 / m, acc = m > q.mass_eps ? q.dt : 0.0;
        for (int d = 0; d < D; ++d) u[d] = A0.p[d][n] * inv_m;
        for (int d = 0; d < D; ++d) v[d] = u[d] + acc * (A0.f[d][n] * inv_m + q.gravity[d]);
        double lost = u[0] * u[0];
        for (int d = 1; d < D; ++d) lost += u[d] * u[d];
        double dv[2 * D] = {}, scratch[2 * D] = {};
        apply_walls(g, q.walls, i, u, scratch);
        apply_walls(g, q.walls, i, v, dv);
        for (int d = 0; d < D; ++d) lost -= u[d] * u[d];
        row[2 * D] += 0.5 * m * lost;
        for (int k = 0; k < 2 * D; ++k) row[k] += m * dv[k] * inv_dt;
        for (int d = 0; d < D; ++d) du[d] = v[d] - u[d];
        for (int d = 0; d < D; ++d) vm[d] = A0.p[d][n] / m;  // MUSL: v = p / m, the walls, no forces
        apply_walls(g, q.walls, i, vm, scratch);
      }
      for (int d = 0; d < D; ++d) {
        INFO("line " << r << ", node " << i[0] << ", axis " << d);
        REQUIRE(A.v[d][n] == v[d]);
        REQUIRE(A.dv[d][n] == du[d]);
        REQUIRE(A.p[d][n] == u[d]);
        REQUIRE(B.v[d][n] == vm[d]);
      }
    }
    i[0] = box.lo[0];
    const std::size_t line = static_cast<std::size_t>(g.line(i));
    for (int k = 0; k < kRowSlots; ++k) REQUIRE(rf[kRowSlots * line + k] == row[k]);
  }
}

}  // namespace SMPM_NS::test
