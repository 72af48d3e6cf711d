// The time step. Simulation owns the particle arrays, the grid and the binning, and runs
// one explicit MPM step as a short list of named phases (see step()).
#pragma once
#include "kernels/dimension.hpp"
#include <array>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/grid.hpp"
#include "engine/material.hpp"
#include "engine/particles.hpp"
#include "engine/solver_config.hpp"
#include "engine/thermo.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/shape.hpp"

namespace smpm {
class CheckpointWriter;
class CheckpointReader;
}  // namespace smpm

namespace SMPM_NS {
namespace kern {
struct G2PParams;
}
namespace transfer {
struct StepArgs;
}

// A step that cannot go on: a particle left the grid or its volume became non-positive.
struct StepError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Wall reaction on the material [N per metre of thickness], normal component, on the low and
// the high face of each axis.
struct WallForces {
  double lo[kern::kDim] = {}, hi[kern::kDim] = {};
};

// Wall-clock seconds spent in each phase, summed over steps. `grid` excludes `contact`.
struct PhaseTimes {
  double sort = 0, p2g = 0, grid = 0, contact = 0, g2p = 0, constitutive = 0, heat = 0;
  double total() const { return sort + p2g + grid + contact + g2p + constitutive + heat; }
};

class Simulation {
 public:
  // body_material[b]: index into materials of the material of body b.
  Simulation(const kern::GridGeom& geom, const SolverConfig& cfg, std::vector<Material> materials,
             std::vector<int> body_material, Particles particles);

  // Advances by one step of dt = min(CFL step, dt_max). Throws StepError on an invalid state.
  void step(double dt_max = std::numeric_limits<double>::infinity());

  double time() const { return time_; }
  long steps() const { return steps_; }
  // Nodes per step the grid passes worked on (the occupied box, kern::occupied_nodes), mean
  // over the steps taken; the grid holds grid().geom.num_nodes().
  double mean_active_nodes() const { return steps_ > 0 ? box_nodes_ / double(steps_) : 0.0; }
  double last_dt() const { return last_dt_; }
  // Whether step() stores what the regional statistics read of the velocity gradient L on the
  // particles (particles().curl2, div, rate2: store_gradient_measures, diagnostics.hpp). Default
  // on. Off, the arrays keep the values of the last step that stored them: 24 B less memory
  // traffic per point and step. The driver turns it on for the steps after which it writes
  // statistics.
  void store_gradient(bool on) { store_gradient_ = on; }
  // The particles' gradient measures are those of the last step taken (stored by it, or no step
  // taken yet).
  bool gradient_current() const { return gradient_step_ == steps_; }
  double stable_dt() const;  // the step the next step() would take: CFL, heat conduction limit
  double heat_dt() const { return heat_dt_; }  // explicit conduction limit [s] (inf when off)
  const std::vector<Thermo>& thermo() const { return thermo_; }
  const Particles& particles() const { return P_; }
  Particles& particles() { return P_; }
  const Grid& grid() const { return grid_; }
  const SolverConfig& config() const { return cfg_; }
  const std::vector<Material>& materials() const { return materials_; }
  const std::vector<int>& body_material() const { return body_material_; }
  const WallForces& wall_forces() const { return wall_; }
  const PhaseTimes& phase_times() const { return times_; }

  // Kinetic and internal energy [J per metre of thickness]: internal is sum m e where the
  // scene carries e, else the elastic strain energy of the stress. Summed in array order, so
  // identical for any thread count.
  // A fixed rigid wall does no work, so kinetic plus internal energy is what is conserved.
  struct Energy {
    double kinetic = 0, internal = 0;
    double total() const { return kinetic + internal; }
  };
  Energy energy() const;
  // Kinetic energy the walls and the contact (welds) took out of the grid's velocities since
  // the start [J per metre], summed in a fixed order. With APIC and an energy field the
  // heating gather gives it to the points, so it is part of `internal` already; else it is lost.
  struct Removed {
    double wall = 0, contact = 0;
  };
  const Removed& removed() const { return removed_; }
  bool removed_is_heat() const { return transfer_heat(); }
  // Checkpoints (engine/checkpoint.hpp): the particle arrays in use and the scalars that carry
  // from step to step (time, step count, the next step's signal speed, removed energy, phase
  // times). restore() takes them into a Simulation built from the same scene (same particle
  // count and fields; else CheckpointError): the steps after it are bitwise those that would
  // have followed save().
  void save(CheckpointWriter& w) const;
  void restore(const CheckpointReader& r);
  // Total momentum [kg m/s per metre].
  std::array<double, kern::kDim> momentum() const;
  std::size_t bytes() const;

