// Plain-pointer views of the particle and grid arrays the kernels work on.
// The engine owns the storage (engine/particles.hpp, engine/grid.hpp); kernels never allocate.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <utility>

#include <omp.h>

#include "tensor.hpp"

namespace smpm::kern {

// A rectangle of nodes, i in [i0, i1], j in [j0, j1] (inclusive; ghosts included, so
// -pad <= i0 and i1 <= nx + pad, the same for j). The grid passes of a step work on the box its
// particles occupy (occupied_nodes, kernels/transfer.hpp): a scene that fills a third of its grid
// (the elastic block) pays for a third of the grid traffic. Empty when i1 < i0 or j1 < j0.
struct NodeBox {
  int i0 = 0, i1 = -1, j0 = 0, j1 = -1;
  bool empty() const { return i1 < i0 || j1 < j0; }
  std::size_t nodes() const { return empty() ? 0 : std::size_t(i1 - i0 + 1) * std::size_t(j1 - j0 + 1); }
};

// Uniform 2D grid of cells of size h. Nodes (i, j), i in [0, nx], j in [0, ny], sit at
// (x0 + i h, y0 + j h). Node storage carries `pad` ghost columns/rows on every side so that
// stencils of particles near the domain edge never need a bounds check; with periodic x the
// real columns are 0..nx-1 and ghosts are folded onto them after each scatter.
struct GridGeom {
  double h = 1.0, x0 = 0.0, y0 = 0.0;
  int nx = 1, ny = 1;   // cells
  int pad = 2;          // ghost nodes per side (>= 2 serves every shape function here)
  int tile = 16;        // tile width in cells (>= 4: the colored scatter needs tile > stencil reach)
  bool periodic_x = false;

  int sx() const { return nx + 1 + 2 * pad; }  // storage row length
  int sy() const { return ny + 1 + 2 * pad; }
  std::size_t num_nodes() const { return static_cast<std::size_t>(sx()) * sy(); }
  // storage index of node (i, j); i, j may be negative down to -pad
  std::size_t node(int i, int j) const {
    return static_cast<std::size_t>(j + pad) * sx() + static_cast<std::size_t>(i + pad);
  }
  int tiles_x() const { return (nx + tile - 1) / tile; }
  int tiles_y() const { return (ny + tile - 1) / tile; }
  int num_tiles() const { return tiles_x() * tiles_y(); }
  // cell keys are tile-major: all cells of tile 0 (row by row), then tile 1, ...
  int cells_per_tile() const { return tile * tile; }
  std::size_t num_keys() const { return static_cast<std::size_t>(num_tiles()) * cells_per_tile(); }
  double length_x() const { return nx * h; }
  double length_y() const { return ny * h; }
  NodeBox all_nodes() const { return NodeBox{-pad, nx + pad, -pad, ny + pad}; }
};


// With multi-body contact every array holds one block of num_nodes() values per velocity field
// (field f of node n at n + f * fstride); fstride is 0 with a single field.
struct GridView {
  double* m;            // mass [kg/m]
  double* px; double* py;  // momentum
  double* fx; double* fy;  // force [N/m]
  double* vx; double* vy;  // updated velocity (after forces and boundary conditions)
  double* dvx; double* dvy;  // v_new - v_old, for FLIP (may be null when unused)
  // several fields only (null otherwise): mass gradient sum_p m_p grad w_ip [kg/m^2], volume
  // sum w V [m^2], and the kinetic energy the contact step dissipated at the node per unit of
  // the node's total mass [J/kg] (the same value in every field's slot), which the heating
  // gather hands to the particles (kern::grid_contact, kern::g2p_particle)
  double* gmx = nullptr; double* gmy = nullptr; double* vol = nullptr; double* heat = nullptr;
  std::size_t fstride = 0;  // num_nodes() with several fields, 0 with one
  int fields = 1;
  // The view of field f alone (a one-field view into the same storage).
  GridView field(int f) const {
    GridView v = *this;
    const std::size_t o = static_cast<std::size_t>(f) * fstride;
    for (double** a : {&v.m, &v.px, &v.py, &v.fx, &v.fy, &v.vx, &v.vy, &v.dvx, &v.dvy, &v.gmx, &v.gmy, &v.vol, &v.heat})
      if (*a) *a += o;
    v.fstride = 0;
    v.fields = 1;
    return v;
  }
};

// Column range of the box's nodes that carry state: periodic x keeps 0..nx-1 (ghosts are copies).
inline void real_columns(const GridGeom& g, const NodeBox& b, int& i0, int& i1) {
  i0 = std::max(b.i0, g.periodic_x ? 0 : -g.pad);
  i1 = std::min(b.i1, g.periodic_x ? g.nx - 1 : g.nx + g.pad);
}

// Particle fields the transfer kernels read or write. Plane strain: stress is the deviator
// (sxx, syy, sxy; szz = -(sxx + syy)) and the pressure p; total stress = s - p I.
struct ParticleView {
  double* x; double* y;
  double* vx; double* vy;
  const double* m;
  double* V;            // current volume [m^2 per unit thickness]
  double* sxx; double* syy; double* sxy; double* p;
  // Velocity gradient L = sum_i v_i grad w_ip^T, set by G2P, read by the constitutive update.
  double* Lxx; double* Lxy; double* Lyx; double* Lyy;
  // APIC affine matrix C = B D^-1 (null unless the transfer is APIC).
  double* Cxx; double* Cxy; double* Cyx; double* Cyy;
  // Artificial viscous pressure, added to p in the internal force (null: no viscosity).
  const double* q;
  // Specific internal energy (null when not tracked), heated by the APIC transfer dissipation.
  double* e;
  // Several velocity fields (two-body contact, separated void faces): the field of each
  // particle, Particles::field (null: one field).
  const std::uint8_t* field_of = nullptr;
  std::size_t field(std::size_t p) const { return field_of ? field_of[p] : 0; }
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

// Where the last gather pass stores the velocity gradient L [1/s] and the constitutive update
// reads it: the particles' own arrays (ParticleView::Lxx...), or a block buffer of
// kern::g2p_blocks that holds it for one block of points (element 0 = the block's first point).
// With the mid-step energy (kern::g2p_blocks' heating USL pass, q.mid = 0.5) it also carries the
// symmetric mid-step rate D_mid (wxx, wyy, wxy: sym of sum_i (v_i^old + v_i^new) / 2 grad w_i^T),
// whose work with the old stress is the energy increment (kern::constitutive_range); L itself is
// always the updated one. Null where no pass writes it.
struct Gradient {
  double* xx; double* xy; double* yx; double* yy;
  double* wxx = nullptr; double* wyy = nullptr; double* wxy = nullptr;
  static Gradient of(const ParticleView& P) { return {P.Lxx, P.Lxy, P.Lyx, P.Lyy}; }
  Gradient operator+(std::size_t k) const {
    const auto off = [k](double* a) { return a ? a + k : nullptr; };
    return {xx + k, xy + k, yx + k, yy + k, off(wxx), off(wyy), off(wxy)};
  }
};

}  // namespace smpm::kern
