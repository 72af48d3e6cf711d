// Particle-to-grid scatter and grid-to-particle gather: one templated body per direction,
// serving every shape function, both transfers (APIC, FLIP/PIC) and both schemes (USL, MUSL).
// Race handling lives in the iteration (colored tiles, serial, or atomic adds for comparison),
// never in the particle body.
#pragma once
#include "dimension.hpp"
#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "stencil.hpp"
#include "views.hpp"

namespace SMPM_NS::kern {

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
  std::size_t node(const Idx<kDim>& i) const { return g.node(i); }
  std::size_t stride(int d) const { return g.stride(d); }
  std::size_t field_offset(std::size_t f) const { return f * G.fstride; }
  inline void add_momentum(std::size_t n, const double* q) const {
    for (int d = 0; d < kDim; ++d) Add::add(G.p[d][n], q[d]);
  }
  inline void add_mass_force(std::size_t n, double m, const double* f) const {
    Add::add(G.m[n], m);
    for (int d = 0; d < kDim; ++d) Add::add(G.f[d][n], f[d]);
  }
  inline void add_contact(std::size_t n, const double* gm, double vol) const {
    for (int d = 0; d < kDim; ++d) Add::add(G.gm[d][n], gm[d]);
    Add::add(G.vol[n], vol);
  }
  inline void add_volume(std::size_t n, double vol) const { Add::add(G.vol[n], vol); }
};

// Nodes a tile's particles reach along an axis: cells c in [t0, t0 + tile) touch nodes c - 1 ..
// c + 2 (every shape function here), so the block spans [t0 - 1, t0 + tile + 1]: tile + 3 nodes.
inline constexpr int tile_span(int tile) { return tile + 3; }

// Slots per node of a scatter's scratch block: the mass, then kDim momentum and kDim force
// components; with two-body contact also kDim mass-gradient components and the volume, with a
// weld the volume alone.
struct Slot {
  static constexpr int mass = 0, momentum = 1, force = 1 + kDim, contact = 1 + 2 * kDim;
  static constexpr int count(bool contact, bool normals) {
    return contact ? (normals ? 2 + 3 * kDim : 2 + 2 * kDim) : 1 + 2 * kDim;
  }
};

// K values per node (Slot); velocity fields follow each other, span^kDim nodes apart.
template <int K>
struct TileSink {
  double* s;
  Idx<kDim> lo;
  int span;
  std::size_t node(const Idx<kDim>& i) const {
    std::size_t k = 0;
    for (int d = kDim - 1; d >= 0; --d) k = k * static_cast<std::size_t>(span) + static_cast<std::size_t>(i[d] - lo[d]);
    return k;
  }
  std::size_t stride(int d) const {
    std::size_t k = 1;
    for (int e = 0; e < d; ++e) k *= static_cast<std::size_t>(span);
    return k;
  }
  std::size_t field_offset(std::size_t f) const { return f * static_cast<std::size_t>(ipow(span, kDim)); }
  inline void add_momentum(std::size_t n, const double* q) const {
    for (int d = 0; d < kDim; ++d) s[K * n + Slot::momentum + d] += q[d];
  }
  inline void add_mass_force(std::size_t n, double m, const double* f) const {
    s[K * n + Slot::mass] += m;
    for (int d = 0; d < kDim; ++d) s[K * n + Slot::force + d] += f[d];
  }
  inline void add_contact(std::size_t n, const double* gm, double vol) const {
    for (int d = 0; d < kDim; ++d) s[K * n + Slot::contact + d] += gm[d];
    s[K * n + Slot::contact + kDim] += vol;
  }
  inline void add_volume(std::size_t n, double vol) const { s[K * n + Slot::contact] += vol; }
};

// A point's position in grid units, (x - origin) * (1 / h) per axis.
SMPM_INLINE Vec<kDim> grid_units(const GridGeom& g, const ParticleView& P, std::size_t p, double inv_h) {
  Vec<kDim> u;
#pragma GCC unroll 3
  for (int d = 0; d < kDim; ++d) u[d] = (P.x[d][p] - g.origin(d)) * inv_h;
  return u;
}
// Storage index of the stencil node with offsets a, from the index of the stencil's first node
// (formed once per point) and the storage's strides (GridGeom, a sink).
template <class Storage>
SMPM_INLINE std::size_t node_index(const Storage& s, std::size_t first, const Idx<kDim>& a) {
#pragma GCC unroll 3
  for (int d = 0; d < kDim; ++d) first += static_cast<std::size_t>(a[d]) * s.stride(d);
  return first;
}
// The stencil's node i (its offsets a) as grid indices.
template <class St>
SMPM_INLINE Idx<kDim> node_of(const St& st, const Idx<kDim>& a) {
  Idx<kDim> i;
#pragma GCC unroll 3
  for (int d = 0; d < kDim; ++d) i[d] = st.base[d] + a[d];
  return i;
}

