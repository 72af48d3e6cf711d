#include "grid_update.hpp"

#include <algorithm>
#include <cmath>

namespace smpm::kern {

namespace {

inline void apply_wall(Wall w, double& vn, double& vt) {
  if (w == Wall::Slip) vn = 0.0;
  else if (w == Wall::NoSlip) vn = vt = 0.0;
}

// Applies all walls to the velocity (vx, vy) of node (i, j) in place and adds the change each
// wall made to dv: dv[0] left (x), dv[1] right (x), dv[2] bottom (y), dv[3] top (y).
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
    double rf[kRowSlots] = {0, 0, 0, 0, 0};
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
      const double acc = m > q.mass_eps ? q.dt : 0.0;
      double vx = ux + acc * (G.fx[n] * inv_m + q.gravity_x);
      double vy = uy + acc * (G.fy[n] * inv_m + q.gravity_y);
      double scratch[4] = {0, 0, 0, 0};
      const double u2 = ux * ux + uy * uy;
      constrain(g, q.walls, i, j, ux, uy, scratch);
      rf[4] += 0.5 * m * (u2 - ux * ux - uy * uy);
      if (q.scatter_velocity) {  // after the walls: see GridUpdateParams
        G.px[n] = ux;
        G.py[n] = uy;
      }
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
  if (b.empty()) return;
  double* const arrays[] = {G.px, G.py, G.m, G.fx, G.fy, G.vol, G.gmx, G.gmy};
  const int count = !all ? 2 : G.gmx ? 8 : G.vol ? 6 : 5;  // two-body contact, a weld, one field
  const std::size_t len = static_cast<std::size_t>(b.i1 - b.i0 + 1);
#pragma omp parallel for schedule(static) collapse(2)
  for (int f = 0; f < G.fields; ++f)
    for (int j = b.j0; j <= b.j1; ++j) {
      const std::size_t n0 = g.node(b.i0, j) + f * G.fstride;
      for (int k = 0; k < count; ++k) std::fill(arrays[k] + n0, arrays[k] + n0 + len, 0.0);
    }
}

namespace {

// The weld of any number of velocity fields with APIC's scatter velocity (q.scatter_velocity):
// at a node where at least two fields hold mass and all fields together fill vmin, every field
// present takes the centre-of-mass velocity, after the forces and before them (p / m in px, py).
// The heating gather's scatter loss then counts 1/2 m_f |u_f - u_cm|^2 per field, together the
// weld's loss (for two fields 1/2 mu |u_0 - u_1|^2), and the mid-step L is the single field's:
// no contact heat (heat = 0).
void weld_fields(const GridGeom& g, const NodeBox& box, const GridView& G, const GridUpdateParams& q, double vmin,
                 double* row_loss) {
  int i0, i1;
  real_columns(g, box, i0, i1);
  const std::size_t fs = G.fstride;
  const int K = G.fields;
#pragma omp parallel for schedule(static)
  for (int j = box.j0; j <= box.j1; ++j) {
    double row = 0.0;
    for (int i = i0; i <= i1; ++i) {
      const std::size_t a = g.node(i, j);
      double M = 0.0, V = 0.0, mvx = 0.0, mvy = 0.0, mpx = 0.0, mpy = 0.0;
      int present = 0;
      for (int f = 0; f < K; ++f) {
        const std::size_t k = a + f * fs;
        G.heat[k] = 0.0;
        V += G.vol[k];
        const double m = G.m[k];
        if (m <= q.mass_eps) continue;
        ++present;
        M += m;
        mvx += m * G.vx[k];
        mvy += m * G.vy[k];
        mpx += m * G.px[k];
        mpy += m * G.py[k];
      }
      if (present < 2 || V < vmin) continue;
      const double cx = mvx / M, cy = mvy / M, px = mpx / M, py = mpy / M;
      for (int f = 0; f < K; ++f) {
        const std::size_t k = a + f * fs;
        if (G.m[k] <= q.mass_eps) continue;
        const double rx = G.px[k] - px, ry = G.py[k] - py;
        row += 0.5 * G.m[k] * (rx * rx + ry * ry);
        G.px[k] = px;
        G.py[k] = py;
        G.vx[k] = cx;  // (scatter_velocity means APIC: no FLIP increments)
        G.vy[k] = cy;
      }
    }
    if (row_loss) row_loss[j + g.pad] = row;
  }
}

}  // namespace

void grid_contact(const GridGeom& g, const NodeBox& box, const GridView& G, const GridUpdateParams& q,
                  const ContactParams& c, double* row_loss) {
  const double vmin = (c.volume_fraction - 1e-9) * g.h * g.h;  // a full node passes despite round-off
  if (row_loss) std::fill(row_loss, row_loss + g.sy(), 0.0);
  if (c.weld && q.scatter_velocity) {
    weld_fields(g, box, G, q, vmin, row_loss);
    return;
  }
  int i0, i1;
  real_columns(g, box, i0, i1);
  const std::size_t fs = G.fstride;
#pragma omp parallel for schedule(static)
  for (int j = box.j0; j <= box.j1; ++j) {
    double row = 0.0;
    for (int i = i0; i <= i1; ++i) {
      const std::size_t a = g.node(i, j), b = a + fs;
      G.heat[a] = G.heat[b] = 0.0;
      const double m0 = G.m[a], m1 = G.m[b];
      if (m0 <= q.mass_eps || m1 <= q.mass_eps || G.vol[a] + G.vol[b] < vmin) continue;
      const double M = m0 + m1;
      const double cx = (m0 * G.vx[a] + m1 * G.vx[b]) / M, cy = (m0 * G.vy[a] + m1 * G.vy[b]) / M;
      double ux, uy;  // corrected velocity of field 0
      if (c.weld) {  // FLIP's (APIC's: weld_fields)
        ux = cx;
        uy = cy;
      } else {
        // sum_p m_p grad N_i(x_p) points out of each body (mass grows the other way)
        double nx = G.gmx[b] - G.gmx[a], ny = G.gmy[b] - G.gmy[a];
        const double len = std::sqrt(nx * nx + ny * ny);
        if (!(len > 0.0)) continue;
        nx /= len;
        ny /= len;
        const double dx = G.vx[a] - cx, dy = G.vy[a] - cy;
        const double dn = dx * nx + dy * ny;
        if (dn >= 0.0) continue;  // separating: no contact force
        const double tx = dx - dn * nx, ty = dy - dn * ny, tl = std::sqrt(tx * tx + ty * ty);
        if (tl <= c.friction * -dn) {
          ux = cx;
          uy = cy;
        } else {
          const double f = c.friction * -dn / tl;
          ux = G.vx[a] - dn * nx - f * tx;
          uy = G.vy[a] - dn * ny - f * ty;
        }
      }
      double wx = (M * cx - m0 * ux) / m1, wy = (M * cy - m0 * uy) / m1;
      double scratch[4] = {0, 0, 0, 0};
      constrain(g, q.walls, i, j, ux, uy, scratch);
      constrain(g, q.walls, i, j, wx, wy, scratch);
      // Energy the contact step removes, per unit of the node's mass, for the heating gather.
      // Each field f goes from its scatter velocity u_f (walls applied) to its final velocity
      // v'_f; its impulse before contact J_f = m_f (v_f - u_f) works through the mid-step
      // velocity (u_f + v'_f) / 2 (the USL gather's L), so the node's energy changes by
      //   sum_f 1/2 m_f (|v'_f|^2 - |u_f|^2) - 1/2 J_f . (u_f + v'_f)
      // which is 0 without contact (v'_f = v_f) and minus the contact's loss with it. (The
      // kinetic energy of the velocities after the forces alone, 1/2 m_f |v_f|^2, counts a
      // field with a sliver of mass at a node, whose force gave it a large velocity, as holding
      // energy no step gave it: +80 % energy over a void collapse.)
      // With the updated velocity in L the step's own balance is off by the explicit defect
      // -1/2 m_f |v_f - u_f|^2 per field, which contact must not count: then a weld's loss is
      // 1/2 mu |u_0 - u_1|^2 (mu = m0 m1 / M, the node then balances as the single field's), a
      // Coulomb contact's the drop of 1/2 mu |v_0 - v_1|^2.
      const double s0 = q.scatter_velocity ? 1.0 : 1.0 / m0, s1 = q.scatter_velocity ? 1.0 : 1.0 / m1;
      double loss = 0.0;
      if (!c.midstep) {
        const double mu = m0 * m1 / M;
        double r2;
        if (c.weld) {
          const double rx = G.px[a] * s0 - G.px[b] * s1, ry = G.py[a] * s0 - G.py[b] * s1;
          r2 = rx * rx + ry * ry;
        } else {
          const double dx = G.vx[a] - G.vx[b], dy = G.vy[a] - G.vy[b], ex = ux - wx, ey = uy - wy;
          r2 = std::max(0.0, dx * dx + dy * dy - ex * ex - ey * ey);
        }
        loss = 0.5 * mu * r2;
      }
      for (int f = 0; f < 2 && c.midstep; ++f) {
        const std::size_t k = f ? b : a;
        const double m = f ? m1 : m0, sc = f ? s1 : s0;
        const double uxf = G.px[k] * sc, uyf = G.py[k] * sc;  // scatter velocity
        const double vxf = f ? wx : ux, vyf = f ? wy : uy;    // final velocity
        const double jx = m * (G.vx[k] - uxf), jy = m * (G.vy[k] - uyf);
        loss -= 0.5 * m * (vxf * vxf + vyf * vyf - uxf * uxf - uyf * uyf) - 0.5 * (jx * (uxf + vxf) + jy * (uyf + vyf));
      }
      G.heat[a] = G.heat[b] = loss / M;
      row += loss;
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
    if (row_loss) row_loss[j + g.pad] = row;
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
