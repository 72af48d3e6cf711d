// Plain-pointer views of the particle and grid arrays the kernels work on.
// The engine owns the storage (engine/particles.hpp, engine/grid.hpp); kernels never allocate.
#pragma once
#include "dimension.hpp"
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <utility>

#include <omp.h>

#include "tensor.hpp"

namespace SMPM_NS::kern {

// A box of nodes, lo[d] <= i_d <= hi[d] along every axis d (inclusive; ghosts included, so
// -pad <= lo[d] and hi[d] <= n_d + pad). The grid passes of a step work on the box its
// particles occupy (occupied_nodes, kernels/transfer.hpp): a scene that fills a third of its grid
// (the elastic block) pays for a third of the grid traffic. Empty when hi[d] < lo[d] on an axis.
struct NodeBox {
  int lo[kDim] = {}, hi[kDim] = {-1};
  bool empty() const {
    for (int d = 0; d < kDim; ++d)
      if (hi[d] < lo[d]) return true;
    return false;
  }
  std::size_t nodes() const {
    if (empty()) return 0;
    std::size_t k = 1;
    for (int d = 0; d < kDim; ++d) k *= std::size_t(hi[d] - lo[d] + 1);
    return k;
  }
  // Lines of nodes along x (axis 0) in the box, and the first node of line r: lines are
  // numbered with axis 1 fastest, then axis 2.
  int lines() const {
    if (empty()) return 0;
    int k = 1;
    for (int d = 1; d < kDim; ++d) k *= hi[d] - lo[d] + 1;
    return k;
  }
  Idx<kDim> line_start(int r) const {
    Idx<kDim> i;
    i[0] = lo[0];
    for (int d = 1; d < kDim; ++d) {
      const int len = hi[d] - lo[d] + 1;
      i[d] = lo[d] + r % len;
      r /= len;
    }
    return i;
  }
};

// Largest tile width the colored scatter's scratch block (kernels/transfer.hpp) is sized for, and
// the default (grid.tile_cells is checked against it). The block lives on each thread's stack:
// K FMax (kMaxTile + 3)^D doubles, at most 69 kB at D = 2 and 340 kB at D = 3 with 8 cells (512
// cells per tile); 16 cells at D = 3 would take 1.75 MB.
inline constexpr int kMaxTile = kDim == 2 ? 16 : 8;

// Uniform grid of cells of size h over kDim axes. Node i (one index per axis, 0 <= i_d <= n_d)
// sits at lo_d + i_d h. Node storage carries `pad` ghost layers on every side so that stencils
// of particles near the domain edge never need a bounds check; along a periodic axis the real
// nodes are 0 .. n_d - 1 and the ghosts are folded onto them after each scatter (the halo phase).
struct GridGeom {
  double h = 1.0;
  double lo[kDim] = {};    // origin [m]
  Idx<kDim> n = uniform<kDim>(1);  // cells per axis
  bool wrap[kDim] = {};    // periodic axes
  int pad = 2;             // ghost nodes per side (>= 2 serves every shape function here)
  int tile = kMaxTile;     // tile width in cells (>= 4: the colored scatter needs tile > stencil reach)