// Scatter of one particle p into its velocity field. APIC adds the affine momentum
// m C (x_i - x_p). Contact also scatters the volume, and with Normals the mass gradient (the
// contact normals of two bodies; a weld of void faces needs none). The internal force at node i
// is -V sigma grad w_i (sigma = s - (p + q) I).
template <class Shape, bool APIC, P2GWhat What, class Sink, bool Contact = false, bool Normals = true>
inline void p2g_particle(const GridGeom& g, const Sink& sink, const ParticleView& P, std::uint32_t p,
                         double lp) {
  constexpr int D = kDim;
  const double inv_h = 1.0 / g.h;
  const Stencil<Shape, D> st(grid_units(g, P, p, inv_h), lp);
  const double m = P.m[p];
  double mv[D], mC[D][D] = {};
#pragma GCC unroll 3
  for (int d = 0; d < D; ++d) mv[d] = m * P.v[d][p];
  if constexpr (APIC) {  // grid-unit offsets: fold h in here
#pragma GCC unroll 3
    for (int r = 0; r < D; ++r)
#pragma GCC unroll 3
      for (int c = 0; c < D; ++c) mC[r][c] = m * P.affine(r, c)[p] * g.h;
  }
  double vs[D][D] = {};  // -V sigma / h
  if constexpr (What == P2GWhat::All) {
    const double Vh = P.V[p] * inv_h;
    const double pq = P.q ? P.p[p] + P.q[p] : P.p[p];
#pragma GCC unroll 3
    for (int d = 0; d < D; ++d) vs[d][d] = -Vh * (P.s[d][p] - pq);
    for (int k = D; k < sym_size(D); ++k) {
      const int a = sym_row(D, k), b = sym_col(D, k);
      vs[a][b] = vs[b][a] = -Vh * P.s[k][p];
    }
  }
  const std::size_t foff = Contact ? sink.field_offset(P.field(p)) : 0;
  const double mh = m * inv_h, Vp = Contact ? P.V[p] : 0.0;
  const std::size_t first = sink.node(node_of(st, Idx<D>{})) + foff;
  const auto node = [&](const Idx<D>& a, int) {
    const std::size_t n = node_index(sink, first, a);
    const double w = st.weight(a);
    double q[D];
#pragma GCC unroll 3
    for (int r = 0; r < D; ++r) {
      q[r] = mv[r];
      if constexpr (APIC) {
        double s = mC[r][0] * st.offset(a, 0);
#pragma GCC unroll 3
        for (int c = 1; c < D; ++c) s += mC[r][c] * st.offset(a, c);
        q[r] += s;
      }
      q[r] = w * q[r];
    }
    sink.add_momentum(n, q);
    if constexpr (What == P2GWhat::All) {
      const Vec<D> gr = st.gradient(a);
      double f[D];
#pragma GCC unroll 3
      for (int r = 0; r < D; ++r) {
        f[r] = vs[r][0] * gr[0];
#pragma GCC unroll 3
        for (int c = 1; c < D; ++c) f[r] += vs[r][c] * gr[c];
      }
      sink.add_mass_force(n, w * m, f);
      if constexpr (Contact && Normals) {
        double gm[D];
#pragma GCC unroll 3
        for (int d = 0; d < D; ++d) gm[d] = mh * gr[d];
        sink.add_contact(n, gm, w * Vp);
      }
      if constexpr (Contact && !Normals) sink.add_volume(n, w * Vp);
    }
  };
  // one field: by lines, the fewest instructions on node addresses; several fields: fully
  // unrolled, which measures faster there (docs/performance.md, "What was tried")
  if constexpr (Contact) st.for_each(node);
  else st.for_each_by_line(node);

}

