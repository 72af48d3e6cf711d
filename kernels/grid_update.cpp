#include "grid_update.hpp"

#include <algorithm>

namespace smpm::kern {

namespace {

// Column range of nodes that carry state: periodic x keeps 0..nx-1 (ghosts are copies).
inline void real_columns(const GridGeom& g, int& i0, int& i1) {
  if (g.periodic_x) {
    i0 = 0;
    i1 = g.nx - 1;
  } else {
    i0 = -g.pad;
    i1 = g.nx + g.pad;
  }
}

inline void apply_wall(Wall w, double& vn, double& vt) {
  if (w == Wall::Slip) vn = 0.0;
  else if (w == Wall::NoSlip) vn = vt = 0.0;
}

// Applies all walls to node (i, j). Returns the velocity change due to the walls in fvx/fvy
// split by wall: out[0] left (x), out[1] right (x), out[2] bottom (y), out[3] top (y).
inline void constrain(const GridGeom& g, const Walls& W, int i, int j, double& vx, double& vy,
                      double* dv) {
  if (!g.periodic_x) {
    if (W.left != Wall::None && i <= 0) {
      const double b = vx;
      apply_wall(W.left, vx, vy);
      dv[0] += vx - b;
    }
    if (W.right != Wall::None && i >= g.nx) {
      const double b = vx;
      apply_wall(W.right, vx, vy);
      dv[1] += vx - b;
    }
  }
  if (W.bottom != Wall::None && j <= 0) {
    const double b = vy;
    apply_wall(W.bottom, vy, vx);
    dv[2] += vy - b;
  }
  if (W.top != Wall::None && j >= g.ny) {
    const double b = vy;
    apply_wall(W.top, vy, vx);
    dv[3] += vy - b;
  }
}

}  // namespace

void grid_update(const GridGeom& g, const GridView& G, const GridUpdateParams& q, double* row_force) {
  int i0, i1;
  real_columns(g, i0, i1);
  const int sy = g.sy();
  const double inv_dt = q.dt > 0.0 ? 1.0 / q.dt : 0.0;
#pragma omp parallel for schedule(static)
  for (int r = 0; r < sy; ++r) {
    const int j = r - g.pad;
    double rf[kRowSlots] = {0, 0, 0, 0};
    for (int i = i0; i <= i1; ++i) {
      const std::size_t n = g.node(i, j);
      const double m = G.m[n];
      if (m <= 0.0) {
        G.vx[n] = G.vy[n] = 0.0;
        if (q.flip) G.dvx[n] = G.dvy[n] = 0.0;
        continue;
      }
      const double inv_m = 1.0 / m;
      double ux = G.px[n] * inv_m, uy = G.py[n] * inv_m;  // old velocity
      const double acc = m > q.mass_eps ? q.dt : 0.0;
      double vx = ux + acc * (G.fx[n] * inv_m + q.gravity_x);
      double vy = uy + acc * (G.fy[n] * inv_m + q.gravity_y);
      double scratch[4] = {0, 0, 0, 0};
      constrain(g, q.walls, i, j, ux, uy, scratch);
      double dv[4] = {0, 0, 0, 0};
      constrain(g, q.walls, i, j, vx, vy, dv);
      for (int k = 0; k < 4; ++k) rf[k] += m * dv[k] * inv_dt;
      G.vx[n] = vx;
      G.vy[n] = vy;
      if (q.flip) {
        G.dvx[n] = vx - ux;
        G.dvy[n] = vy - uy;
      }
    }
    if (row_force)
      for (int k = 0; k < kRowSlots; ++k) row_force[kRowSlots * r + k] = rf[k];
  }
}

void grid_velocity_from_momentum(const GridGeom& g, const GridView& G, const GridUpdateParams& q) {
  int i0, i1;
  real_columns(g, i0, i1);
  const int sy = g.sy();
#pragma omp parallel for schedule(static)
  for (int r = 0; r < sy; ++r) {
    const int j = r - g.pad;
    for (int i = i0; i <= i1; ++i) {
      const std::size_t n = g.node(i, j);
      const double m = G.m[n];
      if (m <= 0.0) {
        G.vx[n] = G.vy[n] = 0.0;
        continue;
      }
      double vx = G.px[n] / m, vy = G.py[n] / m;
      double dv[4] = {0, 0, 0, 0};
      constrain(g, q.walls, i, j, vx, vy, dv);
      G.vx[n] = vx;
      G.vy[n] = vy;
    }
  }
}

void clear_grid(const GridGeom& g, const GridView& G, bool all) {
  const std::size_t nn = g.num_nodes();
#pragma omp parallel for schedule(static)
  for (std::size_t n = 0; n < nn; ++n) {
    G.px[n] = 0.0;
    G.py[n] = 0.0;
    if (all) {
      G.m[n] = 0.0;
      G.fx[n] = 0.0;
      G.fy[n] = 0.0;
    }
  }
}

void fold_periodic(const GridGeom& g, double* const* arrays, int count) {
  if (!g.periodic_x) return;
  const int sy = g.sy();
#pragma omp parallel for schedule(static)
  for (int r = 0; r < sy; ++r) {
    const int j = r - g.pad;
    for (int k = 0; k < count; ++k) {
      double* a = arrays[k];
      for (int i = -g.pad; i < 0; ++i) {
        a[g.node(i + g.nx, j)] += a[g.node(i, j)];
        a[g.node(i, j)] = 0.0;
      }
      for (int i = g.nx; i <= g.nx + g.pad; ++i) {
        a[g.node(i - g.nx, j)] += a[g.node(i, j)];
        a[g.node(i, j)] = 0.0;
      }
    }
  }
}

void fill_periodic_ghosts(const GridGeom& g, double* const* arrays, int count) {
  if (!g.periodic_x) return;
  const int sy = g.sy();
#pragma omp parallel for schedule(static)
  for (int r = 0; r < sy; ++r) {
    const int j = r - g.pad;
    for (int k = 0; k < count; ++k) {
      double* a = arrays[k];
      for (int i = -g.pad; i < 0; ++i) a[g.node(i, j)] = a[g.node(i + g.nx, j)];
      for (int i = g.nx; i <= g.nx + g.pad; ++i) a[g.node(i, j)] = a[g.node(i - g.nx, j)];
    }
  }
}

}  // namespace smpm::kern
