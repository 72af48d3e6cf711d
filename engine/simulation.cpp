#include "kernels/dimension.hpp"
#include "engine/simulation.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <type_traits>
#include <utility>

#include "engine/checkpoint.hpp"
#include "engine/diagnostics.hpp"
#include "engine/timer.hpp"
#include "engine/transfer_step.hpp"
#include "kernels/heat.hpp"
#include "kernels/sort.hpp"
#include "kernels/stencil.hpp"
#include "kernels/transfer.hpp"
#include "kernels/void_closure.hpp"

namespace SMPM_NS {

Simulation::Simulation(const kern::GridGeom& geom, const SolverConfig& cfg, std::vector<Material> materials,
                       std::vector<int> body_material, Particles particles)
    : cfg_(cfg),
      materials_(std::move(materials)),
      body_material_(std::move(body_material)),
      P_(std::move(particles)),
      grid_(geom, cfg.transfer == Transfer::FLIP, cfg.fields(), cfg.contact) {
  if (geom.tile < 4 || geom.tile > kern::kMaxTile)
    throw std::invalid_argument("grid tile width must be 4 to " + std::to_string(kern::kMaxTile) + " cells");
  P_.enable_affine(cfg_.transfer == Transfer::APIC);
  assign_velocity_fields();
  enable_optional_fields();
  resolve_strain_rate();
  // ids name particles in messages and snapshots: their order as given
  for (std::size_t i = 0; i < P_.size(); ++i) P_.id[i] = static_cast<std::uint32_t>(i);
  allocate_work_arrays();
  for (const auto& m : materials_) thermo_.emplace_back(m);
  if (cfg_.heat_conduction) setup_heat_conduction();
  double mmax = 0.0;
  for (double m : P_.m) mmax = std::max(mmax, m);
  mass_eps_ = 1e-9 * mmax;
  // first time step from the initial state
  max_speed_ = 0.0;
  auto pv = P_.view();
  for (std::size_t k = 0; k < materials_.size(); ++k) {
    const kern::Selection sel{P_.body.data(), materials_.size() > 1 ? select_[k].data() : nullptr};
    with_material(materials_[k], [&](const auto& eos, const auto& str) {
      max_speed_ = std::max(max_speed_, kern::max_signal_speed(pv, P_.size(), eos, str, sel));
    });
  }
}

// The velocity field of each point (Particles::field): its body with two-body contact, the side
// of its void (set by the scene) with separated void faces; none with one field.
void Simulation::assign_velocity_fields() {
  const std::size_t n = P_.size();
  if (cfg_.contact) {
    if (body_material_.size() != 2)
      throw std::invalid_argument("multi-body contact needs exactly two bodies (one velocity field each), got " +
                                  std::to_string(body_material_.size()));
    if (cfg_.scheme != Scheme::USL) throw std::invalid_argument("multi-body contact runs with scheme 'usl' only");
    P_.field.resize(n);
    for (std::size_t i = 0; i < n; ++i) P_.field[i] = P_.body[i] == 1 ? 1 : 0;
  }
  if (cfg_.void_faces == VoidFaces::Separate) {
    if (cfg_.contact) throw std::invalid_argument("separated void faces and two-body contact together need four velocity fields (not implemented)");
    if (cfg_.scheme != Scheme::USL) throw std::invalid_argument("separated void faces run with scheme 'usl' only");
    if (P_.field.size() != n) throw std::invalid_argument("separated void faces: the particles carry no field (assign_void_sides)");
    if (cfg_.void_face_fields != 2 && cfg_.void_face_fields != 4)
      throw std::invalid_argument("void-face velocity fields must be 2 or 4, got " + std::to_string(cfg_.void_face_fields));
    for (std::uint8_t f : P_.field)
      if (f >= cfg_.void_face_fields)
        throw std::invalid_argument("separated void faces: a particle's field is outside the " +
                                    std::to_string(cfg_.void_face_fields) + " velocity fields");
  }
  if (cfg_.fields() == 1) std::vector<std::uint8_t>().swap(P_.field);
}

// The optional particle fields: only what the materials and solver settings need.
void Simulation::enable_optional_fields() {
  const std::size_t n = P_.size();
  bool energy = false, plastic = false, stored_work = false;
  for (const auto& m : materials_) {
    energy = energy || m.needs_energy();
    plastic = plastic || m.plastic();
    stored_work = stored_work || (m.plastic() && m.heat_fraction < 1.0);
  }
  Particles::enable(P_.e, n, energy || cfg_.heat_conduction);
  Particles::enable(P_.epsp, n, plastic);
  Particles::enable(P_.q, n, cfg_.artificial_viscosity);
  Particles::enable(P_.wp, n, stored_work);
}

// The rate whose work goes into the energy (StrainRate): the mid-step one needs the heating
// gather (APIC or FLIP with an energy field) and USL.
void Simulation::resolve_strain_rate() {
  if (cfg_.fields() > 2 && !(transfer_heat() && cfg_.transfer == Transfer::APIC))
    throw std::invalid_argument("four void-face velocity fields (contact.void_face_fields = 4) need transfer 'apic' and "
                                "an energy field (a Mie-Grueneisen material or heat conduction): their weld takes APIC's "
                                "scatter velocity");
  const bool can_mid = cfg_.scheme == Scheme::USL && transfer_heat();
  if (cfg_.strain_rate == StrainRate::Midstep && !can_mid)
    throw std::invalid_argument("case key 'solver.strain_rate': 'midstep' needs scheme 'usl' and an "
                                "energy field (a Mie-Grueneisen material or heat conduction); use 'auto' or 'updated'");
  // auto: mid-step energy except with the linear hat, whose cell crossings heat the dense shock
  // state 13 % too hot with it (docs/accuracy.md; FLIP and uGIMP are exact with it because the
  // kinematics take the updated L)
  const bool mid_default = cfg_.shape != kern::ShapeKind::Linear;
  midstep_ = can_mid && (cfg_.strain_rate == StrainRate::Midstep || (cfg_.strain_rate == StrainRate::Auto && mid_default));
}

// The binning, the per-line sums of the grid passes, the node states of the void-face merge
// and the material selections, sized once.
void Simulation::allocate_work_arrays() {
  const auto& geom = grid_.geom;
  const std::size_t n = P_.size();
  key_.resize(n);
  order_.resize(n);
  cell_start_.resize(geom.num_keys() + 1);
  hist_.resize(static_cast<std::size_t>(omp_get_max_threads()) * geom.num_keys());
  row_force_.assign(kern::kRowSlots * static_cast<std::size_t>(geom.num_lines()), 0.0);
  row_loss_.assign(static_cast<std::size_t>(geom.num_lines()), 0.0);
  if (cfg_.void_faces == VoidFaces::Separate && cfg_.void_face_merge) node_state_.assign(3 * geom.num_nodes(), 0);
  select_.resize(materials_.size());
  for (auto& s : select_) s.fill(0);
  for (std::size_t b = 0; b < body_material_.size(); ++b) select_.at(body_material_[b])[b] = 1;
}

// One conductivity for the scene; nodes with less than half a cell of the lightest material's
// full mass carry no heat (kernels/heat.hpp), which bounds the explicit step.
void Simulation::setup_heat_conduction() {
  const double h = grid_.geom.h;
  cv_body_.assign(256, 0.0);
  double cmin = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < body_material_.size(); ++b) {
    const Material& m = materials_[body_material_[b]];
    if (m.cv <= 0.0 || m.conductivity <= 0.0)
      throw std::invalid_argument("heat conduction needs specific_heat and thermal_conductivity > 0 for material " + m.name);
    if (conductivity_ > 0.0 && m.conductivity != conductivity_)
      throw std::invalid_argument("heat conduction: all materials must share one thermal_conductivity");
    conductivity_ = m.conductivity;
    cv_body_[b] = m.cv;
    double c = 0.5 * m.rho0;  // half a cell's mass, 0.5 rho0 h^kDim, times cv
    for (int d = 0; d < kern::kDim; ++d) c *= h;
    cmin = std::min(cmin, c * m.cv);
  }
  heat_cmin_ = cmin;
  heat_dt_ = 0.9 * cmin / (2.0 * kern::kDim * conductivity_);
  grid_.enable_heat();
  // relaxation of sub-cell temperature structure (kernels/heat.hpp): time 10 h^2 / alpha
  double alpha = 0.0;
  for (const auto& m : materials_) alpha = std::max(alpha, m.conductivity / (m.rho0 * m.cv));
  heat_relax_rate_ = alpha / (10.0 * h * h);
  T_.assign(P_.size(), 0.0);
}