// Scatter of the particles at sorted positions [s0, s1) into a sink.
template <class Shape, bool APIC, P2GWhat What, class Sink, bool Contact = false, bool Normals = true>
inline void p2g_range(const GridGeom& g, const Sink& sink, const ParticleView& P, const std::uint32_t* order,
                      std::size_t s0, std::size_t s1, double lp) {
  for (std::size_t s = s0; s < s1; ++s)
    p2g_particle<Shape, APIC, What, Sink, Contact, Normals>(g, sink, P, order[s], lp);
}

// Colored iteration over tiles: tiles of one color (tile parity along every axis) touch
// disjoint nodes (tile width > stencil reach), so they run in parallel with plain adds; the
// 2^kDim colors run one after another. Each tile accumulates K values per node into an
// L1/L2-resident scratch block covering its footprint (body(block, s0, s1) for the particles at
// sorted positions [s0, s1)), then the block is handed node by node to flush(values,
// grid_node, f), clipped to the node storage (a partial last tile's block reaches past it).
// With F fields (F <= FMax, the scratch's capacity) the block holds F sub-blocks of span^kDim
// nodes, field f's at f * K * span^kDim; fields(s0, s1) says which of them the tile's particles
// scatter into (bit f), and only those are zeroed and flushed (a four-field run's tiles mostly
// hold two or three). Fixed tile order and fixed particle order within a tile make every node's
// sum independent of the thread count.
struct TileBlock {
  double* s;
  Idx<kDim> lo;  // the block's first node
  int span;
};
struct OneField {
  unsigned operator()(std::uint32_t, std::uint32_t) const { return 1u; }
};

// Tile t's block of nodes, and its lines along x clipped to the node storage: f(line's first
// node in the grid, its offset in the block's nodes, its length).
template <class F>
inline void for_each_block_line(const GridGeom& g, const TileBlock& blk, F&& f) {
  int len[kDim];
  for (int d = 0; d < kDim; ++d) len[d] = std::min(blk.span, g.cells(d) + g.pad - blk.lo[d] + 1);
  int lines = 1;
  for (int d = 1; d < kDim; ++d) lines *= len[d];
  for (int r = 0; r < lines; ++r) {
    Idx<kDim> i = blk.lo;
    std::size_t off = 0, span_d = 1;
    int rest = r;
    for (int d = 1; d < kDim; ++d) {
      span_d *= static_cast<std::size_t>(blk.span);
      const int o = rest % len[d];
      rest /= len[d];
      i[d] += o;
      off += static_cast<std::size_t>(o) * span_d;
    }
    f(g.node(i), off, len[0]);
  }
}

template <int K, int FMax = 1, class Body, class Flush, class Fields = OneField>
void for_each_tile_colored(const GridGeom& g, const std::uint32_t* cell_start, Body&& body, Flush&& flush, int F = 1,
                           Fields&& fields = Fields{}) {
  if (F < 1 || F > FMax) throw std::invalid_argument("colored scatter: " + std::to_string(F) + " velocity fields, at most " + std::to_string(FMax));
  int T[kDim];
  for (int d = 0; d < kDim; ++d) T[d] = g.tiles(d);
  const int cpt = g.cells_per_tile();
  const int span = tile_span(g.tile);
  const std::size_t block = static_cast<std::size_t>(K) * ipow(span, kDim);
#pragma omp parallel
  {
    alignas(64) double scratch[K * FMax * ipow(tile_span(kMaxTile), kDim)];
    for (int color = 0; color < (1 << kDim); ++color) {
      int nt[kDim], count = 1;
      for (int d = 0; d < kDim; ++d) {
        nt[d] = (T[d] - ((color >> d) & 1) + 1) / 2;
        count *= nt[d];
      }
#pragma omp for schedule(dynamic, 1)
      for (int k = 0; k < count; ++k) {
        // the tile's indices: this color's parity plus twice its place among the color's tiles
        Idx<kDim> lo;
        std::size_t t = 0, tstride = 1;
        int rest = k;
        for (int d = 0; d < kDim; ++d) {
          const int td = ((color >> d) & 1) + 2 * (rest % nt[d]);
          rest /= nt[d];
          t += static_cast<std::size_t>(td) * tstride;
          tstride *= static_cast<std::size_t>(T[d]);
          lo[d] = td * g.tile - 1;
        }
        const std::uint32_t s0 = cell_start[t * cpt], s1 = cell_start[(t + 1) * cpt];
        if (s0 == s1) continue;
        const TileBlock blk{scratch, lo, span};
        const unsigned used = F > 1 ? fields(s0, s1) : 1u;
        for (int f = 0; f < F; ++f)
          if ((used >> f) & 1u) std::fill(scratch + f * block, scratch + (f + 1) * block, 0.0);
        body(blk, s0, s1);
        for (int f = 0; f < F; ++f) {
          if (!((used >> f) & 1u)) continue;
          for_each_block_line(g, blk, [&](std::size_t n0, std::size_t off, int len) {
            const double* sr = scratch + f * block + K * off;
            for (int i = 0; i < len; ++i) flush(sr + K * i, n0 + i, f);
          });
        }
      }
    }
  }
}

