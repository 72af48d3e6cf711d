#include "dimension.hpp"
#include "grid_update.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace SMPM_NS::kern {

namespace {

// Applies every wall to velocity v of node i in place and adds the change each wall made to its
// slot of dv: dv[2 d] the low wall of axis d, dv[2 d + 1] the high one (left, right, bottom,
// top). Slip zeroes the normal component, NoSlip all of them. Axes in order, low wall first.
inline void constrain(const GridGeom& g, const Walls& W, const Idx<kDim>& i, double* v, double* dv) {
  for (int d = 0; d < kDim; ++d) {
    if (g.periodic(d)) continue;
    for (int s = 0; s < 2; ++s) {
      const Wall w = s ? W.hi[d] : W.lo[d];
      if (w == Wall::None || (s ? i[d] < g.cells(d) : i[d] > 0)) continue;
      const double before = v[d];
      if (w == Wall::Slip) {
        v[d] = 0.0;
      } else {
        for (int e = 0; e < kDim; ++e) v[e] = 0.0;
      }
      dv[2 * d + s] += v[d] - before;
    }
  }
}

// The nodes of the line through node i that no wall constrains (constrain leaves them as they
// are): [a, e) along axis 0; empty when a wall of another axis holds the whole line.
std::pair<int, int> off_walls(const GridGeom& g, const Walls& W, const Idx<kDim>& i) {
  for (int d = 1; d < kDim; ++d)
    if (!g.periodic(d) && ((W.lo[d] != Wall::None && i[d] <= 0) || (W.hi[d] != Wall::None && i[d] >= g.cells(d))))
      return {0, 0};
  const bool walls = !g.periodic(0);
  return {walls && W.lo[0] != Wall::None ? 1 : std::numeric_limits<int>::min(),
          walls && W.hi[0] != Wall::None ? g.cells(0) : std::numeric_limits<int>::max()};
}

// Nodes of a line at a time in the vectorized runs off the walls
constexpr int kRunChunk = 64;

}  // namespace