kern::ParticleView Simulation::pview() {
  auto v = P_.view();
  if (cfg_.fields() > 1) v.field_of = P_.field.data();
  return v;
}

double Simulation::stable_dt() const {
  if (cfg_.fixed_dt > 0.0) return cfg_.fixed_dt;
  return std::min(cfg_.cfl * grid_.geom.h / max_speed_, heat_dt_);
}

void Simulation::step(double dt_max) {
  dt_ = std::min(stable_dt(), dt_max);
  bin_particles();      // cell keys, counting sort by tile and cell
  scatter_to_grid();    // P2G: mass, momentum, internal force (colored, atomic-free)
  fold_halo();          // periodic axes: the ghosts' sums onto the nodes they stand for
  update_grid();        // momentum update with gravity and walls, per velocity field
  apply_contact();      // several velocity fields: Coulomb contact, or the weld of void faces
  fill_halo();          // periodic axes: the ghosts take the updated values
  if (cfg_.scheme == Scheme::MUSL) {
    gather_velocity();  // G2P: the particles' new velocities
    remap_momentum();   // their momentum back to the grid, the grid velocity from it
  }
  gather_and_update_stress();  // G2P: (USL: velocity,) position, L; behind each block of points
                               // volume, stress, pressure, energy; the next step's signal speed
  merge_closed_faces();  // void-face fields: a point whose nodes are all full, one welded, joins field 0
  close_cracks();        // a fractured point among compressed cell-mates: its group shares one density
  if (cfg_.heat_conduction) conduct_heat();  // grid conduction, heat back to the particles
  time_ += dt_;
  last_dt_ = dt_;
  ++steps_;
  box_nodes_ += double(box_.nodes());
}

