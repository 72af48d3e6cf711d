// What happens to a void after its faces have met: two passes at the end of a step.
//
// merge_closed_faces: the two faces of a void lie in two velocity fields (engine/porous.cpp,
// assign_void_sides) so that a gap narrower than a cell can keep closing; where the fields
// together fill a node they are welded (kern::grid_contact). Once a void has closed the fields
// have no reason to stay apart; kept apart, they leave the compacted material laminated, thin
// layers of the two fields one over the other, and wherever a disturbance later dips a node's
// fill under the weld's threshold the layers move apart independently and slide into each other
// (the points overlap, 1.8 / 2.5 % of the strip's band at h = 2 / 1 um, and the compaction
// front converges about 3 % slow). So a field-1 point whose every node (every node
// its shape function weighs) is filled to the weld's threshold by the two fields together, one
// of them holding both fields (welded), joins field 0 for good: a void that was there has
// closed, or the point lies where the field boundary runs through solid material (then the
// merge spreads until field 1 is the layer whose nodes reach into a void). A point next to an
// open gap has an unfilled node and stays. With four void-face fields (contact.void_face_fields)
// the same holds for a point of any field but 0: full counts all fields, welded any two.
//
// close_cracks: a point that spalled while its void collapsed (tension past the cutoff: zero
// stress, expanded) can end up inside compacted material, at zero pressure among cell-mates
// that carry the shock's. The grid's velocity field is smooth over a cell, so it cannot compress
// one point of a cell apart from the others: the point's excess volume is a sub-cell volume mode
// the grid does not see, and left alone it stays open for good (13 % of the strip's compacted
// points at zero pressure at h = 4 um; the mean pressure 3-8 % low). So within a cell, where a
// group of points (one body and one velocity field) holds both a fractured point (its EOS pressure below
// the cutoff) and a compressed one (P > 0), every point of the group takes the group's density
// (its mass over its volume) and the pressure of the EOS at that density and its unchanged
// energy; a point still in tension past the cutoff stays fractured. The volume moves within the
// group only (the group's volume is conserved) and no energy changes: the exchange does no work,
// as a crack that closes at zero stress does none. A group without a fractured point, or
// without a compressed one (a spall plane in tension), is untouched. (The cell-averaged volume
// of F-bar / "J-bar" methods against volumetric locking is applied only where a crack closes:
// applied over every cell it keeps the points of a weld overlapping.)
#pragma once
#include "dimension.hpp"
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "stencil.hpp"
#include "views.hpp"

