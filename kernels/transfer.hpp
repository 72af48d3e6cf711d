// Particle-to-grid scatter and grid-to-particle gather: one templated body per direction,
// serving every shape function, both transfers (APIC, FLIP/PIC) and both schemes (USL, MUSL).
// Race handling lives in the iteration (colored tiles, serial, or atomic adds for comparison),
// never in the particle body.
#pragma once
#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "views.hpp"

namespace smpm::kern {

enum class P2GWhat { All, Momentum };  // All: mass, momentum, internal force. Momentum: MUSL remap.
enum class G2PWhat { Full, Velocity, PositionGradient };  // Full: USL. MUSL: Velocity, then the rest.

// Where a particle's contributions go. The particle body (p2g_particle) is the same for every
// sink; the sink decides how a node is addressed and how a value is added.
//  - GridSink<PlainAdd>: straight into the grid arrays (serial reference, and nothing else
//    writes at the same time).
//  - GridSink<AtomicAdd>: into the grid arrays with atomic adds (comparison only).
//  - TileSink: into a small node-major scratch block covering one tile's stencil footprint,
//    which stays in L1; the colored scatter flushes it to the grid after the tile.
struct PlainAdd {
  static inline void add(double& a, double v) { a += v; }
};
struct AtomicAdd {
  static inline void add(double& a, double v) {
#pragma omp atomic
    a += v;
  }
};

template <class Add>
struct GridSink {
  const GridGeom& g;
  const GridView& G;
  std::size_t row(int i, int j) const { return g.node(i, j); }
  std::size_t field_offset(std::size_t f) const { return f * G.fstride; }
  inline void add_momentum(std::size_t n, double qx, double qy) const {
    Add::add(G.px[n], qx);
    Add::add(G.py[n], qy);
  }
  inline void add_mass_force(std::size_t n, double m, double fx, double fy) const {
    Add::add(G.m[n], m);
    Add::add(G.fx[n], fx);
    Add::add(G.fy[n], fy);
  }
  inline void add_contact(std::size_t n, double gmx, double gmy, double vol) const {
    Add::add(G.gmx[n], gmx);
    Add::add(G.gmy[n], gmy);
    Add::add(G.vol[n], vol);
  }
  inline void add_volume(std::size_t n, double vol) const { Add::add(G.vol[n], vol); }
};

// Largest tile width the scratch block is sized for (grid.tile_cells is checked against it).
inline constexpr int kMaxTile = 16;
// Nodes a tile's particles reach: cells c in [t0, t0 + tile) touch nodes c - 1 .. c + 2
// (every shape function here), so the block spans [t0 - 1, t0 + tile + 1]: tile + 3 nodes.
inline constexpr int tile_span(int tile) { return tile + 3; }

// K values per node: m, px, py, fx, fy (K = 5); with contact also grad m (2) and volume (K = 8),
// or the volume alone (K = 6, a weld).
// Velocity fields follow each other, span * span nodes apart.
template <int K>
struct TileSink {
  double* s;
  int i0, j0, span;
  std::size_t row(int i, int j) const { return static_cast<std::size_t>((j - j0) * span + (i - i0)); }
  std::size_t field_offset(std::size_t f) const { return f * static_cast<std::size_t>(span * span); }
  inline void add_momentum(std::size_t n, double qx, double qy) const {
    s[K * n + 1] += qx;
    s[K * n + 2] += qy;
  }
  inline void add_mass_force(std::size_t n, double m, double fx, double fy) const {
    s[K * n + 0] += m;
    s[K * n + 3] += fx;
    s[K * n + 4] += fy;
  }
  inline void add_contact(std::size_t n, double gmx, double gmy, double vol) const {
    s[K * n + 5] += gmx;
    s[K * n + 6] += gmy;
    s[K * n + 7] += vol;
  }
  inline void add_volume(std::size_t n, double vol) const { s[K * n + 5] += vol; }  // K = 6
};

// Scatter of one particle p into its velocity field. APIC adds the affine momentum
// m C (x_i - x_p). Contact also scatters the volume, and with Normals the mass gradient (the
// contact normals of two bodies; a weld of void faces needs none).
template <class Shape, bool APIC, P2GWhat What, class Sink, bool Contact = false, bool Normals = true>
inline void p2g_particle(const GridGeom& g, const Sink& sink, const ParticleView& P, std::uint32_t p,
                         double lp) {
  constexpr int N = Shape::N;
  const double inv_h = 1.0 / g.h;
  const double xg = (P.x[p] - g.x0) * inv_h, yg = (P.y[p] - g.y0) * inv_h;
  double wx[N], wy[N], dwx[N], dwy[N];
  const int bx = Shape::eval(xg, lp, wx, dwx);
  const int by = Shape::eval(yg, lp, wy, dwy);
  const double m = P.m[p];
  const double mvx = m * P.vx[p], mvy = m * P.vy[p];
  double mCxx = 0, mCxy = 0, mCyx = 0, mCyy = 0;
  if constexpr (APIC) {  // grid-unit offsets: fold h in here
    mCxx = m * P.Cxx[p] * g.h; mCxy = m * P.Cxy[p] * g.h;
    mCyx = m * P.Cyx[p] * g.h; mCyy = m * P.Cyy[p] * g.h;
  }
  double vsxx = 0, vsyy = 0, vsxy = 0;  // -V sigma / h
  if constexpr (What == P2GWhat::All) {
    const double Vh = P.V[p] * inv_h;
    const double pq = P.q ? P.p[p] + P.q[p] : P.p[p];
    vsxx = -Vh * (P.sxx[p] - pq);
    vsyy = -Vh * (P.syy[p] - pq);
    vsxy = -Vh * P.sxy[p];
  }
  const std::size_t foff = Contact ? sink.field_offset(P.field(p)) : 0;
  const double mh = m * inv_h, Vp = Contact ? P.V[p] : 0.0;
  for (int b = 0; b < N; ++b) {
    const std::size_t row = sink.row(bx, by + b) + foff;
    const double dy = (by + b) - yg;
    for (int a = 0; a < N; ++a) {
      const std::size_t n = row + a;
      const double w = wx[a] * wy[b];
      double qx = mvx, qy = mvy;
      if constexpr (APIC) {
        const double dx = (bx + a) - xg;
        qx += mCxx * dx + mCxy * dy;
        qy += mCyx * dx + mCyy * dy;
      }
      sink.add_momentum(n, w * qx, w * qy);
      if constexpr (What == P2GWhat::All) {
        const double gx = dwx[a] * wy[b], gy = wx[a] * dwy[b];
        sink.add_mass_force(n, w * m, vsxx * gx + vsxy * gy, vsxy * gx + vsyy * gy);
        if constexpr (Contact && Normals) sink.add_contact(n, mh * gx, mh * gy, w * Vp);
        if constexpr (Contact && !Normals) sink.add_volume(n, w * Vp);
      }
    }
  }
}

// Scatter of the particles at sorted positions [s0, s1) into a sink.
template <class Shape, bool APIC, P2GWhat What, class Sink, bool Contact = false, bool Normals = true>
inline void p2g_range(const GridGeom& g, const Sink& sink, const ParticleView& P, const std::uint32_t* order,
                      std::size_t s0, std::size_t s1, double lp) {
  for (std::size_t s = s0; s < s1; ++s)
    p2g_particle<Shape, APIC, What, Sink, Contact, Normals>(g, sink, P, order[s], lp);
}

// Colored iteration over tiles: tiles of one color (tile parity in x and y) touch disjoint
// nodes (tile width > stencil reach), so they run in parallel with plain adds; the 4 colors run
// one after another. Each tile accumulates K values per node into an L1/L2-resident scratch
// block covering its footprint (body(block, s0, s1) for the particles at sorted positions
// [s0, s1)), then the block is handed node by node to flush(values, grid_node, f), clipped to
// the node storage (a partial last tile's block reaches past it). With F fields (F <= FMax, the
// scratch's capacity) the block holds F sub-blocks of span * span nodes, field f's at
// f * K * span * span; fields(s0, s1) says which of them the tile's particles scatter into
// (bit f), and only those are zeroed and flushed (a four-field run's tiles mostly hold two or
// three). Fixed tile order and fixed particle order within a tile make every node's sum
// independent of the thread count.
struct TileBlock {
  double* s;
  int i0, j0, span;
};
struct OneField {
  unsigned operator()(std::uint32_t, std::uint32_t) const { return 1u; }
};

template <int K, int FMax = 1, class Body, class Flush, class Fields = OneField>
void for_each_tile_colored(const GridGeom& g, const std::uint32_t* cell_start, Body&& body, Flush&& flush, int F = 1,
                           Fields&& fields = Fields{}) {
  if (F < 1 || F > FMax) throw std::invalid_argument("colored scatter: " + std::to_string(F) + " velocity fields, at most " + std::to_string(FMax));
  const int TX = g.tiles_x(), TY = g.tiles_y(), cpt = g.cells_per_tile();
  const int span = tile_span(g.tile);
  const std::size_t block = static_cast<std::size_t>(K) * span * span;
#pragma omp parallel
  {
    alignas(64) double scratch[K * FMax * tile_span(kMaxTile) * tile_span(kMaxTile)];
    for (int color = 0; color < 4; ++color) {
      const int cx = color & 1, cy = color >> 1;
      const int ntx = (TX - cx + 1) / 2, nty = (TY - cy + 1) / 2;
#pragma omp for schedule(dynamic, 1)
      for (int k = 0; k < ntx * nty; ++k) {
        const int tx = cx + 2 * (k % ntx), ty = cy + 2 * (k / ntx);
        const std::size_t t = static_cast<std::size_t>(ty) * TX + tx;
        const std::uint32_t s0 = cell_start[t * cpt], s1 = cell_start[(t + 1) * cpt];
        if (s0 == s1) continue;
        const TileBlock blk{scratch, tx * g.tile - 1, ty * g.tile - 1, span};
        const unsigned used = F > 1 ? fields(s0, s1) : 1u;
        for (int f = 0; f < F; ++f)
          if ((used >> f) & 1u) std::fill(scratch + f * block, scratch + (f + 1) * block, 0.0);
        body(blk, s0, s1);
        const int jn = std::min(span, g.ny + g.pad - blk.j0 + 1);
        const int in = std::min(span, g.nx + g.pad - blk.i0 + 1);
        for (int f = 0; f < F; ++f) {
          if (!((used >> f) & 1u)) continue;
          for (int jj = 0; jj < jn; ++jj) {
            const std::size_t row = g.node(blk.i0, blk.j0 + jj);
            const double* sr = scratch + f * block + K * jj * span;
            for (int ii = 0; ii < in; ++ii) flush(sr + K * ii, row + ii, f);
          }
        }
      }
    }
  }
}

// The nodes the particles binned in cell_start reach: the union of the node blocks of the
// occupied tiles (tile_span), which holds every node a colored scatter writes and every node a
// gather reads. With periodic x it spans all columns (the fold and the ghost fill need them).
// Empty without particles.
inline NodeBox occupied_nodes(const GridGeom& g, const std::uint32_t* cell_start) {
  const int TX = g.tiles_x(), NT = g.num_tiles();
  const std::size_t cpt = static_cast<std::size_t>(g.cells_per_tile());
  int tx0 = TX, tx1 = -1, ty0 = g.tiles_y(), ty1 = -1;
#pragma omp parallel for schedule(static) reduction(min : tx0, ty0) reduction(max : tx1, ty1)
  for (int t = 0; t < NT; ++t) {
    if (cell_start[t * cpt] == cell_start[(t + 1) * cpt]) continue;
    tx0 = std::min(tx0, t % TX);
    tx1 = std::max(tx1, t % TX);
    ty0 = std::min(ty0, t / TX);
    ty1 = std::max(ty1, t / TX);
  }
  if (tx1 < 0) return NodeBox{};
  const int last = tile_span(g.tile) - 1;  // a tile block's nodes: [t tile - 1, t tile - 1 + last]
  NodeBox b;
  b.i0 = g.periodic_x ? -g.pad : tx0 * g.tile - 1;
  b.i1 = g.periodic_x ? g.nx + g.pad : std::min(tx1 * g.tile - 1 + last, g.nx + g.pad);
  b.j0 = ty0 * g.tile - 1;
  b.j1 = std::min(ty1 * g.tile - 1 + last, g.ny + g.pad);
  return b;
}

// Colored scatter of mass, momentum and internal force (or momentum only); with Contact into
// G.fields velocity fields (two bodies: two, with mass gradients; void faces: two or four, with
// volumes).
template <class Shape, bool APIC, P2GWhat What, bool Contact = false, bool Normals = true>
void p2g_colored(const GridGeom& g, const GridView& G, const ParticleView& P, const std::uint32_t* order,
                 const std::uint32_t* cell_start, double lp) {
  constexpr int K = Contact ? (Normals ? 8 : 6) : 5, FMax = Contact ? (Normals ? 2 : 4) : 1;
  const int F = Contact ? G.fields : 1;
  for_each_tile_colored<K, FMax>(
      g, cell_start,
      [&](const TileBlock& b, std::uint32_t s0, std::uint32_t s1) {
        p2g_range<Shape, APIC, What, TileSink<K>, Contact, Normals>(g, TileSink<K>{b.s, b.i0, b.j0, b.span}, P, order,
                                                                    s0, s1, lp);
      },
      [&](const double* v, std::size_t n0, int f) {
        const std::size_t n = n0 + f * G.fstride;
        G.px[n] += v[1];
        G.py[n] += v[2];
        if constexpr (What == P2GWhat::All) {
          G.m[n] += v[0];
          G.fx[n] += v[3];
          G.fy[n] += v[4];
          if constexpr (Contact && Normals) {
            G.gmx[n] += v[5];
            G.gmy[n] += v[6];
            G.vol[n] += v[7];
          }
          if constexpr (Contact && !Normals) G.vol[n] += v[5];
        }
      },
      F,
      [&](std::uint32_t s0, std::uint32_t s1) {
        unsigned used = 0;
        for (std::uint32_t s = s0; s < s1; ++s) used |= 1u << P.field(order[s]);
        return used;
      });
}

// Reference scatters for tests and benchmarks: one thread into the grid, or all threads with
// atomic adds.
template <class Shape, bool APIC, P2GWhat What>
void p2g_serial(const GridGeom& g, const GridView& G, const ParticleView& P, const std::uint32_t* order,
                std::size_t n, double lp) {
  p2g_range<Shape, APIC, What>(g, GridSink<PlainAdd>{g, G}, P, order, 0, n, lp);
}
template <class Shape, bool APIC, P2GWhat What>
void p2g_atomic(const GridGeom& g, const GridView& G, const ParticleView& P, const std::uint32_t* order,
                std::size_t n, double lp) {
  const GridSink<AtomicAdd> sink{g, G};
#pragma omp parallel for schedule(static)
  for (std::size_t s = 0; s < n; ++s) p2g_particle<Shape, APIC, What>(g, sink, P, order[s], lp);
}

struct G2PParams {
  double dt = 0.0;
  double lp = 0.25;          // uGIMP half particle width, grid units
  double flip_alpha = 0.0;   // FLIP fraction (FLIP transfers only)
  // USL pass: L from v_new - mid (v_new - v_old): 0.5 the mid-step velocity, 0 the updated one
  // (see g2p_particle)
  double mid = 0.0;
  // Rigid walls are impenetrable: a point moved past one is put back on it. (With B-splines a
  // point in the first cell also feels nodes inside the material and can overshoot the wall
  // by a fraction of dt |v|.) -inf / +inf where there is no wall.
  double xmin = -1e300, xmax = 1e300, ymin = -1e300, ymax = 1e300;
};

// Gather for one particle. Velocity: APIC (PIC velocity plus the affine matrix C = B D^-1) or
// the FLIP/PIC blend. Position: moved with the grid velocity. Gradient: L = sum_i v_i grad w_i^T
// from the updated velocity. WorkRate (the USL pass with transfer heating, g2p_blocks): also
// the rate of the energy's work, D_mid = sym sum_i v_i^mid grad w_i^T with v_i^mid = v_i^new -
// q.mid (v_i^new - v_i^old) (px, py hold v^old, the grid update's scatter_velocity; FLIP takes
// v^old = v^new - dv), into Lout.wxx, wyy, wxy. The grid's kinetic energy changes by exactly dt
// f_i . (v^old + v^new) / 2 in the explicit update, and with q.mid = 0.5 the constitutive
// update's work dt V sigma : D_mid with the stress that made f_i (kern::constitutive_range,
// mid-step energy) is exactly its negative: the step conserves energy node by node, partly
// filled nodes at void faces and free surfaces included (with the work over L from v^new it
// loses dt^2 |f_i|^2 / (2 m_i) per node, most where m_i is small). The kinematics (volume,
// deviator, viscosity) take L from v^new, the symplectic choice: with the mid-step rate there
// too an undamped mode of frequency w grew by about (w dt)^2 / 4 per step in amplitude, and in
// a porous body moving freely at 1000 m/s round-off grew to 0.5 GPa in 120 ns in its thin
// ligaments (docs/method.md).
//
// Heat (APIC; FLIP below): both transfers dissipate kinetic energy, and both losses split exactly
// into per-particle shares (the kinetic energy of a particle counts its affine field,
// 1/2 m (|v_p|^2 + sum_ab C_ab^2 D_b)):
//   scatter  1/2 sum_i w_ip |v_p + C_p (x_i - x_p) - v_i^old|^2    (v_i^old = p_i / m_i)
//   gather   1/2 (sum_i w_ip |v_i|^2 - |v_p|^2 - sum_ab C_ab^2 D_b)  (least-squares residual)
// both >= 0 [J/kg]. At a shock front this is numerical entropy production; Heat adds it to the
// internal energy, so the transfers conserve total energy and the time integration's O(dt)
// error is what remains. Contact: 0 one velocity field, 1 several (each particle reads its own,
// Particles::field), 2 several with two-body contact, whose loss is added too: sum_i w_ip q_i,
// q_i = the kinetic energy removed at node i per unit of its total mass (kern::grid_contact),
// whose shares over the particles of both fields sum to the loss. (A weld of void faces needs
// no such term: it gives both fields the merged scatter velocity, whose difference to each
// field's own the scatter loss then counts.) Needs the scatter's velocity p / m in px, py (the grid update's
// scatter_velocity, ghosts filled).
//
// PureFlip (FLIP with flip_alpha = 1, velocity pass): v_p += sum_i w_ip dv_i alone; the PIC sum of
// the blend, multiplied by 1 - alpha = 0, is neither read nor formed (half the pass's grid reads).
template <class Shape, bool FLIP, G2PWhat What, bool Heat = false, int Contact = 0, bool PureFlip = false,
          bool WorkRate = false>
SMPM_INLINE void g2p_particle(const GridGeom& g, const GridView& G, const ParticleView& P, std::size_t p,
                         const G2PParams& q, const Gradient& Lout, std::size_t li) {
  static_assert(!PureFlip || (FLIP && What == G2PWhat::Velocity), "PureFlip is the FLIP velocity pass");
  constexpr int N = Shape::N;
  const double inv_h = 1.0 / g.h;
  const double xg = (P.x[p] - g.x0) * inv_h, yg = (P.y[p] - g.y0) * inv_h;
  double wx[N], wy[N], dwx[N], dwy[N];
  const int bx = Shape::eval(xg, q.lp, wx, dwx);
  const int by = Shape::eval(yg, q.lp, wy, dwy);
  double vx = 0, vy = 0, dvx = 0, dvy = 0, lxx = 0, lxy = 0, lyx = 0, lyy = 0;
  constexpr bool kAffine = !FLIP && What != G2PWhat::PositionGradient;
  constexpr bool kGrad = What != G2PWhat::Velocity || (kAffine && Shape::apic_gradient);
  double bxx = 0, bxy = 0, byx = 0, byy = 0;  // B = sum w v (x_i - x_p)^T, grid units
  // USL with transfer heating (g2p_blocks): also the rate of the energy's work, D_mid from the
  // mid-step velocity (q.mid) into Lout.wxx...; L is from the updated velocity in every pass
  static_assert(!WorkRate || (What == G2PWhat::Full && Heat), "the work rate is the heating USL pass's");
  double mxx = 0, mxy = 0, myx = 0, myy = 0;   // sum v_mid grad w^T
  static_assert(!Heat || kAffine || (FLIP && What == G2PWhat::Full),
                "transfer heating is defined for the APIC velocity gather and the FLIP USL gather");
  double v2 = 0, r2 = 0;  // sum w |v_i|^2, sum w |v_p + C_p (x_i - x_p) - v_i^old|^2
  double d2 = 0;          // FLIP: sum w |dv_i|^2
  double qc = 0;          // sum w q_i: the contact step's dissipation (several fields)
  double ux = 0, uy = 0, uxx = 0, uxy = 0, uyx = 0, uyy = 0;  // old v_p and C_p h
  if constexpr (Heat) {
    ux = P.vx[p]; uy = P.vy[p];
    if constexpr (!FLIP) {
      uxx = P.Cxx[p] * g.h; uxy = P.Cxy[p] * g.h; uyx = P.Cyx[p] * g.h; uyy = P.Cyy[p] * g.h;
    }
  }
  // with Contact the view always carries field_of (Simulation::pview): the lookup without
  // field()'s null test vectorizes
  const std::size_t foff = Contact ? static_cast<std::size_t>(P.field_of[p]) * G.fstride : 0;
#pragma GCC unroll 4
  for (int b = 0; b < N; ++b) {
    const std::size_t row = g.node(bx, by + b) + foff;
    const double dy = (by + b) - yg;
#pragma GCC unroll 4
    for (int a = 0; a < N; ++a) {
      const std::size_t n = row + a;
      const double w = wx[a] * wy[b];
      const double gvx = PureFlip ? 0.0 : G.vx[n], gvy = PureFlip ? 0.0 : G.vy[n];
      // USL: L from the mid-step velocity (v_old + v_new) / 2 of the node, v_old the scatter's
      // velocity after the walls (see the comment above)
      double lvx = gvx, lvy = gvy;
      if constexpr (WorkRate && FLIP) {  // FLIP: v_old = v_new - dv (the grid update's increment)
        lvx = gvx - q.mid * G.dvx[n];
        lvy = gvy - q.mid * G.dvy[n];
      } else if constexpr (WorkRate) {
        lvx = gvx - q.mid * (gvx - G.px[n]);
        lvy = gvy - q.mid * (gvy - G.py[n]);
      }
      if constexpr (!PureFlip) {
        vx += w * gvx;
        vy += w * gvy;
      }
      if constexpr (Heat && FLIP) {  // v_i^old = v_i - dv_i
        v2 += w * (gvx * gvx + gvy * gvy);
        d2 += w * (G.dvx[n] * G.dvx[n] + G.dvy[n] * G.dvy[n]);
        const double rx = ux - gvx + G.dvx[n], ry = uy - gvy + G.dvy[n];
        r2 += w * (rx * rx + ry * ry);
        if constexpr (Contact != 0) qc += w * G.heat[n];  // the contact step's loss, a weld's too
      } else if constexpr (Heat) {
        v2 += w * (gvx * gvx + gvy * gvy);
        const double dx = (bx + a) - xg;  // px, py hold the scatter's velocity p / m here
        const double rx = ux + uxx * dx + uxy * dy - G.px[n];
        const double ry = uy + uyx * dx + uyy * dy - G.py[n];
        r2 += w * (rx * rx + ry * ry);
        if constexpr (Contact == 2) qc += w * G.heat[n];
      }
      if constexpr (FLIP && What != G2PWhat::PositionGradient) {
        dvx += w * G.dvx[n];
        dvy += w * G.dvy[n];
      }
      if constexpr (kGrad) {
        const double gx = dwx[a] * wy[b], gy = wx[a] * dwy[b];
        lxx += gvx * gx; lxy += gvx * gy;
        lyx += gvy * gx; lyy += gvy * gy;
        if constexpr (WorkRate) {
          mxx += lvx * gx; mxy += lvx * gy;
          myx += lvy * gx; myy += lvy * gy;
        }
      }
      if constexpr (kAffine && !Shape::apic_gradient) {
        const double dx = (bx + a) - xg;
        bxx += w * gvx * dx; bxy += w * gvx * dy;
        byx += w * gvy * dx; byy += w * gvy * dy;
      }
    }
  }
  double affine = 0.0;  // sum_ab C_ab^2 D_b at the gather's position [m^2/s^2]
  double cxx_ = 0, cxy_ = 0, cyx_ = 0, cyy_ = 0;  // C in grid units, for the affine energy after the move
  if constexpr (kAffine) {
    // D = sum_i w_i (x_i - x_p)^2 per axis, grid units (diagonal for tensor-product shapes)
    double Dx = 0, Dy = 0;
    if constexpr (!Shape::apic_gradient || Heat) {
#pragma GCC unroll 4
      for (int a = 0; a < N; ++a) {
        const double ex = (bx + a) - xg, ey = (by + a) - yg;
        Dx += wx[a] * ex * ex;
        Dy += wy[a] * ey * ey;
      }
    }
    double cxx, cxy, cyx, cyy;  // C in grid units
    if constexpr (Shape::apic_gradient) {
      cxx = lxx; cxy = lxy; cyx = lyx; cyy = lyy;
    } else {
      cxx = bxx / Dx; cxy = bxy / Dy; cyx = byx / Dx; cyy = byy / Dy;
    }
    P.Cxx[p] = cxx * inv_h; P.Cxy[p] = cxy * inv_h;
    P.Cyx[p] = cyx * inv_h; P.Cyy[p] = cyy * inv_h;
    cxx_ = cxx; cxy_ = cxy; cyx_ = cyx; cyy_ = cyy;
    if constexpr (Heat) {
      affine = (cxx * cxx + cyx * cyx) * Dx + (cxy * cxy + cyy * cyy) * Dy;
      P.e[p] += 0.5 * (r2 + v2 - vx * vx - vy * vy - affine) + qc;
    }
  }
  if constexpr (Heat && FLIP) {
    // FLIP/PIC blend v = alpha v_F + (1 - alpha) v_PIC, v_F = v_p + sum w dv_i, v_PIC = sum w v_i:
    // its loss is alpha (FLIP's) + (1 - alpha) (PIC's) + alpha (1 - alpha) 1/2 |v_F - v_PIC|^2,
    // FLIP's 1/2 (sum w |dv_i|^2 - |sum w dv_i|^2) and PIC's the scatter and gather losses
    // above; each share >= 0 and their sum over the points exactly the transfers' loss
    const double al = q.flip_alpha, fx = ux + dvx - vx, fy = uy + dvy - vy;
    P.e[p] += 0.5 * (al * (d2 - dvx * dvx - dvy * dvy) + (1.0 - al) * (r2 + v2 - vx * vx - vy * vy) +
                     al * (1.0 - al) * (fx * fx + fy * fy)) + qc;
  }
  if constexpr (What != G2PWhat::PositionGradient) {
    if constexpr (PureFlip) {
      P.vx[p] = P.vx[p] + dvx;
      P.vy[p] = P.vy[p] + dvy;
    } else if constexpr (FLIP) {
      P.vx[p] = q.flip_alpha * (P.vx[p] + dvx) + (1.0 - q.flip_alpha) * vx;
      P.vy[p] = q.flip_alpha * (P.vy[p] + dvy) + (1.0 - q.flip_alpha) * vy;
    } else {
      P.vx[p] = vx;
      P.vy[p] = vy;
    }
  }
  if constexpr (What != G2PWhat::Velocity) {
    // periodic x: wrap (the second test also catches x + L rounding up to x0 + L); selects,
    // not branches, so the loop stays vectorizable (L = 0 leaves x as it is)
    double x = P.x[p] + q.dt * vx;
    const double L = g.periodic_x ? g.length_x() : 0.0;
    x = x < g.x0 ? x + L : x;
    x = x >= g.x0 + L ? x - L : x;
    P.x[p] = std::min(std::max(x, q.xmin), q.xmax);
    P.y[p] = std::min(std::max(P.y[p] + q.dt * vy, q.ymin), q.ymax);
    if constexpr (Heat && !FLIP && !Shape::constant_D && What == G2PWhat::Full) {
      // D of the linear hat and uGIMP depends on where the point sits in its cell. The affine
      // kinetic energy the next scatter sees (and Simulation::energy counts) is the one at the
      // new position: the difference is heat of the move, so total energy still balances
      double ex[N], ey[N], dex[N], dey[N], Dx = 0, Dy = 0;
      const double xn = (P.x[p] - g.x0) * inv_h, yn = (P.y[p] - g.y0) * inv_h;
      const int cx = Shape::eval(xn, q.lp, ex, dex), cy = Shape::eval(yn, q.lp, ey, dey);
#pragma GCC unroll 4
      for (int a = 0; a < N; ++a) {
        const double ux = (cx + a) - xn, uy = (cy + a) - yn;
        Dx += ex[a] * ux * ux;
        Dy += ey[a] * uy * uy;
      }
      const double after = (cxx_ * cxx_ + cyx_ * cyx_) * Dx + (cxy_ * cxy_ + cyy_ * cyy_) * Dy;
      P.e[p] += 0.5 * (affine - after);
    }
    Lout.xx[li] = lxx * inv_h; Lout.xy[li] = lxy * inv_h;
    Lout.yx[li] = lyx * inv_h; Lout.yy[li] = lyy * inv_h;
    if constexpr (WorkRate) {
      Lout.wxx[li] = mxx * inv_h; Lout.wyy[li] = myy * inv_h;
      Lout.wxy[li] = 0.5 * (mxy + myx) * inv_h;
    }
  }
}

// Parallel gather over particles in array order: race-free by construction. Contact: particles
// read their body's velocity field (a compile-time choice: the one-field path has no lookup).
// Vectorized across particles (omp simd; grid values by gather instructions): the particle
// body is inlined with its stencil loops unrolled and no branches, and the geometry, views and
// parameters are copied into each thread's locals, which the particle stores cannot alias (read
// through the references, GCC reloads them per point and rejects the loop). Each particle's sums
// run in the same order, each operation rounded as written (-ffp-contract=off), in the vector
// body and the remainder: bitwise the same for any thread count (tests/test_contact.cpp,
// tests/test_elastic.cpp, "determinism").
template <class Shape, bool FLIP, G2PWhat What, bool Heat, int Contact, bool PureFlip>
void g2p_loop(const GridGeom& g, const GridView& G, const ParticleView& P, std::size_t n, const G2PParams& q) {
#pragma omp parallel
  {
    const GridGeom gl = g;
    const GridView Gl = G;
    const ParticleView Pl = P;
    const G2PParams ql = q;
    const Gradient Ll = Gradient::of(P);
#pragma omp for simd schedule(static)
    for (std::size_t p = 0; p < n; ++p)
      g2p_particle<Shape, FLIP, What, Heat, Contact, PureFlip>(gl, Gl, Pl, p, ql, Ll, p);
  }
}

// The FLIP velocity pass with flip_alpha = 1 (MUSL, pure FLIP) takes the PureFlip body: the same
// velocities, up to the sign of a zero.
template <class Shape, bool FLIP, G2PWhat What, bool Heat = false, int Contact = 0>
void g2p(const GridGeom& g, const GridView& G, const ParticleView& P, std::size_t n, const G2PParams& q) {
  if constexpr (FLIP && What == G2PWhat::Velocity && !Heat && !Contact) {
    if (q.flip_alpha == 1.0) return g2p_loop<Shape, FLIP, What, Heat, Contact, true>(g, G, P, n, q);
  }
  g2p_loop<Shape, FLIP, What, Heat, Contact, false>(g, G, P, n, q);
}

// The pass that forms L (USL's gather, MUSL's position pass) with the work that reads L done
// block by block right behind it: each thread gathers its share of the points (thread_share) in
// blocks of kGatherBlock points and, after each block, calls after(first, last, L, acc) on it
// while the block's L is in cache (the engine's constitutive update; L.xx[i] ... is the
// gradient of point first + i). Thread t's buffer is at scratch + t * kGatherScratch (7 x
// kGatherBlock doubles, 448 KiB, in L2): with store_L, L goes to the particles' arrays as with
// g2p; else to the buffer's first four blocks, and the particles' L arrays are left as they
// were: the 64 B per point of storing L (write and write-allocate) and the 32 B of reading it
// back are saved. The heating USL pass's work rate D_mid (L.wxx, wyy, wxy) is always in the
// last three blocks. Acc: the per-thread
// result of `after`, merged with Acc::merge (whose order must not matter). The gathered values
// are those of g2p, bitwise (the same particle body; tests/test_kernels.cpp). The block size:
// blocks of 256-2048 points made the gather 2-6 ns per point slower on one thread (each block
// restarts the prefetch streams of both loops, about 20 arrays); 4096-16384 measured alike
// (docs/performance.md).
inline constexpr std::size_t kGatherBlock = 8192;
inline constexpr std::size_t kGatherScratch = 7 * kGatherBlock;  // doubles per thread

template <class Shape, bool FLIP, G2PWhat What, bool Heat, int Contact, class Acc, class After>
Acc g2p_blocks(const GridGeom& g, const GridView& G, const ParticleView& P, std::size_t n, const G2PParams& q,
               double* scratch, bool store_L, After&& after) {
  static_assert(What != G2PWhat::Velocity, "the velocity pass forms no L");
  // the heating USL pass always forms D_mid: with q.mid = 0 (the updated rate: the linear hat, or
  // strain_rate = "updated") it equals sym L and goes unread, which spares those scenes a second
  // instantiation of every gather (compile time) for 3 stores per point
  constexpr bool kWork = What == G2PWhat::Full && Heat;
  Acc total{};
#pragma omp parallel
  {
    const GridGeom gl = g;
    const GridView Gl = G;
    const ParticleView Pl = P;
    const G2PParams ql = q;
    double* const buf = scratch + kGatherScratch * static_cast<std::size_t>(omp_get_thread_num());
    const auto [begin, end] = thread_share(n);
    Acc own{};
    for (std::size_t first = begin; first < end; first += kGatherBlock) {
      const std::size_t last = std::min(first + kGatherBlock, end);
      Gradient L = store_L ? Gradient::of(Pl) + first
                           : Gradient{buf, buf + kGatherBlock, buf + 2 * kGatherBlock, buf + 3 * kGatherBlock};
      if constexpr (kWork) {
        L.wxx = buf + 4 * kGatherBlock;
        L.wyy = buf + 5 * kGatherBlock;
        L.wxy = buf + 6 * kGatherBlock;
      }
#pragma omp simd
      for (std::size_t p = first; p < last; ++p)
        g2p_particle<Shape, FLIP, What, Heat, Contact, false, kWork>(gl, Gl, Pl, p, ql, L, p - first);
      after(first, last, L, own);
    }
#pragma omp critical(smpm_g2p_blocks)
    total.merge(own);
  }
  return total;
}

}  // namespace smpm::kern