// The fracture thresholds of a material [Pa, kg/m^3]: tension below -spall_strength, or
// expansion past rho0 / 2, fractures a point. The second catches hot debris whose energy term
// keeps the pressure up: at rho = 1e-5 rho0 its Mie-Grueneisen sound speed reached 1e8 m/s and
// stalled a porous run at dt = 1e-5 ns. Without a spall strength nothing fractures.
static std::pair<double, double> fracture_limits(const Material& m) {
  const bool spall = m.spall_strength > 0.0;
  return {spall ? -m.spall_strength : -1e300, spall ? 0.5 * m.rho0 : 0.0};
}

// kern::merge_closed_faces over the grid of this step's scatter (docs/method.md).
void Simulation::merge_closed_faces() {
  if (cfg_.void_faces != VoidFaces::Separate || !cfg_.void_face_merge) return;
  Timed t(times_.contact);
  const kern::MergeParams q{cfg_.void_face_volume_fraction, mass_eps_, cfg_.ugimp_lp};
  kern::with_shape(cfg_.shape, [&](auto shape) {
    const auto pv = P_.view();
    kern::merge_closed_faces<decltype(shape)>(grid_.geom, box_, grid_.view(), pv.x, P_.field.data(), P_.size(), q,
                                              node_state_.data());
  });
}