 private:
  // the constructor's parts
  void assign_velocity_fields();
  void enable_optional_fields();
  void resolve_strain_rate();
  void allocate_work_arrays();
  void setup_heat_conduction();
  // the phases of step()
  void bin_particles();  // sort_by_cell, the occupied box, the periodic physical permutation
  void scatter_to_grid();
  void fold_halo();
  void update_grid();
  void apply_contact();
  void fill_halo();
  void gather_velocity();
  void remap_momentum();
  void gather_and_update_stress();
  void merge_closed_faces();
  void close_cracks();
  void conduct_heat();
  // the constitutive update of a block of points, which the last gather pass calls (its L)
  auto stress_pass(double& thread0_seconds);
  kern::G2PParams gather_params() const;
  void sort_by_cell();  // cell keys and the counting sort (order_, cell_start_)
  kern::GridUpdateParams grid_params() const;

  void check_volume(std::ptrdiff_t bad) const;
  kern::ParticleView pview();  // particle view, with velocity fields when contact is on
  transfer::StepArgs transfer_args();  // what the transfers read (engine/transfer_step.hpp)
  // APIC, or FLIP with USL, with an energy field: the transfers' kinetic-energy dissipation
  // heats the particles (see kern::g2p_particle), so total energy is conserved by the transfers.
  bool transfer_heat() const { return !P_.e.empty() && gather_heats(); }
  // the passes compiled only as the heating gather run (USL's gather, MUSL's APIC velocity
  // pass): without an energy field they heat heat_sink_ (transfer_args)
  bool gather_heats() const { return cfg_.transfer == Transfer::APIC || cfg_.scheme == Scheme::USL; }
  // USL strain rate from the mid-step grid velocity (StrainRate, resolved in the constructor)
  bool midstep_ = false;

 public:
  bool midstep() const { return midstep_; }

 private:
  std::string describe_particle(std::size_t p) const;

  SolverConfig cfg_;
  std::vector<Material> materials_;
  std::vector<int> body_material_;
  Particles P_;
  Grid grid_;
  // binning
  std::vector<std::uint32_t> key_, order_, cell_start_, hist_;
  kern::NodeBox box_;  // the nodes this step's particles reach: every grid pass stays inside
  double box_nodes_ = 0.0;  // sum over steps of the box's node count
  std::vector<double> scratch_d_;
  std::vector<double> gather_scratch_;  // L of a block per thread (kern::g2p_blocks), when not stored
  std::vector<double> heat_sink_;       // what the heating gather heats without an energy field (transfer_args)
  std::vector<std::uint32_t> scratch_u_;
  std::vector<std::uint8_t> scratch_b_;
  std::vector<std::uint8_t> node_state_;  // three images of a byte per node: full / welded (kern::merge_closed_faces)
  std::vector<double> row_force_, row_loss_;
  Removed removed_;
  std::vector<std::array<std::uint8_t, 256>> select_;  // per material: which bodies use it

  // heat conduction
  std::vector<Thermo> thermo_;
  std::vector<double> T_, cv_body_;  // particle temperatures [K], cv per body [J/(kg K)]
  double conductivity_ = 0.0, heat_cmin_ = 0.0, heat_relax_rate_ = 0.0;
  double heat_dt_ = std::numeric_limits<double>::infinity();
  double mass_eps_ = 0.0;  // grid nodes lighter than this get no force (see GridUpdateParams)
  double time_ = 0.0, dt_ = 0.0, last_dt_ = 0.0, max_speed_ = 0.0;
  long steps_ = 0;
  bool store_gradient_ = true;
  long gradient_step_ = 0;  // the step count after the last step that stored the gradient measures
  WallForces wall_;
  PhaseTimes times_;

  // One scalar a checkpoint keeps: its name with its unit, and where it lives.
  struct Scalar {
    std::string name;  // "name [unit]"
    double* value;
  };
  // The scalars a checkpoint keeps, in the order of its records "sim/scalars" (the values) and
  // "sim/scalar_names" (their names): save() and restore() both read this one list.
  std::vector<Scalar> checkpoint_scalars();
};

}  // namespace SMPM_NS
