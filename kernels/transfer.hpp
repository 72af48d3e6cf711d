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

#include "simd.hpp"
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
  static constexpr bool kSlotVectors = false, kFullUnroll = false;
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

// The adds of K values per node (Slot) into a node-major block s, node n's values at K n.
template <int KS>
struct SlotAdds {
  static constexpr int K = KS;
  double* s;
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

// K values per node (Slot); velocity fields follow each other, span^kDim nodes apart.
template <int KS>
struct TileSink : SlotAdds<KS> {
  // 3D: a node's K values span whole 8-double vectors (p2g_colored pads K), added as vectors
  // (scatter_slots)
  static constexpr bool kSlotVectors = kDim == 3 && KS % 8 == 0, kFullUnroll = false;
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
};

// The sums of one cell's points over their common stencil of N^kDim nodes, stencil node k's
// values at K k (kern::p2g_cells): every address a constant once the stencil is unrolled, so the
// sums stay in registers.
template <int KS, int N>
struct CellSink : SlotAdds<KS> {
  static constexpr bool kSlotVectors = false, kFullUnroll = true;
  std::size_t node(const Idx<kDim>&) const { return 0; }
  std::size_t stride(int d) const { return static_cast<std::size_t>(ipow(N, d)); }
  std::size_t field_offset(std::size_t) const { return 0; }
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

// The 3D scatter of one point into a TileSink whose nodes hold whole vectors of values. Every
// node value is a sum of (a scalar of the node) x (a vector of the point): the weight w times
// A (mass, momentum, volume), w (x_i - x_p)_c times B_c (APIC's affine momentum), the gradient
// g_c times F_c (force, mass gradient). With w = w_0(a_0) c(a_1..), the terms of the axes
// e >= 1 are constant along a line of nodes and fold into three vectors per line, so node k of
// a line takes three vector products, w_0[k] P1 + dw_0[k] P2 + w_0[k] (x_i - x_p)_0 P3, and
// one vector add per 8 values into the block, instead of one scalar operation per value. The
// same sums as p2g_particle's node loop up to rounding (grouped differently;
// tests/test_3d_kernels.cpp compares them); each point's order is fixed, so any thread count
// gives the same bits. Measured in docs/performance.md ("3D").
template <class Shape, bool APIC, P2GWhat What, bool Contact, bool Normals, class Sink>
SMPM_INLINE void scatter_slots(const Stencil<Shape, kDim>& st, const Sink& sink, std::size_t first, double m,
                               const double* mv, const double (*mC)[kDim], const double (*vs)[kDim], double mh,
                               double Vp) {
  constexpr int D = kDim, N = Shape::N, K = Sink::K, V = K / 8;
  static_assert(N <= 4, "a line holds at most 4 nodes");
  Slots A[V] = {}, B[D][V] = {}, F[D][V] = {};  // the point's vectors: of w, w (x_i - x_p)_c, g_c
  const auto set = [](Slots* v, int slot, double x) { v[slot / 8][slot % 8] = x; };
#pragma GCC unroll 3
  for (int d = 0; d < D; ++d) set(A, Slot::momentum + d, mv[d]);
  if constexpr (APIC)
#pragma GCC unroll 3
    for (int c = 0; c < D; ++c)
#pragma GCC unroll 3
      for (int r = 0; r < D; ++r) set(B[c], Slot::momentum + r, mC[r][c]);
  if constexpr (What == P2GWhat::All) {
    set(A, Slot::mass, m);
#pragma GCC unroll 3
    for (int c = 0; c < D; ++c)
#pragma GCC unroll 3
      for (int r = 0; r < D; ++r) set(F[c], Slot::force + r, vs[r][c]);
    if constexpr (Contact && Normals) {
#pragma GCC unroll 3
      for (int c = 0; c < D; ++c) set(F[c], Slot::contact + c, mh);
      set(A, Slot::contact + D, Vp);
    }
    if constexpr (Contact && !Normals) set(A, Slot::contact, Vp);
  }
  // axis 0's weights w0, derivatives dw0 and w0 (x_i - x_p)_0 per node of a line; through
  // memory, so that each node reads them by broadcast loads (load ports), not lane shuffles
  alignas(32) double s0[3][4] = {};
#pragma GCC unroll 4
  for (int k = 0; k < N; ++k) {
    s0[0][k] = st.w[0][k];
    s0[1][k] = st.dw[0][k];
    s0[2][k] = st.w[0][k] * ((st.base[0] + k) - st.xg[0]);
  }
  asm volatile("" : "+m"(s0));
  st.for_each_line([&](const Idx<D>& a, const auto& lw) __attribute__((always_inline)) {
    double* const line = sink.s + K * node_index(sink, first, a);
    const double c = lw.c;
    // node k of the line takes w0[k] P1 + dw0[k] P2 + w0[k] (x_i - x_p)_0 P3: the terms of axes
    // e >= 1, constant along the line, folded into the line's vectors
    Slots P1[V], P2[V], P3[V];
#pragma GCC unroll 2
    for (int v = 0; v < V; ++v) {
      Slots t = A[v];
      if constexpr (APIC)
#pragma GCC unroll 3
        for (int e = 1; e < D; ++e) t = madd(lw.off[e], B[e][v], t);
      P1[v] = c * t;
      if constexpr (What == P2GWhat::All) {
#pragma GCC unroll 3
        for (int e = 1; e < D; ++e) P1[v] = madd(lw.ce[e], F[e][v], P1[v]);
        P2[v] = c * F[0][v];
      }
      if constexpr (APIC) P3[v] = c * B[0][v];
    }
#pragma GCC unroll 4
    for (int k = 0; k < N; ++k) {
      double* const s = line + K * k;
#pragma GCC unroll 2
      for (int v = 0; v < V; ++v) {
        Slots y;
        __builtin_memcpy(&y, s + 8 * v, sizeof y);
        y = madd(s0[0][k], P1[v], y);
        if constexpr (What == P2GWhat::All) y = madd(s0[1][k], P2[v], y);
        if constexpr (APIC) y = madd(s0[2][k], P3[v], y);
        __builtin_memcpy(s + 8 * v, &y, sizeof y);
      }
    }
  });
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
  // 3D: a node's values as vectors (scatter_slots); one field: by lines, the fewest
  // instructions on node addresses; several fields, and a cell's sums: fully unrolled, which
  // measures faster there (docs/performance.md, "What was tried")
  if constexpr (Sink::kSlotVectors)
    scatter_slots<Shape, APIC, What, Contact, Normals>(st, sink, first, m, mv, mC, vs, mh, Vp);
  else if constexpr (Contact || Sink::kFullUnroll) st.for_each(node);
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
// Each thread takes one run of consecutive tiles of a color, the same region of the grid in
// every color: the nodes that neighbouring tiles of different colors share then stay in one
// core's cache. (Tiles handed out one at a time interleave the threads, and those nodes' cache
// lines moved between the cores at every color: the porous 2D scatter at 1e5 points scaled
// 1.50 with 2 threads, its threads each 25 % slower than one thread alone; docs/performance.md,
// "Thread scaling".) The runs come from for_each_split, weighted by points: the two threads of a
// pair split their run as they go, one from each end, and reach the color's barrier together
// whatever the tiles cost. Which thread scatters a tile changes no sum: the tiles of one color
// touch disjoint nodes.
// With F fields (F <= FMax, the scratch's capacity) the block holds F sub-blocks of span^kDim
// nodes, field f's at f * K * span^kDim; fields(s0, s1) says which of them the tile's particles
// scatter into (bit f), and only those are zeroed and flushed (a four-field run's tiles mostly
// hold two or three). Fixed tile order and fixed particle order within a tile make every node's
// sum independent of the thread count.
struct TileBlock {
  double* s;
  Idx<kDim> lo;  // the block's first node
  int span;
  std::size_t tile;  // the tile's index: its cells' keys start at tile * cells_per_tile
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
  PairSplit splits[1 << kDim][kMaxPairs];
#pragma omp parallel
  {
    alignas(64) double scratch[K * FMax * ipow(tile_span(kMaxTile), kDim)];
    for (int color = 0; color < (1 << kDim); ++color) {
      int nt[kDim], count = 1;
      for (int d = 0; d < kDim; ++d) {
        nt[d] = (T[d] - ((color >> d) & 1) + 1) / 2;
        count *= nt[d];
      }
      // tile k of this color: its index t among all tiles, its block's first node lo (this color's
      // parity plus twice its place among the color's tiles)
      const auto tile = [&](int k, Idx<kDim>& lo) {
        std::size_t t = 0, tstride = 1;
        int rest = k;
        for (int d = 0; d < kDim; ++d) {
          const int td = ((color >> d) & 1) + 2 * (rest % nt[d]);
          rest /= nt[d];
          t += static_cast<std::size_t>(td) * tstride;
          tstride *= static_cast<std::size_t>(T[d]);
          lo[d] = td * g.tile - 1;
        }
        return t;
      };
      const auto weight = [&](std::size_t k) {
        Idx<kDim> lo;
        const std::size_t t = tile(static_cast<int>(k), lo);
        return std::uint64_t{cell_start[(t + 1) * cpt] - cell_start[t * cpt]};
      };
      const auto run_tile = [&](std::size_t k) {
        Idx<kDim> lo;
        const std::size_t t = tile(static_cast<int>(k), lo);
        const std::uint32_t s0 = cell_start[t * cpt], s1 = cell_start[(t + 1) * cpt];
        if (s0 == s1) return;
        const TileBlock blk{scratch, lo, span, t};
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
      };
      for_each_split(splits[color], static_cast<std::size_t>(count), weight, [&](std::size_t k0, std::size_t k1) {
        for (std::size_t k = k0; k < k1; ++k) run_tile(k);
      });
#pragma omp barrier
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

// The block index of the first stencil node of the tile's cell j (cells numbered x fastest; the
// tile's first cell is the block's node lo + 1 on every axis), for a shape whose stencil is its
// cell's.
template <class Shape, int K>
SMPM_INLINE std::size_t cell_first_node(const GridGeom& g, const TileSink<K>& sink, int j) {
  Idx<kDim> first;
  for (int d = 0; d < kDim; ++d) {
    first[d] = sink.lo[d] + 1 + j % g.tile + Shape::cell_first;
    j /= g.tile;
  }
  return sink.node(first);
}

// MUSL's one-field momentum remap of one tile's points for a shape whose stencil is its cell's
// (Shape::cell_stencil) of more than 2 x 2 nodes (the cubic B-spline; the linear hat's goes by
// p2g_cell_vectors): the points of a cell, sorted together, share their N^kDim nodes, so
// their contributions are summed in registers (CellSink) and added to the tile's block once per
// cell. Point by point, consecutive points of a cell would add to the same block values through
// memory, each add waiting for the one before. A node's value is its cells' sums added in cell
// order, each sum in point order: fixed for any thread count. cs: the tile's cpt + 1 cell
// starts; the tile's first cell is the block's node lo + 1 on every axis.
template <class Shape, bool APIC, int K>
inline void p2g_cells(const GridGeom& g, const TileSink<K>& sink, const ParticleView& P, const std::uint32_t* order,
                      const std::uint32_t* cs, double lp) {
  constexpr int N = Shape::N, Nodes = ipow(N, kDim);
  const int cpt = g.cells_per_tile();
  for (int j = 0; j < cpt; ++j) {
    if (cs[j] == cs[j + 1]) continue;
    alignas(64) double acc[K * Nodes] = {};
    const CellSink<K, N> cell{{acc}};
    for (std::uint32_t s = cs[j]; s < cs[j + 1]; ++s)
      p2g_particle<Shape, APIC, P2GWhat::Momentum>(g, cell, P, order[s], lp);
    const std::size_t n0 = cell_first_node<Shape>(g, sink, j);
#pragma GCC unroll 64
    for (int k = 0; k < Nodes; ++k) {
      double* const v = sink.s + K * node_index(sink, n0, Stencil<Shape, kDim>::digits(k));
      const double* const a = acc + K * k;
#pragma GCC unroll 3
      for (int d = 0; d < kDim; ++d) v[Slot::momentum + d] += a[Slot::momentum + d];
    }
  }
}

// The one-field scatter of one tile's points (mass, momentum and force, or MUSL's momentum alone)
// for a 2D shape whose stencil is its cell's 2 x 2 nodes (the linear hat): each value of the
// cell's nodes (Slot) is one vector over its four nodes (Line, node k = a_0 + 2 a_1), summed
// over the cell's points in registers and added to the tile's block once per cell. Point by
// point (p2g_particle) the full scatter makes 20 scalar adds through the block and about 40
// scalar products per point. Each point's node terms take p2g_particle's operations in its
// order, lane by lane (w = w_0 w_1, g = (dw_0 w_1, w_0 dw_1), q_r = w (m v_r [+ m C_r . (x_i -
// x_p)]), f_r = vs_r0 g_0 + vs_r1 g_1); only the grouping of the sums differs from the point by
// point scatter (a cell's points first, then the cell into the block): the momentum alone is
// p2g_cells' bit for bit. cs: the tile's cpt + 1 cell starts; the tile's first cell is the
// block's node lo + 1 on every axis.
template <class Shape, bool APIC, P2GWhat What, int K>
inline void p2g_cell_vectors(const GridGeom& g, const TileSink<K>& sink, const ParticleView& P,
                             const std::uint32_t* order, const std::uint32_t* cs, double lp) {
  static_assert(kDim == 2 && Shape::N == 2 && Shape::cell_stencil, "a cell's stencil of 2 x 2 nodes");
  const int cpt = g.cells_per_tile();
  const double inv_h = 1.0 / g.h, h = g.h;
  const double* const pq_q = P.q;
  for (int j = 0; j < cpt; ++j) {
    if (cs[j] == cs[j + 1]) continue;
    Line M = {}, Q0 = {}, Q1 = {}, F0 = {}, F1 = {};
    for (std::uint32_t s = cs[j]; s < cs[j + 1]; ++s) {
      const std::uint32_t p = order[s];
      const Stencil<Shape, 2> st(grid_units(g, P, p, inv_h), lp);
      const double m = P.m[p];
      const double mv0 = m * P.v[0][p], mv1 = m * P.v[1][p];
      const Line wx = {st.w[0][0], st.w[0][1], st.w[0][0], st.w[0][1]};
      const Line wy = {st.w[1][0], st.w[1][0], st.w[1][1], st.w[1][1]};
      const Line dx = {st.dw[0][0], st.dw[0][1], st.dw[0][0], st.dw[0][1]};
      const Line dy = {st.dw[1][0], st.dw[1][0], st.dw[1][1], st.dw[1][1]};
      const Line w = wx * wy, g0 = dx * wy, g1 = wx * dy;
      Line q0 = Line{mv0, mv0, mv0, mv0}, q1 = Line{mv1, mv1, mv1, mv1};
      if constexpr (APIC) {  // grid-unit offsets: h folded into m C
        const Line x0 = Line{double(st.base[0]), double(st.base[0] + 1), double(st.base[0]), double(st.base[0] + 1)} - st.xg[0];
        const Line x1 = Line{double(st.base[1]), double(st.base[1]), double(st.base[1] + 1), double(st.base[1] + 1)} - st.xg[1];
        q0 = q0 + ((m * P.affine(0, 0)[p] * h) * x0 + (m * P.affine(0, 1)[p] * h) * x1);
        q1 = q1 + ((m * P.affine(1, 0)[p] * h) * x0 + (m * P.affine(1, 1)[p] * h) * x1);
      }
      Q0 += w * q0;
      Q1 += w * q1;
      if constexpr (What == P2GWhat::All) {
        const double Vh = P.V[p] * inv_h;
        const double pq = pq_q ? P.p[p] + pq_q[p] : P.p[p];
        const double vs00 = -Vh * (P.s[0][p] - pq), vs11 = -Vh * (P.s[1][p] - pq), vs01 = -Vh * P.s[2][p];
        M += w * m;
        F0 += vs00 * g0 + vs01 * g1;
        F1 += vs01 * g0 + vs11 * g1;
      }
    }
    const std::size_t n0 = cell_first_node<Shape>(g, sink, j);
#pragma GCC unroll 4
    for (int k = 0; k < 4; ++k) {
      double* const v = sink.s + K * node_index(sink, n0, Stencil<Shape, kDim>::digits(k));
      v[Slot::momentum] += Q0[k];
      v[Slot::momentum + 1] += Q1[k];
      if constexpr (What == P2GWhat::All) {
        v[Slot::mass] += M[k];
        v[Slot::force] += F0[k];
        v[Slot::force + 1] += F1[k];
      }
    }
  }
}

// Colored scatter of mass, momentum and internal force (or momentum only); with Contact into
// G.fields velocity fields (two bodies: two, with mass gradients; void faces: two or four, with
// volumes). A one-field scatter of a shape whose stencil is its cell's goes cell by cell: the
// linear hat's with a cell's node values as vectors (p2g_cell_vectors), the cubic B-spline's
// MUSL momentum as scalar sums (p2g_cells; a full scatter summed that way, twenty scalar sums
// per cell, measured slower: docs/performance.md).
template <class Shape, bool APIC, P2GWhat What, bool Contact = false, bool Normals = true>
void p2g_colored(const GridGeom& g, const GridView& G, const ParticleView& P, const std::uint32_t* order,
                 const std::uint32_t* cell_start, double lp) {
  constexpr bool kCellVectors = Shape::cell_stencil && Shape::N == 2 && !Contact && kDim == 2;
  constexpr bool kCells = Shape::cell_stencil && !Contact && kDim == 2 && What == P2GWhat::Momentum && !kCellVectors;
  // 3D: whole vectors of 8 values per node (scatter_slots), one cache line for 7 or 8 values
  constexpr int K0 = Slot::count(Contact, Normals), K = kDim == 3 ? (K0 + 7) / 8 * 8 : K0;
  constexpr int FMax = Contact ? (Normals ? 2 : 4) : 1;
  const int F = Contact ? G.fields : 1;
  for_each_tile_colored<K, FMax>(
      g, cell_start,
      [&](const TileBlock& b, std::uint32_t s0, std::uint32_t s1) {
        const TileSink<K> sink{{b.s}, b.lo, b.span};
        if constexpr (kCells) {
          p2g_cells<Shape, APIC, K>(g, sink, P, order, cell_start + b.tile * g.cells_per_tile(), lp);
        } else if constexpr (kCellVectors) {
          p2g_cell_vectors<Shape, APIC, What, K>(g, sink, P, order, cell_start + b.tile * g.cells_per_tile(), lp);
        } else {
          p2g_range<Shape, APIC, What, TileSink<K>, Contact, Normals>(g, sink, P, order, s0, s1, lp);
        }
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

// The node loop of g2p_particle in 2D (3D: gather_sums_by_line; tests/test_3d_kernels.cpp holds
// the two equal): every sum its template arguments ask for, node by node in
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
  st.for_each(node);
  return S;
}

// gather_sums by lines (the 3D gather): the stencil's weight is the product w_0(a_0) c(a_1..),
// so every sum over the nodes is a sum over the lines along axis 0 of (the line's cross weight
// c) x (the line's node values, a vector over a_0), contracted with the 1D weights of axis 0 at
// the end: S_v = sum_k w_0[k] (sum_lines c_line v_line)[k]. The line values load as one vector
// (contiguous nodes), each sum takes one multiply and one add per line and component instead of
// per node, and the weight products are formed once per line. The same sums as gather_sums up
// to rounding (grouped differently; tests/test_3d_kernels.cpp compares them); each point's order
// is fixed, so any thread count gives the same bits. Measured against the node-by-node loop in
// docs/performance.md ("3D").
template <class Shape, bool FLIP, G2PWhat What, bool Heat, int Contact, bool PureFlip, bool WorkRate>
SMPM_INLINE GatherSums gather_sums_by_line(const GridGeom& g, const GridView& G, const Stencil<Shape, kDim>& st,
                                           std::size_t foff, double mid, const Vec<kDim> u, const Mat<kDim> uC) {
  constexpr int D = kDim, N = Shape::N;
  static_assert(N <= 4, "a line holds at most 4 nodes");
  constexpr bool kAffine = !FLIP && What != G2PWhat::PositionGradient;
  constexpr bool kGrad = What != G2PWhat::Velocity || (kAffine && Shape::apic_gradient);
  constexpr bool kB = kAffine && !Shape::apic_gradient;
  constexpr bool kDv = FLIP && What != G2PWhat::PositionGradient;
  constexpr bool kQc = Heat && (FLIP ? Contact != 0 : Contact == 2);
  Line w0 = {}, dw0 = {}, o0 = {};  // axis 0: weights, derivatives, offsets x_i - x_p
#pragma GCC unroll 4
  for (int k = 0; k < N; ++k) {
    w0[k] = st.w[0][k];
    dw0[k] = st.dw[0][k];
    o0[k] = (st.base[0] + k) - st.xg[0];
  }
  // per component r: sum_lines c v_r (Av), c_e v_r with c_e the cross weight with the
  // derivative on axis e >= 1 (Ag), c off_e v_r (Ab); Aw.. the same of the work-rate velocity
  Line Av[D] = {}, Ag[D][D] = {}, Ab[D][D] = {}, Awv[D] = {}, Awg[D][D] = {}, Adv[D] = {};
  Line Ae2 = {}, Ad2 = {}, Aqc = {};  // heat: sum w (|v_i|^2 + |r_i|^2) (the two always add), FLIP's d2, qc
  Line M0[D];  // C h (x_i - x_p)_0 along a line, per component
#pragma GCC unroll 3
  for (int d = 0; d < D; ++d) M0[d] = uC(d, 0) * o0;
  const std::size_t first = g.node(node_of(st, Idx<D>{})) + foff;
  st.for_each_line([&](const Idx<D>& a, const auto& lw) __attribute__((always_inline)) {
    const std::size_t n = node_index(g, first, a);
    const double c = lw.c;
    Line gv[D], e2 = {}, d2 = {};
#pragma GCC unroll 3
    for (int d = 0; d < D; ++d) {
      gv[d] = PureFlip ? Line{} : load_line<N>(G.v[d] + n);
      if constexpr (!PureFlip) Av[d] = madd(c, gv[d], Av[d]);
      if constexpr (kGrad)
#pragma GCC unroll 3
        for (int e = 1; e < D; ++e) Ag[e][d] = madd(lw.ce[e], gv[d], Ag[e][d]);
      if constexpr (kB)
#pragma GCC unroll 3
        for (int e = 1; e < D; ++e) Ab[e][d] = madd(c * lw.off[e], gv[d], Ab[e][d]);
      Line dn = {};
      if constexpr (kDv || (Heat && FLIP) || (WorkRate && FLIP)) dn = load_line<N>(G.dv[d] + n);
      if constexpr (kDv) Adv[d] = madd(c, dn, Adv[d]);
      if constexpr (WorkRate) {
        // the mid-step velocity, as gather_sums
        Line lv;
        if constexpr (FLIP) lv = madd(-mid, dn, gv[d]);
        else lv = madd(-mid, gv[d] - load_line<N>(G.p[d] + n), gv[d]);
        Awv[d] = madd(c, lv, Awv[d]);
#pragma GCC unroll 3
        for (int e = 1; e < D; ++e) Awg[e][d] = madd(lw.ce[e], lv, Awg[e][d]);
      }
      if constexpr (Heat) {
        Line r;
        if constexpr (FLIP) {
          r = u[d] - gv[d] + dn;
          d2 = madd(dn, dn, d2);
        } else {
          double rb = u[d];
#pragma GCC unroll 3
          for (int e = 1; e < D; ++e) rb += uC(d, e) * lw.off[e];
          r = (rb + M0[d]) - load_line<N>(G.p[d] + n);
        }
        e2 = madd(r, r, madd(gv[d], gv[d], e2));
      }
    }
    if constexpr (Heat) {
      Ae2 = madd(c, e2, Ae2);
      if constexpr (FLIP) Ad2 = madd(c, d2, Ad2);
      if constexpr (kQc) Aqc = madd(c, load_line<N>(G.heat + n), Aqc);
    }
  });
  GatherSums S;
#pragma GCC unroll 3
  for (int d = 0; d < D; ++d) {
    if constexpr (!PureFlip) S.v[d] = lane_sum(Av[d] * w0);
    if constexpr (kDv) S.dv[d] = lane_sum(Adv[d] * w0);
    if constexpr (kGrad) {
      S.L[d][0] = lane_sum(Av[d] * dw0);
#pragma GCC unroll 3
      for (int e = 1; e < D; ++e) S.L[d][e] = lane_sum(Ag[e][d] * w0);
    }
    if constexpr (WorkRate) {
      S.W[d][0] = lane_sum(Awv[d] * dw0);
#pragma GCC unroll 3
      for (int e = 1; e < D; ++e) S.W[d][e] = lane_sum(Awg[e][d] * w0);
    }
    if constexpr (kB) {
      S.B[d][0] = lane_sum(Av[d] * (w0 * o0));
#pragma GCC unroll 3
      for (int e = 1; e < D; ++e) S.B[d][e] = lane_sum(Ab[e][d] * w0);
    }
  }
  if constexpr (Heat) {
    S.v2 = lane_sum(Ae2 * w0);  // S.r2 stays 0: g2p_particle reads S.r2 + S.v2
    if constexpr (FLIP) S.d2 = lane_sum(Ad2 * w0);
    if constexpr (kQc) S.qc = lane_sum(Aqc * w0);
  }
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
  GatherSums S;
  if constexpr (D == 3)
    S = gather_sums_by_line<Shape, FLIP, What, Heat, Contact, PureFlip, WorkRate>(g, G, st, foff, q.mid, u, uC);
  else
    S = gather_sums<Shape, FLIP, What, Heat, Contact, PureFlip, WorkRate>(g, G, st, foff, q.mid, u, uC);
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
void g2p_loop(const GridGeom& g, const GridView& G, const ParticleView& P, std::size_t n, const G2PParams& q,
              const Gradient& L) {
#pragma omp parallel
  {
    const GridGeom gl = g;
    const GridView Gl = G;
    const ParticleView Pl = P;
    const G2PParams ql = q;
    const Gradient Ll = L;
    if constexpr (kDim == 2) {
#pragma omp for simd schedule(static)
      for (std::size_t p = 0; p < n; ++p)
        g2p_particle<Shape, FLIP, What, Heat, Contact, PureFlip>(gl, Gl, Pl, p, ql, Ll, p);
    } else {  // one point at a time, its lines as vectors (gather_sums_by_line)
#pragma omp for schedule(static)
      for (std::size_t p = 0; p < n; ++p)
        g2p_particle<Shape, FLIP, What, Heat, Contact, PureFlip>(gl, Gl, Pl, p, ql, Ll, p);
    }
  }
}

// The FLIP velocity pass with flip_alpha = 1 (MUSL, pure FLIP) takes the PureFlip body: the same
// velocities, up to the sign of a zero. L: arrays over the n points for the passes that form the
// velocity gradient (What != Velocity); the velocity pass takes none.
template <class Shape, bool FLIP, G2PWhat What, bool Heat = false, int Contact = 0>
void g2p(const GridGeom& g, const GridView& G, const ParticleView& P, std::size_t n, const G2PParams& q,
         const Gradient& L = {}) {
  if constexpr (FLIP && What == G2PWhat::Velocity && !Heat && !Contact) {
    if (q.flip_alpha == 1.0) return g2p_loop<Shape, FLIP, What, Heat, Contact, true>(g, G, P, n, q, L);
  }
  g2p_loop<Shape, FLIP, What, Heat, Contact, false>(g, G, P, n, q, L);
}

// The pass that forms L (USL's gather, MUSL's position pass) with the work that reads L done
// block by block right behind it: each thread gathers its runs of the points (for_each_split
// over units of kGatherUnit points: the two threads of a pair split their points as they go,
// so a run of costlier points - plastic, shocked, fractured - does not leave one waiting) in
// blocks of up to kGatherBlock points and, after each block, calls after(first, last, L, acc) on it
// while the block's L is in cache (the engine's constitutive update; L.xx[i] ... is the
// gradient of point first + i). Thread t's buffer is at scratch + t * kGatherScratch (D^2 +
// D (D + 1) / 2 blocks of kGatherBlock doubles: 448 KiB in 2D, 960 KiB in 3D): L in the first D^2
// blocks, the heating USL pass's work rate D_mid (L.work(k)) in the others. L is never stored on
// the particles: that would cost D^2 doubles per point, and 8 D^2 B per point of writes (and
// write-allocates) per step; what the statistics read from it, `after` keeps. Acc: the per-thread
// result of `after`, merged with Acc::merge (whose order must not matter). The gathered values
// are those of g2p, bitwise (the same particle body; tests/test_kernels.cpp). The block size:
// blocks of 256-2048 points made the gather 2-6 ns per point slower on one thread (each block
// restarts the prefetch streams of both loops, about 20 arrays); 4096-16384 measured alike
// (docs/performance.md).
inline constexpr std::size_t kGatherBlock = 8192;
inline constexpr std::size_t kGatherUnit = 256;  // points per item of the threads' split (for_each_split)
inline constexpr std::size_t kGatherScratch = (kDim * kDim + sym_size(kDim)) * kGatherBlock;  // doubles per thread

template <class Shape, bool FLIP, G2PWhat What, bool Heat, int Contact, class Acc, class After>
Acc g2p_blocks(const GridGeom& g, const GridView& G, const ParticleView& P, std::size_t n, const G2PParams& q,
               double* scratch, After&& after) {
  static_assert(What != G2PWhat::Velocity, "the velocity pass forms no L");
  // the heating USL pass always forms D_mid: with q.mid = 0 (the updated rate: the linear hat, or
  // strain_rate = "updated") it equals sym L and goes unread, which spares those scenes a second
  // instantiation of every gather (compile time) for 3 stores per point
  constexpr bool kWork = What == G2PWhat::Full && Heat;
  Acc total{};
  PairSplit splits[kMaxPairs];
#pragma omp parallel
  {
    double* const buf = scratch + kGatherScratch * static_cast<std::size_t>(omp_get_thread_num());
    Acc own{};
    const auto points = [&](std::size_t begin, std::size_t end) {
      // locals of this call, which the particle stores cannot alias (through the closure's
      // references GCC reloads them per point and does not vectorize: the gather 2x slower)
      const GridGeom gl = g;
      const GridView Gl = G;
      const ParticleView Pl = P;
      const G2PParams ql = q;
      for (std::size_t first = begin; first < end; first += kGatherBlock) {
        const std::size_t last = std::min(first + kGatherBlock, end);
        Gradient L;
        for (int r = 0; r < kDim; ++r)
          for (int c = 0; c < kDim; ++c) L.at(r, c) = buf + (r * kDim + c) * kGatherBlock;
        if constexpr (kWork)
          for (int k = 0; k < sym_size(kDim); ++k) L.work(k) = buf + (kDim * kDim + k) * kGatherBlock;
        // 2D: vectorized across points; 3D: one point at a time, each line of its stencil one
        // vector (gather_sums_by_line; the 3D gather vectorized across points, by gather
        // instructions for 27 nodes, was slower: docs/performance.md)
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
    };
    // the points in runs of whole units (the last one partial), split between the pairs' threads
    for_each_split(splits, (n + kGatherUnit - 1) / kGatherUnit, [](std::size_t) { return std::uint64_t{1}; },
                   [&](std::size_t u0, std::size_t u1) { points(u0 * kGatherUnit, std::min(u1 * kGatherUnit, n)); });
#pragma omp critical(smpm_g2p_blocks)
    total.merge(own);
  }
  return total;
}

}  // namespace SMPM_NS::kern