// kern::close_cracks for every material with a tension cutoff, over the cells of this step's
// binning (docs/method.md); the next step's signal speed takes the points it sets.
void Simulation::close_cracks() {
  if (!cfg_.crack_closure) return;
  Timed t(times_.constitutive);
  const auto opt = [](std::vector<double>& v) { return v.empty() ? nullptr : v.data(); };
  for (std::size_t k = 0; k < materials_.size(); ++k) {
    const Material& mat = materials_[k];
    if (!(mat.spall_strength > 0.0)) continue;
    const kern::ParticleView pv = P_.view();
    kern::CrackArrays A{P_.m.data(), P_.V.data(), P_.p.data(), {}, opt(P_.q), opt(P_.e), {}, P_.body.data(),
                        P_.field.empty() ? nullptr : P_.field.data(),
                        materials_.size() > 1 ? select_[k].data() : nullptr};
    std::copy(std::begin(pv.s), std::end(pv.s), A.s);
    std::copy(std::begin(pv.v), std::end(pv.v), A.v);
    const auto [p_min, rho_min] = fracture_limits(mat);
    const kern::CrackParams prm{p_min, rho_min};
    with_material(mat, [&](const auto& eos, const auto& str) {
      const auto r = kern::close_cracks(A, order_.data(), cell_start_.data(), grid_.geom.num_keys(), prm, eos,
                                        [&](double rho, double P, std::uint32_t i) {
                                          double v2 = 0.0;
                                          for (int d = 0; d < kern::kDim; ++d) v2 += pv.v[d][i] * pv.v[d][i];
                                          return kern::signal_speed(eos, str, rho, P, v2);
                                        });
      max_speed_ = std::max(max_speed_, r.max_speed);
    });
  }
}

void Simulation::sort_by_cell() {
  const auto& g = grid_.geom;
  const std::size_t n = P_.size();
  const auto pv = P_.view();
  const auto bad = kern::sort_by_cell(g, pv.x, n, key_.data(), hist_.data(), cell_start_.data(), order_.data());
  if (bad >= 0) {
    std::string span;
    for (int d = 0; d < kern::kDim; ++d)
      span += std::string(d ? ", " : "") + kern::kAxisNames[d] + " in [" + std::to_string(g.origin(d)) + ", " +
              std::to_string(g.origin(d) + g.cells(d) * g.h) + "]";
    throw StepError("particle left the grid: " + describe_particle(static_cast<std::size_t>(bad)) +
                    "; the grid spans " + span + " m: enlarge the grid or add a wall");
  }
}

void Simulation::bin_particles() {
  Timed t(times_.sort);
  sort_by_cell();
  box_ = kern::occupied_nodes(grid_.geom, cell_start_.data());  // the grid passes of this step stay inside
  if (cfg_.permute_every > 0 && steps_ % cfg_.permute_every == 0) {
    const std::size_t n = P_.size();
    P_.permute(order_.data(), scratch_d_, scratch_u_, scratch_b_);
    kern::gather_permute(key_.data(), order_.data(), n, scratch_u_.data());
    key_.swap(scratch_u_);
    for (std::size_t s = 0; s < n; ++s) order_[s] = static_cast<std::uint32_t>(s);
  }
}

transfer::StepArgs Simulation::transfer_args() {
  auto P = pview();
  // The USL gather and MUSL's APIC velocity pass exist only as the heating gather (engine/
  // transfer_step_impl.hpp). Without an energy field it heats heat_sink_, which nothing reads:
  // the velocities, positions, L and C are those of a gather without heating (up to the sign
  // of a zero: L's mid-step term is 0 * (v_new - v_old) there), at the cost of the heating sums.
  if (!P.e && gather_heats()) {
    if (heat_sink_.size() != P_.size()) heat_sink_.assign(P_.size(), 0.0);
    P.e = heat_sink_.data();
  }
  return {grid_.geom, grid_.view(), P, P_.size(), order_.data(), cell_start_.data(), box_, cfg_};
}

void Simulation::scatter_to_grid() {
  Timed t(times_.p2g);
  const auto a = transfer_args();
  kern::with_shape(cfg_.shape, [&](auto shape) { transfer::scatter<decltype(shape)>(a); });
}

void Simulation::fold_halo() {
  Timed t(times_.p2g);
  using A = NodeArray;
  grid_.fold(box_, {A::Mass, A::Momentum, A::Force, A::Volume, A::MassGradient});
}

