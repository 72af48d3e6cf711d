// The solver's settings: shape function, transfer, scheme, time step, walls, contact, void
// faces, heat conduction. A Scene carries one (engine/scene.hpp), Simulation runs with it.
#pragma once
#include "kernels/dimension.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/shape.hpp"

namespace SMPM_NS {

enum class Transfer { APIC, FLIP };
// Void faces of a porous body: one velocity field (faces closer than about a cell share
// nodes and stop approaching), or two, by the side of the nearest void each point lies on
// (Particles::field), welded where they fill a node (kern::grid_contact).
enum class VoidFaces { SingleField, Separate };
// Velocity of the USL strain rate: the node's mid-step velocity (energy-conserving step, not
// symplectic: needs the damping of APIC or viscosity; with the heating gather only, APIC or FLIP
// with an energy field) or the updated one (symplectic, loses dt^2 |f|^2 / 2m per node and
// step). The kinematics (volume, deviator) always take the updated velocity; only the
// energy's work takes the mid-step one. Auto: mid-step for every shape but the linear hat, whose
// cell crossings heat the dense shock state too hot with it (Simulation's constructor;
// docs/accuracy.md, docs/method.md).
enum class StrainRate { Auto, Midstep, Updated };
// USL: stress from the updated grid velocity. MUSL: from the velocity remapped from the
// updated particles.
enum class Scheme { USL, MUSL };

struct SolverConfig {
  kern::ShapeKind shape = kern::ShapeKind::Quadratic;
  double ugimp_lp = 0.25;       // uGIMP half particle width in cells (= 1 / (2 points per cell))
  Transfer transfer = Transfer::APIC;
  double flip_alpha = 0.99;     // FLIP fraction of the FLIP/PIC blend (FLIP transfer only)
  Scheme scheme = Scheme::USL;
  StrainRate strain_rate = StrainRate::Auto;
  double cfl = 0.4;             // dt = cfl h / max_p(c_p + |v_p|)
  double fixed_dt = 0.0;        // [s]; > 0 replaces the CFL time step
  int permute_every = 20;       // physical permutation of particle arrays every k steps (0: never)
  double gravity[kern::kDim] = {};  // [m/s^2]
  kern::Walls walls;
  // Artificial bulk viscosity q = rho h (c_Q h tr(D)^2 - c_L c tr(D)), compression only.
  bool artificial_viscosity = false;
  double av_linear = 0.06;     // c_L
  double av_quadratic = 1.5;   // c_Q
  // Heat conduction on the grid (kernels/heat.hpp); its explicit limit is folded into dt.
  bool heat_conduction = false;
  // Multi-body contact: one velocity field per body (exactly two bodies), Coulomb friction,
  // contact only while approaching and where the nodal volume shows the bodies touching
  // (kernels/grid_update.hpp). Off: one field, bodies stick once they meet.
  bool contact = false;
  double friction = 0.0;                 // Coulomb mu
  double contact_volume_fraction = 1.0;  // nodal volume (in cells) needed for contact
  VoidFaces void_faces = VoidFaces::SingleField;
  double void_face_volume_fraction = 0.9;  // nodal volume (in cells) at which the faces weld (docs/method.md)
  // a void-face point whose nodes are all full, one of them welded, joins field 0 for good
  // (kern::merge_closed_faces): closed voids leave no laminated layers that slide into each other
  bool void_face_merge = true;
  // a fractured point among compressed points of its cell, body and field: the group shares one
  // density (kern::close_cracks), so cracks inside compacted material close
  bool crack_closure = true;
  // velocity fields of the void faces: 2 (split along the impact direction) or 4 (across it
  // too; APIC with an energy field only: kern::grid_contact's weld_fields), engine/porous.hpp
  int void_face_fields = 2;
  int fields() const { return contact ? 2 : void_faces == VoidFaces::Separate ? void_face_fields : 1; }
};

}  // namespace SMPM_NS