void grid_update(const GridGeom& g, const NodeBox& box, const GridView& G, const GridUpdateParams& q,
                 double* row_force) {
  const NodeBox b = real_nodes(g, box);
  const double inv_dt = q.dt > 0.0 ? 1.0 / q.dt : 0.0;
  if (row_force) std::fill(row_force, row_force + kRowSlots * static_cast<std::size_t>(g.num_lines()), 0.0);
  struct Row {
    double rf[kRowSlots];
  };
  for_each_node_by_line<Row>(
      g, b,
      [&](Row& row, const Idx<kDim>& i, std::size_t n) {
        double* rf = row.rf;
        const double m = G.m[n];
        if (m <= 0.0) {
          for (int d = 0; d < kDim; ++d) {
            G.v[d][n] = 0.0;
            if (q.flip) G.dv[d][n] = 0.0;
            if (q.scatter_velocity) G.p[d][n] = 0.0;
          }
          return;
        }
        const double inv_m = 1.0 / m;
        const double acc = m > q.mass_eps ? q.dt : 0.0;
        double u[kDim], v[kDim];  // old and new velocity
        for (int d = 0; d < kDim; ++d) u[d] = G.p[d][n] * inv_m;
        for (int d = 0; d < kDim; ++d) v[d] = u[d] + acc * (G.f[d][n] * inv_m + q.gravity[d]);
        double scratch[2 * kDim] = {};
        const double u2 = norm2(u);
        constrain(g, q.walls, i, u, scratch);
        double lost = u2;
        for (int d = 0; d < kDim; ++d) lost -= u[d] * u[d];
        rf[2 * kDim] += 0.5 * m * lost;
        if (q.scatter_velocity)  // after the walls: see GridUpdateParams
          for (int d = 0; d < kDim; ++d) G.p[d][n] = u[d];
        double dv[2 * kDim] = {};
        constrain(g, q.walls, i, v, dv);
        for (int k = 0; k < 2 * kDim; ++k) rf[k] += m * dv[k] * inv_dt;
        for (int d = 0; d < kDim; ++d) {
          G.v[d][n] = v[d];
          if (q.flip) G.dv[d][n] = v[d] - u[d];
        }
      },
      [&](const Idx<kDim>& i) { return off_walls(g, q.walls, i); },
      [&](Row& row, std::size_t n0, int count) {
        // node() with the walls doing nothing: the same operations, so the same bits, selecting
        // instead of returning early; the walls' reactions gain m 0 / dt = 0, and the kinetic
        // energy they removed, round-off here, is summed in node order. Local pointers and
        // flags: read through G and q inside the loop, GCC does not vectorize it.
        const double dt = q.dt, eps = q.mass_eps;
        const bool flip = q.flip, sv = q.scatter_velocity;
        for (int c0 = 0; c0 < count; c0 += kRunChunk) {
          const int len = std::min(kRunChunk, count - c0);
          const std::size_t k0 = n0 + c0;
          const double* __restrict m = G.m + k0;
          const double* __restrict f[kDim];
          double *__restrict p[kDim], *__restrict v[kDim], *__restrict dv[kDim];  // p: read, and written with sv
          double gravity[kDim];
          for (int d = 0; d < kDim; ++d) {
            p[d] = G.p[d] + k0;
            f[d] = G.f[d] + k0;
            v[d] = G.v[d] + k0;
            dv[d] = flip ? G.dv[d] + k0 : nullptr;  // null without FLIP
            gravity[d] = q.gravity[d];
          }
          double lost[kRunChunk];
#pragma omp simd
          for (int c = 0; c < len; ++c) {
            const double mc = m[c];
            const bool has = !(mc <= 0.0);
            const double inv_m = 1.0 / (has ? mc : 1.0);
            const double acc = mc > eps ? dt : 0.0;
            double u[kDim], w[kDim];
#pragma GCC unroll 3
            for (int d = 0; d < kDim; ++d) u[d] = p[d][c] * inv_m;
#pragma GCC unroll 3
            for (int d = 0; d < kDim; ++d) w[d] = u[d] + acc * (f[d][c] * inv_m + gravity[d]);
            double l = u[0] * u[0];  // norm2(u), written out: a pointer to u keeps the loop scalar
#pragma GCC unroll 3
            for (int d = 1; d < kDim; ++d) l += u[d] * u[d];
#pragma GCC unroll 3
            for (int d = 0; d < kDim; ++d) l -= u[d] * u[d];
            lost[c] = has ? 0.5 * mc * l : 0.0;
#pragma GCC unroll 3
            for (int d = 0; d < kDim; ++d) {
              v[d][c] = has ? w[d] : 0.0;
              if (flip) dv[d][c] = has ? w[d] - u[d] : 0.0;
              if (sv) p[d][c] = has ? u[d] : 0.0;
            }
          }
          for (int c = 0; c < len; ++c) row.rf[2 * kDim] += lost[c];
        }
      },
      [&](const Row& row, int line) {
        if (row_force)
          for (int k = 0; k < kRowSlots; ++k) row_force[kRowSlots * line + k] = row.rf[k];
      });
}

void grid_velocity_from_momentum(const GridGeom& g, const NodeBox& box, const GridView& G, const GridUpdateParams& q) {
  struct None {};
  for_each_node_by_line<None>(
      g, real_nodes(g, box),
      [&](None&, const Idx<kDim>& i, std::size_t n) {
        const double m = G.m[n];
        double v[kDim] = {};
        if (m > 0.0) {
          for (int d = 0; d < kDim; ++d) v[d] = G.p[d][n] / m;
          double dv[2 * kDim] = {};
          constrain(g, q.walls, i, v, dv);
        }
        for (int d = 0; d < kDim; ++d) G.v[d][n] = v[d];
      },
      [&](const Idx<kDim>& i) { return off_walls(g, q.walls, i); },
      [&](None&, std::size_t n0, int count) {  // node() with the walls doing nothing
        const double* __restrict m = G.m + n0;
        const double* __restrict p[kDim];
        double* __restrict v[kDim];
        for (int d = 0; d < kDim; ++d) {
          p[d] = G.p[d] + n0;
          v[d] = G.v[d] + n0;
        }
#pragma omp simd
        for (int c = 0; c < count; ++c) {
          const bool has = m[c] > 0.0;
#pragma GCC unroll 3
          for (int d = 0; d < kDim; ++d) v[d][c] = has ? p[d][c] / (has ? m[c] : 1.0) : 0.0;
        }
      },
      [](None&, int) {});
}