  // per axis: cells, origin [m], periodicity, storage length (nodes with ghosts), storage stride
  int cells(int d) const { return n[d]; }
  double origin(int d) const { return lo[d]; }
  bool periodic(int d) const { return wrap[d]; }
  double length(int d) const { return n[d] * h; }  // [m]
  int size(int d) const { return cells(d) + 1 + 2 * pad; }
  std::size_t stride(int d) const {
    std::size_t s = 1;
    for (int e = 0; e < d; ++e) s *= static_cast<std::size_t>(size(e));
    return s;
  }
  std::size_t num_nodes() const { return stride(kDim); }
  // storage lines along x (axis 0): num_nodes() / size(0)
  int num_lines() const { return static_cast<int>(num_nodes() / static_cast<std::size_t>(size(0))); }
  // storage index of node i (components down to -pad), and of the line along x it lies on
  std::size_t node(const Idx<kDim>& i) const {
    std::size_t k = 0;
    for (int d = kDim - 1; d >= 0; --d) k = k * static_cast<std::size_t>(size(d)) + static_cast<std::size_t>(i[d] + pad);
    return k;
  }
  std::size_t node(int i, int j) const { return node(Idx<kDim>{{i, j}}); }
  int line(const Idx<kDim>& i) const { return static_cast<int>(node(i) / static_cast<std::size_t>(size(0))); }
  // the nodes that carry state along axis d: 0 .. n_d - 1 when periodic (ghosts are copies),
  // -pad .. n_d + pad otherwise
  int first_real(int d) const { return periodic(d) ? 0 : -pad; }
  int last_real(int d) const { return periodic(d) ? cells(d) - 1 : cells(d) + pad; }
  // tiles along axis d, tiles in all (numbered with x fastest)
  int tiles(int d) const { return (cells(d) + tile - 1) / tile; }
  int num_tiles() const {
    int k = 1;
    for (int d = 0; d < kDim; ++d) k *= tiles(d);
    return k;
  }
  // cell keys are tile-major: all cells of tile 0 (x fastest), then tile 1, ...
  int cells_per_tile() const {
    int k = 1;
    for (int d = 0; d < kDim; ++d) k *= tile;
    return k;
  }
  std::size_t num_keys() const { return static_cast<std::size_t>(num_tiles()) * cells_per_tile(); }
  NodeBox all_nodes() const {
    NodeBox b;
    for (int d = 0; d < kDim; ++d) {
      b.lo[d] = -pad;
      b.hi[d] = cells(d) + pad;
    }
    return b;
  }
};


// Doubles each array of the velocity fields holds past its last node (engine/grid.hpp): the 3D
// gather loads a line of up to 4 nodes as one 4-double vector and masks the lanes past the
// stencil (kern::load_line), which reads up to 3 doubles past a line that ends the array. 2D
// reads none.
inline constexpr std::size_t kLinePad = kDim == 3 ? 4 : 0;

// With multi-body contact every array holds one block of num_nodes() values per velocity field
// (field f of node n at n + f * fstride); fstride is 0 with a single field. Vector quantities
// are one array per axis.
struct GridView {
  double* m;              // mass [kg/m]
  double* p[kDim];        // momentum [kg m/s per m]; after the grid update with scatter_velocity, p / m
  double* f[kDim];        // force [N/m]
  double* v[kDim];        // updated velocity (after forces and boundary conditions) [m/s]
  double* dv[kDim];       // v_new - v_old, for FLIP (null when unused)
  // several fields only (null otherwise): mass gradient sum_p m_p grad w_ip [kg/m^2], volume
  // sum w V [m^2], and the kinetic energy the contact step dissipated at the node per unit of
  // the node's total mass [J/kg] (the same value in every field's slot), which the heating
  // gather hands to the particles (kern::grid_contact, kern::g2p_particle)
  double* gm[kDim] = {};
  double* vol = nullptr;
  double* heat = nullptr;
  std::size_t fstride = 0;  // num_nodes() with several fields, 0 with one
  int fields = 1;
  // The view of field f alone (a one-field view into the same storage).
  GridView field(int fi) const {
    GridView w = *this;
    const std::size_t o = static_cast<std::size_t>(fi) * fstride;
    const auto shift = [o](double*& a) {
      if (a) a += o;
    };
    shift(w.m);
    shift(w.vol);
    shift(w.heat);
    for (int d = 0; d < kDim; ++d)
      for (double** a : {&w.p[d], &w.f[d], &w.v[d], &w.dv[d], &w.gm[d]}) shift(*a);
    w.fstride = 0;
    w.fields = 1;
    return w;
  }
};

// The box clipped to the nodes that carry state (GridGeom::first_real, last_real) on every axis.
inline NodeBox real_nodes(const GridGeom& g, const NodeBox& b) {
  NodeBox r = b;
  for (int d = 0; d < kDim; ++d) {
    r.lo[d] = std::max(b.lo[d], g.first_real(d));
    r.hi[d] = std::min(b.hi[d], g.last_real(d));
  }
  return r;
}

// Every node of box b, line by line along axis 0, the lines shared out over the threads (omp
// parallel for, static; a line's nodes in order on one thread): node(acc, i, n) for node i at
// storage index n, then line_end(acc, line) with the line's storage index (GridGeom::line). acc
// (an Acc per line, value-initialized) carries the line's sums: wall reactions, contact losses.
// With run: the nodes [a, e) of axis 0 that span(i) names for the line of node i go to
// run(acc, n_a, e - a) together, in their place in the line's order (a loop that vectorizes
// over nodes that need no per-node case, such as the nodes off the walls); the line's other
// nodes to node().
template <class Acc, class Node, class Span, class Run, class LineEnd>
inline void for_each_node_by_line(const GridGeom& g, const NodeBox& b, Node&& node, Span&& span, Run&& run,
                                  LineEnd&& line_end) {
  const int lines = b.lines();
#pragma omp parallel for schedule(static)
  for (int r = 0; r < lines; ++r) {
    Idx<kDim> i = b.line_start(r);
    const int line = g.line(i);
    const auto [a0, e0] = span(static_cast<const Idx<kDim>&>(i));
    const int a = std::max(a0, b.lo[0]), e = std::max(a, std::min(e0, b.hi[0] + 1));
    Acc acc{};
    for (i[0] = b.lo[0]; i[0] < a; ++i[0]) node(acc, static_cast<const Idx<kDim>&>(i), g.node(i));
    if (e > a) {
      i[0] = a;
      run(acc, g.node(i), e - a);
    }
    for (i[0] = e; i[0] <= b.hi[0]; ++i[0]) node(acc, static_cast<const Idx<kDim>&>(i), g.node(i));
    line_end(acc, line);
  }
}
template <class Acc, class Node, class LineEnd>
inline void for_each_node_by_line(const GridGeom& g, const NodeBox& b, Node&& node, LineEnd&& line_end) {
  for_each_node_by_line<Acc>(
      g, b, node, [](const Idx<kDim>&) { return std::pair<int, int>{0, 0}; }, [](Acc&, std::size_t, int) {}, line_end);
}
// The same without per-line sums: node(i, n).
template <class Node>
inline void for_each_node_by_line(const GridGeom& g, const NodeBox& b, Node&& node) {
  struct None {};
  for_each_node_by_line<None>(
      g, b, [&](None&, const Idx<kDim>& i, std::size_t n) { node(i, n); }, [](None&, int) {});
}

// Particle fields the transfer kernels read or write, one array per component: position and
// velocity by axis, the stress deviator by symmetric component (kernels/tensor.hpp's order; at
// D = 2, s_zz = -(s_xx + s_yy)), C row major. Total stress = s - p I. The velocity gradient is
// not a particle field: the gather passes that form it write it where a Gradient points.
struct ParticleView {
  static constexpr int K = sym_size(kDim);
  double* x[kDim];
  double* v[kDim];
  const double* m;
  double* V;            // current volume [m^2 per unit thickness]
  double* s[K];         // stress deviator [Pa]
  double* p;            // pressure [Pa]
  // APIC affine matrix C = B D^-1 (null unless the transfer is APIC).
  double* C[kDim * kDim];
  // Artificial viscous pressure, added to p in the internal force (null: no viscosity).
  const double* q;
  // Specific internal energy (null when not tracked), heated by the APIC transfer dissipation.
  double* e;
  // Several velocity fields (two-body contact, separated void faces): the field of each
  // particle, Particles::field (null: one field).
  const std::uint8_t* field_of = nullptr;
  std::size_t field(std::size_t i) const { return field_of ? field_of[i] : 0; }
  // The affine matrix by row r and column c.
  SMPM_INLINE double* affine(int r, int c) const { return C[r * kDim + c]; }
};

// The calling thread's share [begin, end) of n items in an omp parallel region: contiguous
// shares in thread order, as schedule(static) splits a loop.
inline std::pair<std::size_t, std::size_t> thread_share(std::size_t n) {
  const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
  const std::size_t nt = static_cast<std::size_t>(omp_get_num_threads());
  const std::size_t q = n / nt, r = n % nt;
  const std::size_t begin = t * q + std::min(t, r);
  return {begin, begin + q + (t < r ? 1 : 0)};
}

// Items [begin, end) of the parts [p0, p1) when n items of weights weight(k) >= 0 are cut into
// nparts contiguous parts in order, part p starting at the first item before which at least
// p / nparts of the total weight lies (items of weight 0 may fall to either neighbour). The
// parts cover [0, n) exactly once.
template <class Weight>
std::pair<std::size_t, std::size_t> weighted_parts(std::size_t n, Weight&& weight, std::uint64_t p0, std::uint64_t p1,
                                                   std::uint64_t nparts) {
  if (p0 == 0 && p1 == nparts) return {0, n};
  std::uint64_t total = 0;
  for (std::size_t k = 0; k < n; ++k) total += weight(k);
  const std::uint64_t from = total * p0 / nparts, to = total * p1 / nparts;
  std::size_t begin = n, end = n;
  std::uint64_t before = 0;  // the weight of the items before k
  for (std::size_t k = 0; k < n; ++k) {
    if (begin == n && before >= from) begin = k;
    if (p1 < nparts && before >= to) {
      end = k;
      break;
    }
    before += weight(k);
  }
  return {std::min(begin, end), end};
}

// The calling thread's share [begin, end) of n items of weights weight(k) >= 0: its part of
// weighted_parts in thread order. Every thread scans all n weights.
template <class Weight>
std::pair<std::size_t, std::size_t> thread_share(std::size_t n, Weight&& weight) {
  const std::uint64_t t = static_cast<std::uint64_t>(omp_get_thread_num());
  return weighted_parts(n, weight, t, t + 1, static_cast<std::uint64_t>(omp_get_num_threads()));
}

// A run of items [b, e) that two threads split as they go: the front thread takes chunks from
// the front, the back thread from the back, each a quarter of what is left (at least one item),
// until they meet. Each thread's items are one contiguous run, and the two finish within about
// one chunk of each other whatever the items cost. A chunk is claimed with one compare-and-swap
// on the pair's word; the items' own work needs no atomics. init() may be called by both
// threads: the first call sets the run, a later one (the same run) leaves it.
class alignas(64) PairSplit {
 public:
  void init(std::uint32_t b, std::uint32_t e) {
    std::uint64_t unset = kUnset;
    v_.compare_exchange_strong(unset, pack(b, e), std::memory_order_acq_rel);
  }
  // The next chunk [c0, c1) of the calling side; false when the run is used up.
  bool claim(bool front, std::uint32_t& c0, std::uint32_t& c1) {
    std::uint64_t v = v_.load(std::memory_order_acquire);
    for (;;) {
      const std::uint32_t lo = static_cast<std::uint32_t>(v), hi = static_cast<std::uint32_t>(v >> 32);
      if (lo >= hi) return false;
      const std::uint32_t c = std::max<std::uint32_t>(1, (hi - lo) / 4);
      c0 = front ? lo : hi - c;
      c1 = c0 + c;
      const std::uint64_t next = front ? pack(c1, hi) : pack(lo, c0);
      if (v_.compare_exchange_weak(v, next, std::memory_order_acq_rel)) return true;
    }
  }