kern::GridUpdateParams Simulation::grid_params() const {
  kern::GridUpdateParams q;
  q.dt = dt_;
  for (int d = 0; d < kern::kDim; ++d) q.gravity[d] = cfg_.gravity[d];
  q.walls = cfg_.walls;
  q.flip = cfg_.transfer == Transfer::FLIP;
  q.mass_eps = mass_eps_;
  // APIC's heating gather reads p / m (kern::g2p_particle); FLIP's takes v - dv
  q.scatter_velocity = transfer_heat() && cfg_.transfer == Transfer::APIC;
  return q;
}

void Simulation::update_grid() {
  Timed t(times_.grid);
  const auto& g = grid_.geom;
  const auto G = grid_.view();
  const auto q = grid_params();
  WallForces w;
  for (int f = 0; f < G.fields; ++f) {
    kern::grid_update(g, box_, G.field(f), q, row_force_.data());
    for (int r = 0; r < g.num_lines(); ++r) {
      const double* rf = &row_force_[kern::kRowSlots * r];
      for (int d = 0; d < kern::kDim; ++d) {
        w.lo[d] += rf[2 * d];
        w.hi[d] += rf[2 * d + 1];
      }
      removed_.wall += rf[2 * kern::kDim];
    }
  }
  wall_ = w;
}

void Simulation::apply_contact() {
  if (cfg_.fields() == 1) return;
  Timed t(times_.contact);
  const bool weld = cfg_.void_faces == VoidFaces::Separate;
  const kern::ContactParams c{cfg_.friction, weld,
                              weld ? cfg_.void_face_volume_fraction : cfg_.contact_volume_fraction, midstep_};
  kern::grid_contact(grid_.geom, box_, grid_.view(), grid_params(), c, row_loss_.data());
  for (double r : row_loss_) removed_.contact += r;
}

void Simulation::fill_halo() {
  Timed t(times_.grid);
  using A = NodeArray;
  grid_.fill(box_, {A::Velocity, A::VelocityChange});
  if (grid_params().scatter_velocity)  // the gather reads the scatter's velocity (and contact heat)
    grid_.fill(box_, {A::Momentum, A::ContactHeat});
  else if (transfer_heat())  // FLIP's heating gather: contact heat (several fields)
    grid_.fill(box_, {A::ContactHeat});
}

// The constitutive update of points [first, last), L their velocity gradient (element 0 = point
// first), every material in turn (volume, stress, pressure, energy; the signal speed into acc).
// The last gather pass calls it on each block of points it has gathered (kern::g2p_blocks);
// thread 0 adds its time in it to thread0_seconds, the phase time reported as "constitutive".
auto Simulation::stress_pass(double& thread0_seconds) {
  const auto opt = [](std::vector<double>& v) { return v.empty() ? nullptr : v.data(); };
  const kern::ConstitutiveState state{opt(P_.e), opt(P_.epsp), opt(P_.q), opt(P_.wp)};
  std::vector<kern::ConstitutiveParams> params(materials_.size());
  for (std::size_t k = 0; k < materials_.size(); ++k) {
    kern::ConstitutiveParams& q = params[k];
    q.dt = dt_;
    q.av_length = grid_.geom.h;
    q.av_linear = cfg_.av_linear;
    q.av_quadratic = cfg_.av_quadratic;
    const auto [p_min, rho_min] = fracture_limits(materials_[k]);
    q.p_min = p_min;
    q.rho_min = rho_min;
    q.midstep = midstep_;
  }
  return [this, pv = P_.view(), state, params = std::move(params), &thread0_seconds](
             std::size_t first, std::size_t last, const kern::Gradient& L, kern::ConstitutiveResult& acc) {
    const bool timed = omp_get_thread_num() == 0;
    const double t0 = timed ? omp_get_wtime() : 0.0;
    if (store_gradient_) store_gradient_measures(L, first, last, P_);
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      const kern::Selection sel{P_.body.data(), materials_.size() > 1 ? select_[k].data() : nullptr};
      acc.merge(constitutive_block(materials_[k], pv, state, L, first, last, params[k], sel));
    }
    if (timed) thread0_seconds += omp_get_wtime() - t0;
  };
}