void clear_grid(const GridGeom& g, const NodeBox& b, const GridView& G, bool all) {
  if (b.empty()) return;
  // what a P2G writes: momentum; with `all` mass, force and the contact arrays in use
  double* arrays[3 * kDim + 2];
  int count = 0;
  for (int d = 0; d < kDim; ++d) arrays[count++] = G.p[d];
  if (all) {
    arrays[count++] = G.m;
    for (int d = 0; d < kDim; ++d) arrays[count++] = G.f[d];
    if (G.vol) arrays[count++] = G.vol;
    for (int d = 0; d < kDim; ++d)
      if (G.gm[d]) arrays[count++] = G.gm[d];
  }
  const std::size_t len = static_cast<std::size_t>(b.hi[0] - b.lo[0] + 1);
  const int lines = b.lines();
#pragma omp parallel for schedule(static) collapse(2)
  for (int f = 0; f < G.fields; ++f)
    for (int r = 0; r < lines; ++r) {
      const std::size_t n0 = g.node(b.line_start(r)) + f * G.fstride;
      for (int k = 0; k < count; ++k) std::fill(arrays[k] + n0, arrays[k] + n0 + len, 0.0);
    }
}

namespace {

// The weld of any number of velocity fields with APIC's scatter velocity (q.scatter_velocity):
// at a node where at least two fields hold mass and all fields together fill vmin, every field
// present takes the centre-of-mass velocity, after the forces and before them (p / m in p).
// The heating gather's scatter loss then counts 1/2 m_f |u_f - u_cm|^2 per field, together the
// weld's loss (for two fields 1/2 mu |u_0 - u_1|^2), and the mid-step L is the single field's:
// no contact heat (heat = 0 where allocated: the APIC gather of void faces does not read it).
void weld_fields(const GridGeom& g, const NodeBox& box, const GridView& G, const GridUpdateParams& q, double vmin,
                 double* row_loss) {
  const NodeBox b = real_nodes(g, box);
  const std::size_t fs = G.fstride;
  const int K = G.fields;
  for_each_node_by_line<double>(
      g, b,
      [&](double& row, const Idx<kDim>&, std::size_t a) {
        double M = 0.0, V = 0.0, mv[kDim] = {}, mp[kDim] = {};
        int present = 0;
        for (int f = 0; f < K; ++f) {
          const std::size_t k = a + f * fs;
          if (G.heat) G.heat[k] = 0.0;
          V += G.vol[k];
          const double m = G.m[k];
          if (m <= q.mass_eps) continue;
          ++present;
          M += m;
          for (int d = 0; d < kDim; ++d) {
            mv[d] += m * G.v[d][k];
            mp[d] += m * G.p[d][k];
          }
        }
        if (present < 2 || V < vmin) return;
        double c[kDim], u[kDim];  // centre-of-mass velocity after the forces and before them
        for (int d = 0; d < kDim; ++d) {
          c[d] = mv[d] / M;
          u[d] = mp[d] / M;
        }
        for (int f = 0; f < K; ++f) {
          const std::size_t k = a + f * fs;
          if (G.m[k] <= q.mass_eps) continue;
          double e[kDim];
          for (int d = 0; d < kDim; ++d) e[d] = G.p[d][k] - u[d];
          row += 0.5 * G.m[k] * norm2(e);
          for (int d = 0; d < kDim; ++d) {
            G.p[d][k] = u[d];
            G.v[d][k] = c[d];  // (scatter_velocity means APIC: no FLIP increments)
          }
        }
      },
      [&](double row, int line) {
        if (row_loss) row_loss[line] = row;
      });
}

// Coulomb contact (or FLIP's weld) of field 0's velocity v0 against the centre of mass c at a
// node (see grid_contact): the corrected velocity of field 0 into u; false where the fields
// separate (or have no normal) and nothing changes.
SMPM_INLINE bool coulomb(const GridView& G, std::size_t a, std::size_t b, const double* c, const ContactParams& p,
                         double* u) {
  if (p.weld) {  // FLIP's (APIC's: weld_fields)
    for (int d = 0; d < kDim; ++d) u[d] = c[d];
    return true;
  }
  // sum_p m_p grad N_i(x_p) points out of each body (mass grows the other way)
  double nrm[kDim], dv[kDim], t[kDim];
  for (int d = 0; d < kDim; ++d) nrm[d] = G.gm[d][b] - G.gm[d][a];
  const double len = std::sqrt(norm2(nrm));
  if (!(len > 0.0)) return false;
  for (int d = 0; d < kDim; ++d) nrm[d] /= len;
  for (int d = 0; d < kDim; ++d) dv[d] = G.v[d][a] - c[d];
  double dn = dv[0] * nrm[0];
  for (int d = 1; d < kDim; ++d) dn += dv[d] * nrm[d];
  if (dn >= 0.0) return false;  // separating: no contact force
  for (int d = 0; d < kDim; ++d) t[d] = dv[d] - dn * nrm[d];
  const double tl = std::sqrt(norm2(t));
  if (tl <= p.friction * -dn) {
    for (int d = 0; d < kDim; ++d) u[d] = c[d];
  } else {
    const double f = p.friction * -dn / tl;
    for (int d = 0; d < kDim; ++d) u[d] = G.v[d][a] - dn * nrm[d] - f * t[d];
  }
  return true;
}

// The energy the contact step removes at a node (see the comment in grid_contact): fields a and
// b of masses m0, m1 end at velocities u and w.
SMPM_INLINE double contact_loss(const GridView& G, std::size_t a, std::size_t b, double m0, double m1,
                                const double* u, const double* w, const GridUpdateParams& q,
                                const ContactParams& c) {
  const double M = m0 + m1;
  const double s0 = q.scatter_velocity ? 1.0 : 1.0 / m0, s1 = q.scatter_velocity ? 1.0 : 1.0 / m1;
  double loss = 0.0;
  if (!c.midstep) {
    const double mu = m0 * m1 / M;
    double r2;
    if (c.weld) {
      double rv[kDim];
      for (int d = 0; d < kDim; ++d) rv[d] = G.p[d][a] * s0 - G.p[d][b] * s1;
      r2 = norm2(rv);
    } else {
      double dv[kDim], ev[kDim];
      for (int d = 0; d < kDim; ++d) {
        dv[d] = G.v[d][a] - G.v[d][b];
        ev[d] = u[d] - w[d];
      }
      double s = norm2(dv);
      for (int d = 0; d < kDim; ++d) s -= ev[d] * ev[d];
      r2 = std::max(0.0, s);
    }
    loss = 0.5 * mu * r2;
  }
  for (int f = 0; f < 2 && c.midstep; ++f) {
    const std::size_t k = f ? b : a;
    const double m = f ? m1 : m0, sc = f ? s1 : s0;
    const double* vf = f ? w : u;  // final velocity
    double uf[kDim], jf[kDim];     // scatter velocity, impulse before contact
    for (int d = 0; d < kDim; ++d) {
      uf[d] = G.p[d][k] * sc;
      jf[d] = m * (G.v[d][k] - uf[d]);
    }
    double kin = norm2(vf);
    for (int d = 0; d < kDim; ++d) kin -= uf[d] * uf[d];
    double work = jf[0] * (uf[0] + vf[0]);
    for (int d = 1; d < kDim; ++d) work += jf[d] * (uf[d] + vf[d]);
    loss -= 0.5 * m * kin - 0.5 * work;
  }
  return loss;
}

}  // namespace