// The nodes the particles binned in cell_start reach: the union of the node blocks of the
// occupied tiles (tile_span), which holds every node a colored scatter writes and every node a
// gather reads. Along a periodic axis it spans all nodes (the fold and the ghost fill need
// them). Empty without particles.
inline NodeBox occupied_nodes(const GridGeom& g, const std::uint32_t* cell_start) {
  const int NT = g.num_tiles();
  const std::size_t cpt = static_cast<std::size_t>(g.cells_per_tile());
  int T[kDim], t0[kDim], t1[kDim];
  for (int d = 0; d < kDim; ++d) {
    T[d] = g.tiles(d);
    t0[d] = T[d];
    t1[d] = -1;
  }
#pragma omp parallel for schedule(static) reduction(min : t0[:kDim]) reduction(max : t1[:kDim])
  for (int t = 0; t < NT; ++t) {
    if (cell_start[t * cpt] == cell_start[(t + 1) * cpt]) continue;
    int rest = t;
    for (int d = 0; d < kDim; ++d) {
      const int td = rest % T[d];
      rest /= T[d];
      t0[d] = std::min(t0[d], td);
      t1[d] = std::max(t1[d], td);
    }
  }
  if (t1[0] < 0) return NodeBox{};
  const int last = tile_span(g.tile) - 1;  // a tile block's nodes: [t tile - 1, t tile - 1 + last]
  NodeBox b;
  for (int d = 0; d < kDim; ++d) {
    const int top = g.cells(d) + g.pad;
    b.lo[d] = g.periodic(d) ? -g.pad : t0[d] * g.tile - 1;
    b.hi[d] = g.periodic(d) ? top : std::min(t1[d] * g.tile - 1 + last, top);
  }
  return b;
}