kern::G2PParams Simulation::gather_params() const {
  const auto& g = grid_.geom;
  kern::G2PParams q{dt_, cfg_.ugimp_lp, cfg_.flip_alpha, midstep_ ? 0.5 : 0.0};
  // walls: the largest double below the far edge keeps a clamped point inside the grid
  for (int d = 0; d < kern::kDim; ++d) {
    const double o = g.origin(d), top = o + g.cells(d) * g.h;
    if (cfg_.walls.lo[d] != kern::Wall::None) q.lo[d] = o;
    if (cfg_.walls.hi[d] != kern::Wall::None) q.hi[d] = std::nextafter(top, o);
  }
  return q;
}

void Simulation::gather_velocity() {
  Timed t(times_.g2p);
  const auto a = transfer_args();
  const auto q = gather_params();
  kern::with_shape(cfg_.shape, [&](auto shape) { transfer::gather_velocity<decltype(shape)>(a, q); });
}

void Simulation::remap_momentum() {
  Timed t(times_.g2p);
  const auto a = transfer_args();
  kern::with_shape(cfg_.shape, [&](auto shape) { transfer::scatter_momentum<decltype(shape)>(a, cfg_.ugimp_lp); });
  grid_.fold(box_, {NodeArray::Momentum});
  kern::GridUpdateParams q;
  q.walls = cfg_.walls;
  kern::grid_velocity_from_momentum(grid_.geom, box_, a.G, q);
  grid_.fill(box_, {NodeArray::Velocity});
}

void Simulation::gather_and_update_stress() {
  const double t_start = omp_get_wtime();
  double stress_seconds = 0.0;
  const auto stress = stress_pass(stress_seconds);
  const auto a = transfer_args();
  const auto q = gather_params();
  // L of each block in a per-thread buffer (with the energy's mid-step rate)
  const int threads = omp_get_max_threads();
  if (gather_scratch_.size() < kern::kGatherScratch * static_cast<std::size_t>(threads))
    gather_scratch_.assign(kern::kGatherScratch * static_cast<std::size_t>(threads), 0.0);
  const auto update = transfer::BlockUpdate::of(stress);
  const kern::ConstitutiveResult r = kern::with_shape(cfg_.shape, [&](auto shape) {
    return transfer::gather_and_update_stress<decltype(shape)>(a, q, gather_scratch_.data(), update);
  });
  times_.constitutive += stress_seconds;
  times_.g2p += omp_get_wtime() - t_start - stress_seconds;
  if (store_gradient_) gradient_step_ = steps_ + 1;
  check_volume(r.bad);
  max_speed_ = r.max_speed;
}

void Simulation::conduct_heat() {
  Timed t(times_.heat);
  const auto& g = grid_.geom;
  const std::size_t n = P_.size();
#pragma omp parallel for schedule(static)
  for (std::size_t p = 0; p < n; ++p) {
    const int k = body_material_[P_.body[p]];
    T_[p] = particle_temperature(P_, p, thermo_[k], materials_[k]);
  }
  const kern::HeatGrid H{grid_.cap.data(), grid_.capT.data(), grid_.T.data(), grid_.dT.data()};
  const auto pv = P_.view();
  kern::HeatParticles hp{{}, P_.m.data(), T_.data(), P_.body.data(), cv_body_.data(), P_.e.data()};
  for (int d = 0; d < kern::kDim; ++d) hp.pos[d] = pv.x[d];
  std::fill(grid_.cap.begin(), grid_.cap.end(), 0.0);
  std::fill(grid_.capT.begin(), grid_.capT.end(), 0.0);
  // the particles moved in this step: sort them again for the scatter
  sort_by_cell();
  using A = NodeArray;
  const kern::NodeBox all = g.all_nodes();
  kern::with_shape(cfg_.shape, [&](auto shape) {
    using S = decltype(shape);
    kern::heat_scatter<S>(g, H, hp, order_.data(), cell_start_.data(), cfg_.ugimp_lp);
    grid_.fold(all, {A::HeatCapacity, A::HeatContent});
    kern::heat_temperatures(g, H);
    grid_.fill(all, {A::Temperature, A::HeatCapacity});  // the fluxes read the ghosts' neighbours
    kern::heat_conduct(g, H, conductivity_, heat_cmin_, dt_);
    grid_.fill(all, {A::TemperatureChange});
    kern::heat_gather<S>(g, H, hp, n, cfg_.ugimp_lp, std::min(1.0, heat_relax_rate_ * dt_));
  });
}