void grid_contact(const GridGeom& g, const NodeBox& box, const GridView& G, const GridUpdateParams& q,
                  const ContactParams& c, double* row_loss) {
  double vmin = c.volume_fraction - 1e-9;  // times h^kDim: a full node passes despite round-off
  for (int d = 0; d < kDim; ++d) vmin *= g.h;
  if (row_loss) std::fill(row_loss, row_loss + g.num_lines(), 0.0);
  if (c.weld && q.scatter_velocity) {
    weld_fields(g, box, G, q, vmin, row_loss);
    return;
  }
  const NodeBox nb = real_nodes(g, box);
  const std::size_t fs = G.fstride;
  for_each_node_by_line<double>(
      g, nb,
      [&](double& row, const Idx<kDim>& i, std::size_t a) {
        const std::size_t b = a + fs;
        if (G.heat) G.heat[a] = G.heat[b] = 0.0;
        const double m0 = G.m[a], m1 = G.m[b];
        if (m0 <= q.mass_eps || m1 <= q.mass_eps || G.vol[a] + G.vol[b] < vmin) return;
        const double M = m0 + m1;
        double cm[kDim], u[kDim], w[kDim];  // centre of mass; corrected velocities of fields 0, 1
        for (int d = 0; d < kDim; ++d) cm[d] = (m0 * G.v[d][a] + m1 * G.v[d][b]) / M;
        if (!coulomb(G, a, b, cm, c, u)) return;
        for (int d = 0; d < kDim; ++d) w[d] = (M * cm[d] - m0 * u[d]) / m1;
        double scratch[2 * kDim] = {};
        constrain(g, q.walls, i, u, scratch);
        constrain(g, q.walls, i, w, scratch);
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
        const double loss = contact_loss(G, a, b, m0, m1, u, w, q, c);
        if (G.heat) G.heat[a] = G.heat[b] = loss / M;
        row += loss;
        for (int d = 0; d < kDim; ++d) {
          if (q.flip) {
            G.dv[d][a] += u[d] - G.v[d][a];
            G.dv[d][b] += w[d] - G.v[d][b];
          }
          G.v[d][a] = u[d];
          G.v[d][b] = w[d];
        }
      },
      [&](double row, int line) {
        if (row_loss) row_loss[line] = row;
      });
}