 private:
  static constexpr std::uint64_t kUnset = ~std::uint64_t{0};
  static std::uint64_t pack(std::uint32_t b, std::uint32_t e) { return std::uint64_t{b} | (std::uint64_t{e} << 32); }
  std::atomic<std::uint64_t> v_{kUnset};
};

inline constexpr int kMaxPairs = 32;  // thread pairs that split their items; further threads take fixed shares

// In an omp parallel region, body(k0, k1) for each run [k0, k1) of the calling thread's items
// of [0, n) of weights weight(k): threads go in pairs, a pair's run holds about 2 / threads of
// the total weight (weighted_parts), and its two threads split it as they go (PairSplit: the
// even thread from the front, the odd one from the back), so the two finish together whatever
// the items cost; an odd last thread, or one past kMaxPairs pairs, takes its own share
// (thread_share). Each thread's items are one contiguous run. splits: kMaxPairs splits, freshly
// reset (constructed), shared by the team.
template <class Weight, class Body>
void for_each_split(PairSplit* splits, std::size_t n, Weight&& weight, Body&& body) {
  const int t = omp_get_thread_num(), nt = omp_get_num_threads(), pair = t / 2;
  if ((t ^ 1) < nt && pair < kMaxPairs) {
    const auto [b, e] = weighted_parts(n, weight, 2 * pair, 2 * pair + 2, nt);
    PairSplit& split = splits[pair];
    split.init(static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(e));
    std::uint32_t c0, c1;
    while (split.claim(t % 2 == 0, c0, c1)) body(std::size_t{c0}, std::size_t{c1});
  } else {
    const auto [b, e] = thread_share(n, weight);
    if (b < e) body(b, e);
  }
}

// Where a gather pass that forms the velocity gradient L = sum_i v_i grad w_ip^T [1/s] writes it
// and the constitutive update reads it: the block buffer of kern::g2p_blocks, which holds it for
// one block of points (element 0 = the block's first point), or arrays over all points (g2p,
// constitutive_update: the tests' and benchmarks' separate passes).
// With the mid-step energy (kern::g2p_blocks' heating USL pass, q.mid = 0.5) it also carries the
// symmetric mid-step rate D_mid (w: sym of sum_i (v_i^old + v_i^new) / 2 grad w_i^T),
// whose work with the old stress is the energy increment (kern::constitutive_range); L itself is
// always the updated one. Null where no pass writes it.
struct Gradient {
  static constexpr int K = sym_size(kDim);
  double* L[kDim * kDim] = {};  // row major
  double* w[K] = {};            // mid-step rate by symmetric component (null: not written)
  SMPM_INLINE double*& at(int r, int c) { return L[r * kDim + c]; }
  SMPM_INLINE double* at(int r, int c) const { return L[r * kDim + c]; }
  // the mid-step rate's symmetric component k (kernels/tensor.hpp's order)
  SMPM_INLINE double*& work(int k) { return w[k]; }
  SMPM_INLINE double* work(int k) const { return w[k]; }
  Gradient operator+(std::size_t k) const {
    Gradient g;
    for (int c = 0; c < kDim * kDim; ++c) g.L[c] = L[c] + k;
    for (int c = 0; c < K; ++c) g.w[c] = w[c] ? w[c] + k : nullptr;
    return g;
  }
};

}  // namespace SMPM_NS::kern