void Simulation::check_volume(std::ptrdiff_t bad) const {
  if (bad < 0) return;
  throw StepError("non-positive or NaN volume: " + describe_particle(static_cast<std::size_t>(bad)) +
                  "; the velocity gradient over one step exceeded what the particle can take: "
                  "lower cfl or refine the grid");
}

std::string Simulation::describe_particle(std::size_t p) const {
  std::ostringstream s;
  s.precision(9);
  s << "particle " << P_.id[p] << " (body " << int(P_.body[p]) << ") at step " << steps_ << ", t = " << time_
    << " s";
  for (const auto& [what, a, unit] : {std::tuple{"position", &P_.x, "m"}, {"velocity", &P_.v, "m/s"}}) {
    s << ", " << what << " (";
    for (int d = 0; d < kern::kDim; ++d) s << (d ? ", " : "") << (*a)[d][p];
    s << ") " << unit;
  }
  s << ", volume " << P_.V[p] << " m^2";
  return s.str();
}

Simulation::Energy Simulation::energy() const {
  Energy e;
  const bool has_e = !P_.e.empty(), apic = !P_.C[0].empty();
  const auto& g = grid_.geom;
  const auto pv = const_cast<Particles&>(P_).view();
  for (std::size_t p = 0; p < P_.size(); ++p) {
    double v[kern::kDim];
    for (int d = 0; d < kern::kDim; ++d) v[d] = pv.v[d][p];
    e.kinetic += 0.5 * P_.m[p] * kern::norm2(v);
    if (apic) {  // the affine field's share: 1/2 m sum_ab C_ab^2 D_b
      double Dn[kern::kDim], C[kern::kDim][kern::kDim];
      kern::with_shape(cfg_.shape, [&](auto shape) {
        kern::Vec<kern::kDim> u;
        for (int d = 0; d < kern::kDim; ++d) u[d] = (pv.x[d][p] - g.origin(d)) / g.h;
        const kern::Stencil<decltype(shape), kern::kDim> st(u, cfg_.ugimp_lp);
        for (int d = 0; d < kern::kDim; ++d) Dn[d] = st.inertia(d);
      });
      for (int r = 0; r < kern::kDim; ++r)
        for (int c = 0; c < kern::kDim; ++c) C[r][c] = pv.affine(r, c)[p];
      e.kinetic += 0.5 * P_.m[p] * (g.h * g.h) * kern::affine_energy(C, Dn);
    }
    if (has_e) {
      e.internal += P_.m[p] * P_.e[p];
    } else {
      const Material& mat = materials_[body_material_[P_.body[p]]];
      kern::Sym<kern::kDim> s;
      for (int k = 0; k < kern::Sym<kern::kDim>::K; ++k) s[k] = P_.s[k][p];
      e.internal += P_.V[p] * mat.strain_energy_density(s, P_.p[p]);
    }
  }
  return e;
}