namespace {

// Node k of box b, counted with axis 0 fastest.
inline Idx<kDim> box_node(const NodeBox& b, std::size_t k) {
  Idx<kDim> i;
  for (int d = 0; d < kDim; ++d) {
    const std::size_t len = static_cast<std::size_t>(b.hi[d] - b.lo[d] + 1);
    i[d] = b.lo[d] + static_cast<int>(k % len);
    k /= len;
  }
  return i;
}

// The ghosts of periodic axis d, over the box's other axes: fold adds each ghost node onto the
// node it stands for and zeroes it (low ghosts first, then high); fill copies the real node
// into the ghost.
template <bool Fold>
void periodic_axis(const GridGeom& g, const NodeBox& b, int d, double* const* arrays, int count) {
  NodeBox layer = b;
  layer.lo[d] = layer.hi[d] = 0;
  const std::ptrdiff_t cnt = static_cast<std::ptrdiff_t>(layer.nodes());
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(g.stride(d)), n = g.cells(d);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t k = 0; k < cnt; ++k) {
    const std::ptrdiff_t n0 = static_cast<std::ptrdiff_t>(g.node(box_node(layer, static_cast<std::size_t>(k))));
    for (int a = 0; a < count; ++a) {
      double* A = arrays[a];
      for (std::ptrdiff_t c = -g.pad; c < 0; ++c) {
        const std::ptrdiff_t ghost = n0 + c * step, real = n0 + (c + n) * step;
        if (Fold) {
          A[real] += A[ghost];
          A[ghost] = 0.0;
        } else {
          A[ghost] = A[real];
        }
      }
      for (std::ptrdiff_t c = n; c <= n + g.pad; ++c) {
        const std::ptrdiff_t ghost = n0 + c * step, real = n0 + (c - n) * step;
        if (Fold) {
          A[real] += A[ghost];
          A[ghost] = 0.0;
        } else {
          A[ghost] = A[real];
        }
      }
    }
  }
}

}  // namespace

void fold_periodic(const GridGeom& g, const NodeBox& b, double* const* arrays, int count) {
  for (int d = 0; d < kDim; ++d)
    if (g.periodic(d)) periodic_axis<true>(g, b, d, arrays, count);
}

void fill_periodic_ghosts(const GridGeom& g, const NodeBox& b, double* const* arrays, int count) {
  for (int d = kDim - 1; d >= 0; --d)
    if (g.periodic(d)) periodic_axis<false>(g, b, d, arrays, count);
}

}  // namespace SMPM_NS::kern