namespace SMPM_NS::kern {

// ---- merge_closed_faces ----------------------------------------------------------------------

struct MergeParams {
  double fill = 0.9;     // node volume (sum over the fields of sum_p w V_p) in cells at which a node is full
  double mass_eps = 0.0; // a field with at most this mass at a node is absent there
  double lp = 0.25;      // uGIMP half width in cells (Shape::eval)
};

// out[c] for c < len: the state of the window of N nodes in[c + off[k]], k < N (bit 0 of all,
// bit 1 of any).
template <int N>
inline void window_states(const std::uint8_t* in, const std::ptrdiff_t* off, std::uint8_t* out, int len) {
#pragma omp simd
  for (int c = 0; c < len; ++c) {
    unsigned all = 1u, any = 0u;
    for (int k = 0; k < N; ++k) {
      const unsigned v = in[c + off[k]];
      all &= v;
      any |= v;
    }
    out[c] = static_cast<std::uint8_t>((all & 1u) | (any & 2u));
  }
}

// Points [0, n): field[p] > 0 -> 0 where its nodes are all full and one is welded (two fields
// hold mass there). The grid holds this step's scatter (per field: m, vol; field f at offset
// f G.fstride) in the nodes of box (every node a point's shape function reaches). First each
// node's state (bit 0 full, bit 1 welded) into node_state (3 g.num_nodes() bytes, three images
// indexed by g.node; the box's real columns are written): one byte instead of 2 F doubles per
// node (four fields: contact phase 1.79 -> 1.61 s on 300 steps of the 5 um case). Then, one axis
// at a time, each node takes the states of the N nodes from it along that axis (bit 0 of all,
// bit 1 of any; a periodic axis wraps), from one image into another: after kDim passes a node
// holds the state of the N^kDim block it is the first corner of, and a point reads one byte, at
// the first node of its stencil, instead of N^kDim (docs/performance.md). A point with a zero
// weight (its stencil leaves that node out) reads its nodes one by one, up to the first that is
// not full. Each point is decided on its own from the grid: race-free and the same for any
// thread count.
// Returns the number of points merged.
template <class Shape>
std::size_t merge_closed_faces(const GridGeom& g, const NodeBox& box, const GridView& G, const double* const* x,
                               std::uint8_t* field, std::size_t n, const MergeParams& q, std::uint8_t* node_state) {
  const std::size_t fs = G.fstride;
  double full = q.fill;  // a full node's volume, fill h^kDim
  for (int d = 0; d < kDim; ++d) full *= g.h;
  const NodeBox b = real_nodes(g, box);
  const int lines = b.lines();
  constexpr int kChunk = 64;  // nodes of a line at a time, fields outer: the sums vectorize
#pragma omp parallel for schedule(static)
  for (int r = 0; r < lines; ++r) {
    Idx<kDim> i = b.line_start(r);
    for (int c0 = b.lo[0]; c0 <= b.hi[0]; c0 += kChunk) {
      const int len = std::min(kChunk, b.hi[0] - c0 + 1);
      i[0] = c0;
      const std::size_t k0 = g.node(i);
      double V[kChunk];
      int present[kChunk];
      for (int c = 0; c < len; ++c) V[c] = 0.0, present[c] = 0;
      for (int f = 0; f < G.fields; ++f) {
        const double* vol = G.vol + k0 + f * fs;
        const double* m = G.m + k0 + f * fs;
#pragma omp simd
        for (int c = 0; c < len; ++c) {
          V[c] += vol[c];
          present[c] += m[c] > q.mass_eps;
        }
      }
      for (int c = 0; c < len; ++c)
        node_state[k0 + c] = static_cast<std::uint8_t>(V[c] < full ? 0 : present[c] >= 2 ? 3 : 1);
    }
  }
  // The blocks: per axis the first nodes a stencil can have (S0..S1) and the nodes read (R0..R1).
  constexpr int N = Shape::N;
  // node j of axis d, a periodic axis's ghosts wrapped onto the nodes they stand for (the scatter
  // folded them there)
  const auto wrapped = [&g](int d, int j) {
    return !g.periodic(d) ? j : j < 0 ? j + g.cells(d) : j >= g.cells(d) ? j - g.cells(d) : j;
  };
  std::size_t stride[kDim];
  int S0[kDim], S1[kDim], R0[kDim], R1[kDim];
  for (int d = 0; d < kDim; ++d) {
    stride[d] = g.stride(d);
    R0[d] = g.periodic(d) ? 0 : b.lo[d];
    R1[d] = g.periodic(d) ? g.cells(d) - 1 : b.hi[d];
    S0[d] = g.periodic(d) ? -g.pad : b.lo[d];
    S1[d] = g.periodic(d) ? g.cells(d) - 1 : b.hi[d] - (N - 1);
  }
  const std::uint8_t* in = node_state;  // the node states stay in image 0, the passes alternate 1 and 2
  std::uint8_t* out = node_state + g.num_nodes();
  std::uint8_t* spare = out + g.num_nodes();
  for (int d = 0; d < kDim; ++d) {
    NodeBox w;  // the nodes this pass writes: blocks on the axes done, lines of N on d
    for (int e = 0; e < kDim; ++e) {
      w.lo[e] = e <= d ? S0[e] : R0[e];
      w.hi[e] = e <= d ? S1[e] : R1[e];
    }
    const int wl = w.lines(), cells = g.cells(d);
    const bool wrap = g.periodic(d);
    const auto sd = static_cast<std::ptrdiff_t>(stride[d]);
#pragma omp parallel for schedule(static)
    for (int r = 0; r < wl; ++r) {
      const Idx<kDim> i = w.line_start(r);
      const std::size_t n0 = g.node(i);
      const int len = w.hi[0] - w.lo[0] + 1;
      std::ptrdiff_t off[N];  // from a node to the k-th of its window
      if (d > 0) {  // the same offsets along the whole line
        for (int k = 0; k < N; ++k) off[k] = (wrapped(d, i[d] + k) - i[d]) * sd;
        window_states<N>(in + n0, off, out + n0, len);
        continue;
      }
      // along the line itself: the windows that wrap one by one, the others as one run
      for (int k = 0; k < N; ++k) off[k] = k;
      const int c0 = wrap ? std::clamp(-w.lo[0], 0, len) : 0;
      const int c1 = wrap ? std::clamp(cells - (N - 1) - w.lo[0], c0, len) : len;
      window_states<N>(in + n0 + c0, off, out + n0 + c0, c1 - c0);
      for (int c = 0; c < len; ++c) {
        if (c == c0) c = c1;
        if (c >= len) break;
        const int id = w.lo[0] + c;
        std::ptrdiff_t o[N];
        for (int k = 0; k < N; ++k) o[k] = wrapped(0, id + k) - id;
        window_states<N>(in + n0 + c, o, out + n0 + c, 1);
      }
    }
    in = out;
    std::swap(out, spare);
  }
  std::size_t merged = 0;
  const long cnt = static_cast<long>(n);
#pragma omp parallel for schedule(static) reduction(+ : merged)
  for (long p = 0; p < cnt; ++p) {
    if (field[p] == 0) continue;
    Vec<kDim> u;
    for (int d = 0; d < kDim; ++d) u[d] = (x[d][p] - g.origin(d)) / g.h;
    const Stencil<Shape, kDim> st(u, q.lp);
    bool block = true;  // every weight nonzero, the first node among the blocks'
    for (int d = 0; d < kDim; ++d) {
      block = block && st.base[d] >= S0[d] && st.base[d] <= S1[d];
      for (int a = 0; a < N; ++a) block = block && st.w[d][a] != 0.0;
    }
    unsigned s;  // bit 0: every node full, bit 1: one welded
    if (block) {
      Idx<kDim> i;
      for (int d = 0; d < kDim; ++d) i[d] = st.base[d];
      s = in[g.node(i)];
    } else {
      // the nodes of nonzero weight one by one, from the node states (image 0)
      std::size_t node[ipow(N, kDim)];
      int m = 1;
      node[0] = 0;
      for (int d = 0; d < kDim; ++d) {
        std::size_t off[N];
        int len = 0;
        for (int a = 0; a < N; ++a) {
          if (st.w[d][a] == 0.0) continue;
          off[len++] = static_cast<std::size_t>(wrapped(d, st.base[d] + a) + g.pad) * stride[d];
        }
        for (int k = m - 1; k >= 0; --k)  // node[k] -> node[k * len + a]: from the last, in place
          for (int a = len - 1; a >= 0; --a) node[k * len + a] = node[k] + off[a];
        m *= len;
      }
      unsigned any = 0u;
      int k = 0;
      for (; k < m; ++k) {
        const unsigned v = node_state[node[k]];
        if (!(v & 1u)) break;
        any |= v;
      }
      s = k == m ? 1u | (any & 2u) : 0u;
    }
    if ((s & 1u) && (s & 2u)) {
      field[p] = 0;
      ++merged;
    }
  }
  return merged;
}

// ---- close_cracks ----------------------------------------------------------------------------

struct CrackArrays {
  const double* m;
  double* V;
  double* p;
  double* s[sym_size(kDim)];  // stress deviator by symmetric component
  double* q;          // artificial viscous pressure, or null
  const double* e;    // specific internal energy, or null (an EOS without energy)
  const double* v[kDim];
  const std::uint8_t* body;
  const std::uint8_t* field;   // velocity field per point, or null (one field)
  const std::uint8_t* select;  // per body: whether this material's call handles it; null: all
};

struct CrackParams {
  double p_min = -1e300;  // tension cutoff [Pa]: a point whose EOS pressure is below it is fractured
  double rho_min = 0.0;   // debris below this density [kg/m^3]: neither counted nor changed
};

struct CrackResult {
  double max_speed = 0.0;   // signal speed of the points set intact [m/s], for the next dt
  std::size_t changed = 0;  // points whose volume was set
};

// The points of cell k are order[cell_start[k] .. cell_start[k + 1]). Cells run in parallel
// (a point is in one cell: race-free; a group's sums go in sorted order, so the result is the
// same for any thread count). P = eos.cold(rho) + eos.gamma_rho() e; speed(rho, P, i) the
// signal speed of intact point i.
template <class Eos, class Speed>
CrackResult close_cracks(const CrackArrays& A, const std::uint32_t* order, const std::uint32_t* cell_start,
                         std::size_t num_keys, const CrackParams& prm, const Eos& eos, Speed&& speed) {
  constexpr int kGroups = 8;  // (body, field) pairs in one cell; more are left alone
  const double gr = eos.gamma_rho();
  const auto energy = [&](std::uint32_t i) { return A.e ? A.e[i] : 0.0; };
  const auto tag_of = [&](std::uint32_t i) { return A.body[i] * 4 + (A.field ? A.field[i] : 0); };  // at most 4 fields
  const auto counted = [&](std::uint32_t i) {
    return (!A.select || A.select[A.body[i]]) && !(A.m[i] < prm.rho_min * A.V[i]);  // debris
  };
  double vmax = 0.0;
  std::size_t changed = 0;
  const long nk = static_cast<long>(num_keys);
#pragma omp parallel for schedule(static) reduction(max : vmax) reduction(+ : changed)
  for (long k = 0; k < nk; ++k) {
    const std::uint32_t s0 = cell_start[k], s1 = cell_start[k + 1];
    if (s1 - s0 < 2) continue;
    int tag[kGroups], nfr[kGroups], ncomp[kGroups];
    double sm[kGroups], sv[kGroups];
    int ng = 0;
    bool any = false;
    for (std::uint32_t s = s0; s < s1; ++s) {
      const std::uint32_t i = order[s];
      if (!counted(i)) continue;
      const int t = tag_of(i);
      int g = 0;
      while (g < ng && tag[g] != t) ++g;
      if (g == ng) {
        if (ng == kGroups) continue;
        tag[g] = t, sm[g] = sv[g] = 0.0, nfr[g] = ncomp[g] = 0, ++ng;
      }
      sm[g] += A.m[i];
      sv[g] += A.V[i];
      // the constitutive update stored zero stress on every fractured point: only those need
      // the EOS (the same expression it tested, so the same answer)
      bool zero = A.p[i] == 0.0;
      for (int c = 0; c < sym_size(kDim); ++c) zero &= A.s[c][i] == 0.0;
      const bool fr = zero && eos.cold(A.m[i] / A.V[i]) + gr * energy(i) < prm.p_min;
      nfr[g] += fr;
      ncomp[g] += A.p[i] > 0.0;
      any |= fr;
    }
    if (!any) continue;
    for (int g = 0; g < ng; ++g) {
      if (nfr[g] == 0 || ncomp[g] == 0) continue;
      const double rho = sm[g] / sv[g];
      const double cold = eos.cold(rho);
      for (std::uint32_t s = s0; s < s1; ++s) {
        const std::uint32_t i = order[s];
        if (!counted(i) || tag_of(i) != tag[g]) continue;
        A.V[i] = A.m[i] / rho;
        const double P = cold + gr * energy(i);
        const bool fr = P < prm.p_min;
        A.p[i] = fr ? 0.0 : P;
        if (fr) {
          for (double* a : A.s) a[i] = 0.0;
          if (A.q) A.q[i] = 0.0;
        } else {
          vmax = std::max(vmax, speed(rho, P, i));
        }
        ++changed;
      }
    }
  }
  return {vmax, changed};
}

}  // namespace SMPM_NS::kern