std::vector<Simulation::Scalar> Simulation::checkpoint_scalars() {
  std::vector<Scalar> s{{"time [s]", &time_},
                        {"dt [s]", &dt_},
                        {"last_dt [s]", &last_dt_},
                        {"max_speed [m/s]", &max_speed_},
                        {"box_nodes [1]", &box_nodes_},
                        {"removed_wall [J/m]", &removed_.wall},
                        {"removed_contact [J/m]", &removed_.contact}};
  for (int d = 0; d < kern::kDim; ++d) {  // wall reactions, low then high face, axis by axis
    s.push_back({std::string("wall_lo_") + kern::kAxisNames[d] + " [N/m]", &wall_.lo[d]});
    s.push_back({std::string("wall_hi_") + kern::kAxisNames[d] + " [N/m]", &wall_.hi[d]});
  }
  for (auto [name, t] : {std::pair{"sort", &times_.sort}, {"p2g", &times_.p2g}, {"grid", &times_.grid},
                         {"contact", &times_.contact}, {"g2p", &times_.g2p}, {"constitutive", &times_.constitutive},
                         {"heat", &times_.heat}})
    s.push_back({std::string("time_") + name + " [s of wall time]", t});
  return s;
}

void Simulation::save(CheckpointWriter& w) const {
  const_cast<Particles&>(P_).each_array([&](const char* name, const auto& a) { w.put(std::string("p/") + name, a); });
  std::string fields;
  for (const auto& f : P_.fields_in_use()) fields += f + " ";
  w.put("sim/fields", fields);
  w.put("sim/steps", std::int64_t{steps_});
  w.put("sim/gradient_step", std::int64_t{gradient_step_});
  std::vector<double> scalars;
  std::string names;
  for (const Scalar& s : const_cast<Simulation&>(*this).checkpoint_scalars()) {
    scalars.push_back(*s.value);
    names += s.name + ";";
  }
  w.put("sim/scalars", scalars);
  w.put("sim/scalar_names", names);
}

void Simulation::restore(const CheckpointReader& r) {
  std::string fields;
  for (const auto& f : P_.fields_in_use()) fields += f + " ";
  if (r.text("sim/fields") != fields)
    throw CheckpointError("checkpoint " + r.file().string() + " holds the particle fields '" + r.text("sim/fields") +
                          "', the case builds '" + fields + "': not a checkpoint of this case");
  const std::size_t n = P_.size();
  P_.each_array([&](const char* name, auto& a) {
    r.get(std::string("p/") + name, a);
    if (a.size() != n)
      throw CheckpointError("checkpoint " + r.file().string() + " holds " + std::to_string(a.size()) +
                            " particles, the case builds " + std::to_string(n) + ": not a checkpoint of this case");
  });
  steps_ = r.integer("sim/steps");
  gradient_step_ = r.integer("sim/gradient_step");
  std::vector<double> v;
  r.get("sim/scalars", v);
  const auto slots = checkpoint_scalars();
  std::string names;
  for (const Scalar& s : slots) names += s.name + ";";
  // a checkpoint without the names record holds the same list by position
  if (r.has("sim/scalar_names") && r.text("sim/scalar_names") != names)
    throw CheckpointError("checkpoint " + r.file().string() + " holds the scalars '" + r.text("sim/scalar_names") +
                          "', this build keeps '" + names + "': not a checkpoint of this build");
  if (v.size() != slots.size())
    throw CheckpointError("checkpoint " + r.file().string() + ": sim/scalars has " + std::to_string(v.size()) +
                          " values, expected " + std::to_string(slots.size()));
  for (std::size_t k = 0; k < slots.size(); ++k) *slots[k].value = v[k];
}

std::array<double, kern::kDim> Simulation::momentum() const {
  std::array<double, kern::kDim> q{};
  const auto pv = const_cast<Particles&>(P_).view();
  for (std::size_t p = 0; p < P_.size(); ++p)
    for (int d = 0; d < kern::kDim; ++d) q[d] += P_.m[p] * pv.v[d][p];
  return q;
}

std::size_t Simulation::bytes() const {
  return P_.bytes() + grid_.bytes() +
         (key_.capacity() + order_.capacity() + cell_start_.capacity() + hist_.capacity() + scratch_u_.capacity()) *
             sizeof(std::uint32_t) +
         (scratch_d_.capacity() + gather_scratch_.capacity() + heat_sink_.capacity()) * sizeof(double) + scratch_b_.capacity() +
         node_state_.capacity();
}

}  // namespace SMPM_NS
