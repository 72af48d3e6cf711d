#include "grid_update.hpp"

#include <algorithm>
#include <cmath>

namespace smpm::kern {

namespace {

// Column range of the box's nodes that carry state: periodic x keeps 0..nx-1 (ghosts are copies).
inline void real_columns(const GridGeom& g, const NodeBox& b, int& i0, int& i1) {
  i0 = std::max(b.i0, g.periodic_x ? 0 : -g.pad);
  i1 = std::min(b.i1, g.periodic_x ? g.nx - 1 : g.nx + g.pad);
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

void grid_update(const GridGeom& g, const NodeBox& b, const GridView& G, const GridUpdateParams& q,
                 double* row_force) {
  int i0, i1;
  real_columns(g, b, i0, i1);
  const double inv_dt = q.dt > 0.0 ? 1.0 / q.dt : 0.0;
  if (row_force) std::fill(row_force, row_force + kRowSlots * static_cast<std::size_t>(g.sy()), 0.0);
#pragma omp parallel for schedule(static)
  for (int j = b.j0; j <= b.j1; ++j) {
    const int r = j + g.pad;
    double rf[kRowSlots] = {0, 0, 0, 0};
    for (int i = i0; i <= i1; ++i) {
      const std::size_t n = g.node(i, j);
      const double m = G.m[n];
      if (m <= 0.0) {
        G.vx[n] = G.vy[n] = 0.0;
        if (q.flip) G.dvx[n] = G.dvy[n] = 0.0;
        if (q.scatter_velocity) G.px[n] = G.py[n] = 0.0;
        continue;
      }
      const double inv_m = 1.0 / m;
      double ux = G.px[n] * inv_m, uy = G.py[n] * inv_m;  // old velocity
      if (q.scatter_velocity) {
        G.px[n] = ux;
        G.py[n] = uy;
      }
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

void grid_velocity_from_momentum(const GridGeom& g, const NodeBox& b, const GridView& G, const GridUpdateParams& q) {
  int i0, i1;
  real_columns(g, b, i0, i1);
#pragma omp parallel for schedule(static)
  for (int j = b.j0; j <= b.j1; ++j) {
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

void clear_grid(const GridGeom& g, const NodeBox& b, const GridView& G, bool all) {
#pragma omp parallel for schedule(static) collapse(2)
  for (int f = 0; f < G.fields; ++f)
    for (int j = b.j0; j <= b.j1; ++j) {
      const std::size_t n0 = g.node(b.i0, j) + f * G.fstride, n1 = n0 + (b.i1 - b.i0 + 1);
      for (std::size_t n = n0; n < n1; ++n) {
        G.px[n] = 0.0;
        G.py[n] = 0.0;
        if (all) {
          G.m[n] = 0.0;
          G.fx[n] = 0.0;
          G.fy[n] = 0.0;
          if (G.gmx) G.gmx[n] = G.gmy[n] = G.vol[n] = 0.0;
        }
      }
    }
}

void grid_contact(const GridGeom& g, const NodeBox& box, const GridView& G, const GridUpdateParams& q,
                  const ContactParams& c) {
  int i0, i1;
  real_columns(g, box, i0, i1);
  const std::size_t fs = G.fstride;
  const double vmin = (c.volume_fraction - 1e-9) * g.h * g.h;  // a full node passes despite round-off
#pragma omp parallel for schedule(static)
  for (int j = box.j0; j <= box.j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      const std::size_t a = g.node(i, j), b = a + fs;
      const double m0 = G.m[a], m1 = G.m[b];
      if (m0 <= q.mass_eps || m1 <= q.mass_eps || G.vol[a] + G.vol[b] < vmin) continue;
      // sum_p m_p grad N_i(x_p) points out of each body (mass grows the other way)
      double nx = G.gmx[b] - G.gmx[a], ny = G.gmy[b] - G.gmy[a];
      const double len = std::sqrt(nx * nx + ny * ny);
      if (!(len > 0.0)) continue;
      nx /= len;
      ny /= len;
      const double M = m0 + m1;
      const double cx = (m0 * G.vx[a] + m1 * G.vx[b]) / M, cy = (m0 * G.vy[a] + m1 * G.vy[b]) / M;
      const double dx = G.vx[a] - cx, dy = G.vy[a] - cy;
      const double dn = dx * nx + dy * ny;
      if (dn >= 0.0) continue;  // separating: no contact force
      const double tx = dx - dn * nx, ty = dy - dn * ny, tl = std::sqrt(tx * tx + ty * ty);
      double ux, uy;  // corrected velocity of field 0
      if (tl <= c.friction * -dn) {
        ux = cx;
        uy = cy;
      } else {
        const double f = c.friction * -dn / tl;
        ux = G.vx[a] - dn * nx - f * tx;
        uy = G.vy[a] - dn * ny - f * ty;
      }
      double wx = (M * cx - m0 * ux) / m1, wy = (M * cy - m0 * uy) / m1;
      double scratch[4] = {0, 0, 0, 0};
      constrain(g, q.walls, i, j, ux, uy, scratch);
      constrain(g, q.walls, i, j, wx, wy, scratch);
      if (q.flip) {
        G.dvx[a] += ux - G.vx[a];
        G.dvy[a] += uy - G.vy[a];
        G.dvx[b] += wx - G.vx[b];
        G.dvy[b] += wy - G.vy[b];
      }
      G.vx[a] = ux;
      G.vy[a] = uy;
      G.vx[b] = wx;
      G.vy[b] = wy;
    }
  }
}

void fold_periodic(const GridGeom& g, const NodeBox& b, double* const* arrays, int count) {
  if (!g.periodic_x) return;
#pragma omp parallel for schedule(static)
  for (int j = b.j0; j <= b.j1; ++j) {
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

void fill_periodic_ghosts(const GridGeom& g, const NodeBox& b, double* const* arrays, int count) {
  if (!g.periodic_x) return;
#pragma omp parallel for schedule(static)
  for (int j = b.j0; j <= b.j1; ++j) {
    for (int k = 0; k < count; ++k) {
      double* a = arrays[k];
      for (int i = -g.pad; i < 0; ++i) a[g.node(i, j)] = a[g.node(i + g.nx, j)];
      for (int i = g.nx; i <= g.nx + g.pad; ++i) a[g.node(i, j)] = a[g.node(i - g.nx, j)];
    }
  }
}

}  // namespace smpm::kern