// Colored scatter of mass, momentum and internal force (or momentum only); with Contact into
// G.fields velocity fields (two bodies: two, with mass gradients; void faces: two or four, with
// volumes).
template <class Shape, bool APIC, P2GWhat What, bool Contact = false, bool Normals = true>
void p2g_colored(const GridGeom& g, const GridView& G, const ParticleView& P, const std::uint32_t* order,
                 const std::uint32_t* cell_start, double lp) {
  constexpr int K = Slot::count(Contact, Normals), FMax = Contact ? (Normals ? 2 : 4) : 1;
  const int F = Contact ? G.fields : 1;
  for_each_tile_colored<K, FMax>(
      g, cell_start,
      [&](const TileBlock& b, std::uint32_t s0, std::uint32_t s1) {
        p2g_range<Shape, APIC, What, TileSink<K>, Contact, Normals>(g, TileSink<K>{b.s, b.lo, b.span}, P, order, s0,
                                                                    s1, lp);
      },
      [&](const double* v, std::size_t n0, int f) {
        const std::size_t n = n0 + f * G.fstride;
        for (int d = 0; d < kDim; ++d) G.p[d][n] += v[Slot::momentum + d];
        if constexpr (What == P2GWhat::All) {
          G.m[n] += v[Slot::mass];
          for (int d = 0; d < kDim; ++d) G.f[d][n] += v[Slot::force + d];
          if constexpr (Contact && Normals) {
            for (int d = 0; d < kDim; ++d) G.gm[d][n] += v[Slot::contact + d];
            G.vol[n] += v[Slot::contact + kDim];
          }
          if constexpr (Contact && !Normals) G.vol[n] += v[Slot::contact];
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
  // by a fraction of dt |v|.) Per axis; -inf / +inf where there is no wall.
  Vec<kDim> lo = uniform<kDim>(-1e300), hi = uniform<kDim>(1e300);
};

// Gather for one particle. Velocity: APIC (PIC velocity plus the affine matrix C = B D^-1) or
// the FLIP/PIC blend. Position: moved with the grid velocity. Gradient: L = sum_i v_i grad w_i^T
// from the updated velocity. WorkRate (the USL pass with transfer heating, g2p_blocks): also
// the rate of the energy's work, D_mid = sym sum_i v_i^mid grad w_i^T with v_i^mid = v_i^new -
// q.mid (v_i^new - v_i^old) (p holds v^old, the grid update's scatter_velocity; FLIP takes
// v^old = v^new - dv), into Lout's work rate. The grid's kinetic energy changes by exactly dt
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
// field's own the scatter loss then counts.) Needs the scatter's velocity p / m in p (the grid
// update's scatter_velocity, ghosts filled).
//
// PureFlip (FLIP with flip_alpha = 1, velocity pass): v_p += sum_i w_ip dv_i alone; the PIC sum of
// the blend, multiplied by 1 - alpha = 0, is neither read nor formed (half the pass's grid reads).
// Moves point p with velocity v over q.dt: a periodic axis wraps it (the second test also
// catches x + L rounding up to origin + L; selects, not branches, so the loop stays
// vectorizable; L = 0 on other axes leaves x as it is), a wall puts it back on the wall.
SMPM_INLINE void move_point(const GridGeom& g, const ParticleView& P, std::size_t p, const G2PParams& q,
                            const double* v) {
#pragma GCC unroll 3
  for (int d = 0; d < kDim; ++d) {
    double c = P.x[d][p] + q.dt * v[d];
    const double o = g.origin(d), L = g.periodic(d) ? g.cells(d) * g.h : 0.0;
    c = c < o ? c + L : c;
    c = c >= o + L ? c - L : c;
    P.x[d][p] = std::min(std::max(c, q.lo[d]), q.hi[d]);
  }
}

// What the gather sums over a point's nodes (grid units: gradients and offsets per cell).
struct GatherSums {
  double v[kDim] = {}, dv[kDim] = {};    // sum w v_i, FLIP: sum w dv_i
  double L[kDim][kDim] = {};             // sum v_i grad w^T
  double W[kDim][kDim] = {};             // sum v_i^mid grad w^T (the work rate)
  double B[kDim][kDim] = {};             // sum w v_i (x_i - x_p)^T
  double v2 = 0, r2 = 0, d2 = 0, qc = 0;  // sum w |v_i|^2, the scatter loss, FLIP: sum w |dv_i|^2, contact loss
};

// L = sum_i v_i grad w_i^T [1/s] into Lout at li; with the work rate (WorkRate) also its
// symmetric part sym(W) [1/s], the off-diagonal entries as 0.5 (W_ab + W_ba).
template <bool WorkRate>
SMPM_INLINE void store_gradient(const GatherSums& S, double inv_h, const Gradient& Lout, std::size_t li) {
#pragma GCC unroll 3
  for (int r = 0; r < kDim; ++r)
#pragma GCC unroll 3
    for (int c = 0; c < kDim; ++c) Lout.at(r, c)[li] = S.L[r][c] * inv_h;
  if constexpr (WorkRate) {
#pragma GCC unroll 3
    for (int d = 0; d < kDim; ++d) Lout.work(d)[li] = S.W[d][d] * inv_h;
    for (int k = kDim; k < sym_size(kDim); ++k) {
      const int a = sym_row(kDim, k), b = sym_col(kDim, k);
      Lout.work(k)[li] = 0.5 * (S.W[a][b] + S.W[b][a]) * inv_h;
    }
  }
}

// The node loop of g2p_particle: every sum its template arguments ask for, node by node in
// storage order. u, uC: the point's old velocity and C h (the heating gather's scatter loss).
template <class Shape, bool FLIP, G2PWhat What, bool Heat, int Contact, bool PureFlip, bool WorkRate>
SMPM_INLINE GatherSums gather_sums(const GridGeom& g, const GridView& G, const Stencil<Shape, kDim>& st,
                                   std::size_t foff, double mid, const Vec<kDim> u, const Mat<kDim> uC) {
  constexpr int D = kDim;
  GatherSums S;
  constexpr bool kAffine = !FLIP && What != G2PWhat::PositionGradient;
  constexpr bool kGrad = What != G2PWhat::Velocity || (kAffine && Shape::apic_gradient);
  const std::size_t first = g.node(node_of(st, Idx<D>{})) + foff;
  auto node = [&](const Idx<D>& a, int) __attribute__((always_inline)) {
    const std::size_t n = node_index(g, first, a);
    const double w = st.weight(a);
    double gv[D], lv[D];  // the node's velocity; the mid-step one of the work rate
#pragma GCC unroll 3
    for (int d = 0; d < D; ++d) {
      gv[d] = PureFlip ? 0.0 : G.v[d][n];
      lv[d] = gv[d];
      // USL: the work rate from the mid-step velocity (v_old + v_new) / 2 of the node, v_old the
      // scatter's velocity after the walls; FLIP: v_old = v_new - dv (the grid update's increment)
      if constexpr (WorkRate && FLIP) lv[d] = gv[d] - mid * G.dv[d][n];
      else if constexpr (WorkRate) lv[d] = gv[d] - mid * (gv[d] - G.p[d][n]);
      if constexpr (!PureFlip) S.v[d] += w * gv[d];
    }
    if constexpr (Heat) {
      double r[D], dn[D];
#pragma GCC unroll 3
      for (int d = 0; d < D; ++d) {
        if constexpr (FLIP) {  // v_i^old = v_i - dv_i
          dn[d] = G.dv[d][n];
          r[d] = u[d] - gv[d] + dn[d];
        } else {  // p holds the scatter's velocity p / m here
          r[d] = u[d];
#pragma GCC unroll 3
          for (int c = 0; c < D; ++c) r[d] += uC(d, c) * st.offset(a, c);
          r[d] -= G.p[d][n];
        }
      }
      S.v2 += w * norm2(gv);
      if constexpr (FLIP) S.d2 += w * norm2(dn);
      S.r2 += w * norm2(r);
      if constexpr (FLIP ? Contact != 0 : Contact == 2) S.qc += w * G.heat[n];  // FLIP: a weld's loss too
    }
    if constexpr (FLIP && What != G2PWhat::PositionGradient) {
#pragma GCC unroll 3
      for (int d = 0; d < D; ++d) S.dv[d] += w * G.dv[d][n];
    }
    if constexpr (kGrad) {
      const Vec<D> gr = st.gradient(a);
#pragma GCC unroll 3
      for (int r = 0; r < D; ++r)
#pragma GCC unroll 3
        for (int c = 0; c < D; ++c) {
          S.L[r][c] += gv[r] * gr[c];
          if constexpr (WorkRate) S.W[r][c] += lv[r] * gr[c];
        }
    }
    if constexpr (kAffine && !Shape::apic_gradient) {
#pragma GCC unroll 3
      for (int r = 0; r < D; ++r)
#pragma GCC unroll 3
        for (int c = 0; c < D; ++c) S.B[r][c] += w * gv[r] * st.offset(a, c);
    }
  };
  if constexpr (D == 3) st.for_each_by_line(node);
  else st.for_each(node);
  return S;
}

// The affine field's kinetic energy per unit mass, sum_ab C_ab^2 D_b [grid units], C and the
// inertia D per axis.
SMPM_INLINE double affine_energy(const double (*C)[kDim], const double* Dn) {
  double e = 0.0;
#pragma GCC unroll 3
  for (int c = 0; c < kDim; ++c) {
    double s = C[0][c] * C[0][c];
#pragma GCC unroll 3
    for (int r = 1; r < kDim; ++r) s += C[r][c] * C[r][c];
    e = c == 0 ? s * Dn[c] : e + s * Dn[c];
  }
  return e;
}

// 1/2 (a - sum_d v_d^2 - b): the least-squares residual of a gather, a = sum w |v_i|^2 (+ the
// scatter loss), b the affine share.
SMPM_INLINE double residual(double a, const double* v, double b) {
#pragma GCC unroll 3
  for (int d = 0; d < kDim; ++d) a -= v[d] * v[d];
  return a - b;
}

// Gather for one particle. Velocity: APIC (PIC velocity plus the affine matrix C = B D^-1) or
// the FLIP/PIC blend. Position: moved with the grid velocity. Gradient: L = sum_i v_i grad w_i^T
// from the updated velocity. WorkRate (the USL pass with transfer heating, g2p_blocks): also
// the rate of the energy's work, D_mid = sym sum_i v_i^mid grad w_i^T with v_i^mid = v_i^new -
// q.mid (v_i^new - v_i^old) (p holds v^old, the grid update's scatter_velocity; FLIP takes
// v^old = v^new - dv), into Lout's work rate. The grid's kinetic energy changes by exactly dt
// f_i . (v^old + v^new) / 2 in the explicit update, and with q.mid = 0.5 the constitutive
// update's work dt V sigma : D_mid with the stress that made f_i (kern::constitutive_range,
// mid-step energy) is exactly its negative: the step conserves energy node by node, partly
// filled nodes at void faces and free surfaces included (with the work over L from v^new it
// loses dt^2 |f_i|^2 / (2 m_i) per node, most where m_i is small). The kinematics (volume,
// deviator, viscosity) take L from v^new, the symplectic choice: with the mid-step rate there
// too an undamped mode of frequency w grew by about (w dt)^2 / 4 per step in amplitude, and in
// thin ligaments of a porous run the round-off grew without bound.
//
// Heat (APIC; FLIP with USL): the transfers' loss of kinetic energy (the point's kinetic energy
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
// field's own the scatter loss then counts.) Needs the scatter's velocity p / m in p (the grid
// update's scatter_velocity, ghosts filled).
//
// PureFlip (FLIP with flip_alpha = 1, velocity pass): v_p += sum_i w_ip dv_i alone; the PIC sum of
// the blend, multiplied by 1 - alpha = 0, is neither read nor formed (half the pass's grid reads).
template <class Shape, bool FLIP, G2PWhat What, bool Heat = false, int Contact = 0, bool PureFlip = false,
          bool WorkRate = false>
SMPM_INLINE void g2p_particle(const GridGeom& g, const GridView& G, const ParticleView& P, std::size_t p,
                              const G2PParams& q, const Gradient& Lout, std::size_t li) {
  static_assert(!PureFlip || (FLIP && What == G2PWhat::Velocity), "PureFlip is the FLIP velocity pass");
  static_assert(!WorkRate || (What == G2PWhat::Full && Heat), "the work rate is the heating USL pass's");
  constexpr int D = kDim;
  constexpr bool kAffine = !FLIP && What != G2PWhat::PositionGradient;
  static_assert(!Heat || kAffine || (FLIP && What == G2PWhat::Full),
                "transfer heating is defined for the APIC velocity gather and the FLIP USL gather");
  const double inv_h = 1.0 / g.h;
  const Stencil<Shape, D> st(grid_units(g, P, p, inv_h), q.lp);
  Vec<D> u{};  // old v_p and C_p h
  Mat<D> uC{};
  if constexpr (Heat) {
#pragma GCC unroll 3
    for (int r = 0; r < D; ++r) {
      u[r] = P.v[r][p];
      if constexpr (!FLIP)
#pragma GCC unroll 3
        for (int c = 0; c < D; ++c) uC(r, c) = P.affine(r, c)[p] * g.h;
    }
  }
  // with Contact the view always carries field_of (Simulation::pview): the lookup without
  // field()'s null test vectorizes
  const std::size_t foff = Contact ? static_cast<std::size_t>(P.field_of[p]) * G.fstride : 0;
  const GatherSums S = gather_sums<Shape, FLIP, What, Heat, Contact, PureFlip, WorkRate>(g, G, st, foff, q.mid, u, uC);
  double Dn[D] = {}, C[D][D] = {}, affine = 0.0;  // inertia, C (grid units), affine energy
  if constexpr (kAffine) {
    if constexpr (!Shape::apic_gradient || Heat)
#pragma GCC unroll 3
      for (int d = 0; d < D; ++d) Dn[d] = st.inertia(d);
#pragma GCC unroll 3
    for (int r = 0; r < D; ++r)
#pragma GCC unroll 3
      for (int c = 0; c < D; ++c) {
        C[r][c] = Shape::apic_gradient ? S.L[r][c] : S.B[r][c] / Dn[c];
        P.affine(r, c)[p] = C[r][c] * inv_h;
      }
    if constexpr (Heat) {
      affine = affine_energy(C, Dn);
      P.e[p] += 0.5 * residual(S.r2 + S.v2, S.v, affine) + S.qc;
    }
  }
  if constexpr (Heat && FLIP) {
    // FLIP/PIC blend v = alpha v_F + (1 - alpha) v_PIC, v_F = v_p + sum w dv_i, v_PIC = sum w v_i:
    // its loss is alpha (FLIP's) + (1 - alpha) (PIC's) + alpha (1 - alpha) 1/2 |v_F - v_PIC|^2,
    // FLIP's 1/2 (sum w |dv_i|^2 - |sum w dv_i|^2) and PIC's the scatter and gather losses
    // above; each share >= 0 and their sum over the points exactly the transfers' loss
    const double al = q.flip_alpha;
    double fd[D];
#pragma GCC unroll 3
    for (int d = 0; d < D; ++d) fd[d] = u[d] + S.dv[d] - S.v[d];
    P.e[p] += 0.5 * (al * residual(S.d2, S.dv, 0.0) + (1.0 - al) * residual(S.r2 + S.v2, S.v, 0.0) +
                     al * (1.0 - al) * norm2(fd)) + S.qc;
  }
  if constexpr (What != G2PWhat::PositionGradient) {
#pragma GCC unroll 3
    for (int d = 0; d < D; ++d) {
      double* v = P.v[d];
      if constexpr (PureFlip) v[p] = v[p] + S.dv[d];
      else if constexpr (FLIP) v[p] = q.flip_alpha * (v[p] + S.dv[d]) + (1.0 - q.flip_alpha) * S.v[d];
      else v[p] = S.v[d];
    }
  }
  if constexpr (What != G2PWhat::Velocity) {
    move_point(g, P, p, q, S.v);
    if constexpr (Heat && !FLIP && !Shape::constant_D && What == G2PWhat::Full) {
      // D of the linear hat and uGIMP depends on where the point sits in its cell. The affine
      // kinetic energy the next scatter sees (and Simulation::energy counts) is the one at the
      // new position: the difference is heat of the move, so total energy still balances
      const Stencil<Shape, D> moved(grid_units(g, P, p, inv_h), q.lp);
      double Dm[D];
#pragma GCC unroll 3
      for (int d = 0; d < D; ++d) Dm[d] = moved.inertia(d);
      P.e[p] += 0.5 * (affine - affine_energy(C, Dm));
    }
    store_gradient<WorkRate>(S, inv_h, Lout, li);
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
// back are saved. The heating USL pass's work rate D_mid (L.work(k)) is always in the
// last three blocks. Acc: the per-thread
// result of `after`, merged with Acc::merge (whose order must not matter). The gathered values
// are those of g2p, bitwise (the same particle body; tests/test_kernels.cpp). The block size:
// blocks of 256-2048 points made the gather 2-6 ns per point slower on one thread (each block
// restarts the prefetch streams of both loops, about 20 arrays); 4096-16384 measured alike
// (docs/performance.md).
inline constexpr std::size_t kGatherBlock = 8192;
inline constexpr std::size_t kGatherScratch = (kDim * kDim + sym_size(kDim)) * kGatherBlock;  // doubles per thread

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
      Gradient L = Gradient::of(Pl) + first;
      if (!store_L)
        for (int r = 0; r < kDim; ++r)
          for (int c = 0; c < kDim; ++c) L.at(r, c) = buf + (r * kDim + c) * kGatherBlock;
      if constexpr (kWork)
        for (int k = 0; k < sym_size(kDim); ++k) L.work(k) = buf + (kDim * kDim + k) * kGatherBlock;
      // 2D: vectorized across points; 3D: one point at a time, its 27-node stencil walked line by
      // line (for_each_by_line): the vectorized 3D gather (gather instructions for 27 nodes, 21
      // sums per point) ran the dense 3D bench 13 % slower than this (docs/performance.md)
      if constexpr (kDim == 2) {
#pragma omp simd
        for (std::size_t p = first; p < last; ++p)
          g2p_particle<Shape, FLIP, What, Heat, Contact, false, kWork>(gl, Gl, Pl, p, ql, L, p - first);
      } else {
        for (std::size_t p = first; p < last; ++p)
          g2p_particle<Shape, FLIP, What, Heat, Contact, false, kWork>(gl, Gl, Pl, p, ql, L, p - first);
      }
      after(first, last, L, own);
    }
#pragma omp critical(smpm_g2p_blocks)
    total.merge(own);
  }
  return total;
}

}  // namespace SMPM_NS::kern
