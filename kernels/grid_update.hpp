// Grid phases: clear, periodic fold, momentum update with forces and walls, ghost refresh.
#pragma once
#include "dimension.hpp"
#include <cstddef>

#include "views.hpp"

namespace SMPM_NS::kern {

enum class Wall : int { None = 0, Slip = 1, NoSlip = 2 };

// Walls sit on the domain's faces: the low one of axis d at origin_d, the high one at
// origin_d + n_d h (left and right for x, bottom and top for y). A wall constrains every node on
// or beyond it: Slip zeroes the normal velocity, NoSlip every component. A periodic axis has no
// walls.
struct Walls {
  Wall lo[kDim] = {}, hi[kDim] = {};
  bool any() const {
    for (int d = 0; d < kDim; ++d)
      if (lo[d] != Wall::None || hi[d] != Wall::None) return true;
    return false;
  }
};

struct GridUpdateParams {
  double dt = 0.0;
  double gravity[kDim] = {};  // [m/s^2]
  // Nodes with 0 < mass <= mass_eps (a particle's stencil tail, e.g. a linear-hat particle just
  // past a node) move with their momentum only: a force over such a mass would give an
  // arbitrarily large acceleration that the velocity gradient picks up through grad w.
  double mass_eps = 0.0;
  Walls walls;
  bool flip = false;      // also store dv = v_new - v_old
  // Replace the momenta p by the scatter's velocity p / m with the walls applied (0 on
  // empty nodes): the APIC gather reads it for the mid-step velocity of L and for the transfer
  // heating (kernels/transfer.hpp), with no division. The walls' share: a wall node's normal
  // velocity p_n / m, zeroed here, is kinetic energy 1/2 p_n^2 / m that the wall takes out of
  // the grid; measured against the constrained velocity, the heating gather's scatter loss
  // counts it (the cross term of the least-squares split vanishes), so it heats the points at
  // the wall instead of vanishing.
  bool scatter_velocity = false;
};

// Every grid pass works on the nodes of a box b (the step's occupied_nodes, or
// g.all_nodes()); nodes outside it are neither read nor written.

// Reaction of each wall on the material, summed per storage line along x so that the total is
// formed in a fixed order (deterministic for any thread count). row_force has kRowSlots *
// num_lines() entries per call: [low and high wall of each axis (their normal component), the
// kinetic energy the walls removed from the scatter's velocities, 1/2 m |u - u_walls|^2 (J/m)]
// per line (0 outside the box); the caller sums them.
inline constexpr int kRowSlots = 2 * kDim + 1;
void grid_update(const GridGeom& g, const NodeBox& b, const GridView& G, const GridUpdateParams& q,
                 double* row_force);

// Contact between two velocity fields (Bardenhagen et al. 2001). After each field's own update
// (grid_update on G.field(f)), at every node where both fields carry mass and
// sum_f V_f >= volume_fraction h^2 (the fields fill the node's cell: they touch there):
//   weld (separated void faces of one body): both fields take the centre-of-mass velocity, as
//   the single field would; else (two bodies):
//   n = (g_1 - g_0) / |...|, g_f = sum_p m_p grad N_i(x_p) the outward normal of field f
//   (n points from body 1 into body 0)
//   v_cm = (m_0 v_0 + m_1 v_1) / (m_0 + m_1),  d = v_0 - v_cm
//   approaching (d . n < 0): the normal part of d is removed; the tangential part t is
//   removed too when |t| <= mu |d . n| (stick), else reduced by mu |d . n| (Coulomb slip);
//   v_1 follows from momentum conservation. Separating fields (d . n >= 0) move freely.
// Walls are applied again to the corrected velocities. Coulomb contact: the energy a node loses,
// per unit of its mass, goes to G.heat (both fields' slots; 0 where nothing changed), which the
// heating gather adds to the particles' internal energy (kern::g2p_particle). A weld (with the
// scatter velocity in p) gives both fields the merged scatter velocity as well, so that the
// heating gather's scatter loss counts its loss and G.heat stays 0. row_loss sums either.
// G.heat may be null where no gather reads it (void faces under APIC, engine/grid.hpp): then
// only row_loss takes the loss.
struct ContactParams {
  double friction = 0.0;         // Coulomb coefficient mu
  bool weld = false;             // weld, not Coulomb contact
  // Nodal volume sum_f sum_p w V_p needed for contact, in cells. 1: the bodies fill the node's
  // cell, i.e. they touch there. Below 1, nodes at a body's corner or a thin gap count as
  // contact and plough: a block sliding at 1 m/s on a frictionless floor lost 17 % of its speed
  // at 0.9 and was kicked up; at 1 nothing (docs/verification.md).
  double volume_fraction = 1.0;
  bool midstep = false;  // the energy's work takes the mid-step velocity (kern::G2PParams::mid)
};
// row_loss (num_lines() entries, or null): the energy contact removed, summed per storage row.
void grid_contact(const GridGeom& g, const NodeBox& b, const GridView& G, const GridUpdateParams& q,
                  const ContactParams& c, double* row_loss = nullptr);

// MUSL remap: velocity = momentum / mass, walls applied, no forces.
void grid_velocity_from_momentum(const GridGeom& g, const NodeBox& b, const GridView& G, const GridUpdateParams& q);

// Zero the arrays a P2G writes (mass and forces only when `all`), every field.
void clear_grid(const GridGeom& g, const NodeBox& b, const GridView& G, bool all);

// Every periodic axis: add the ghost nodes' sums onto the nodes they stand for (after a scatter;
// axes in order), and copy the real nodes into the ghosts (after the grid update; axes in
// reverse order, so that corner ghosts take filled values), for the arrays given. Called through
// Grid::fold and Grid::fill (engine/grid.hpp), which name the arrays.
void fold_periodic(const GridGeom& g, const NodeBox& b, double* const* arrays, int count);
void fill_periodic_ghosts(const GridGeom& g, const NodeBox& b, double* const* arrays, int count);

}  // namespace SMPM_NS::kern
