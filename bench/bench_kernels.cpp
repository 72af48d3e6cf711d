// Kernel and step benchmarks (Google Benchmark 1.7).
//
// Every benchmark reports `particle_steps_per_s`: particles processed per second of wall time
// (one "particle-step" = one particle through that phase once). Names:
//   BM_Sort/N                         sort_by_cell: keys and counting sort (shape-independent)
//   BM_P2G_{Colored,Atomic,Serial}<shape>/N   clear_grid + P2G (All, APIC)
//   BM_GridUpdate<shape>/N            grid_update (+ fill_periodic_ghosts, a no-op here)
//   BM_G2P<shape>/N                   g2p<shape, PIC/APIC, Full>
//   BM_Step<shape>/N                  smpm::Simulation::step() (elastic, APIC, USL, CFL dt)
//   BM_StepShock<shape>/N             the same with the full shock physics (MG, J2, AV, heating)
// shape in {linear, ugimp, quadratic, cubic}; N = particles (4 per cell, ppc = 2).
// Select with --benchmark_filter, e.g. --benchmark_filter='P2G.*<quadratic>/65536'.
//
// Kernel benchmarks share one state per particle count (built on first use, then cached):
// a grid of N/4 cells fully covered by particles jittered inside their sub-cells, with random
// velocities, affine matrices and stresses, and the particle arrays physically sorted by
// tile and cell (Particles::permute with the counting-sort order) as the engine keeps them.
#include <benchmark/benchmark.h>

#include <array>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "engine/grid.hpp"
#include "engine/material.hpp"
#include "engine/particles.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/shape.hpp"
#include "kernels/sort.hpp"
#include "kernels/transfer.hpp"
#include "tests/gradient_arrays.hpp"

namespace {


using namespace smpm;

constexpr int kPpc = 2;                // points per cell per axis: 4 particles per cell
constexpr double kH = 1e-3;            // cell size [m]
constexpr double kLp = 0.5 / kPpc;     // uGIMP half particle width [cells]
constexpr double kCfl = 0.4;
constexpr long kStepRebuild = 2000;    // BM_Step: rebuild the simulation after this many steps

Material bench_material() {  // aluminium-like, linear elastic
  Material m;
  m.name = "bench";
  m.rho0 = 2700.0;
  m.E = 70e9;
  m.nu = 0.3;
  return m;
}

// The study's aluminium: Mie-Grueneisen EOS, von Mises with hardening (cases/materials.toml).
Material shock_material() {
  Material m = bench_material();
  m.name = "aluminium";
  m.eos = MieGruneisenModel{5350.0, 1.34, 2.0};
  m.strength = VonMisesModel{120e6, 384e6};
  m.E = 69e9;
  m.nu = 0.33;
  m.cv = 880.0;
  return m;
}

double wave_speed() {
  const Material m = bench_material();
  return std::sqrt((m.bulk_modulus() + 4.0 / 3.0 * m.shear_modulus()) / m.rho0);
}

double cfl_dt() { return kCfl * kH / wave_speed(); }

// the coordinate arrays of the particles, per axis (kern::sort_by_cell)
std::array<const double*, kern::kDim> positions(smpm::Particles& P) {
  const auto v = P.view();
  std::array<const double*, kern::kDim> a{};
  for (int d = 0; d < kern::kDim; ++d) a[d] = v.x[d];
  return a;
}

kern::Walls slip_box() {
  kern::Walls w;
  for (int d = 0; d < kern::kDim; ++d) w.lo[d] = w.hi[d] = kern::Wall::Slip;
  return w;
}

template <class S>
constexpr kern::ShapeKind shape_kind() {
  if constexpr (std::is_same_v<S, kern::Linear>) return kern::ShapeKind::Linear;
  else if constexpr (std::is_same_v<S, kern::UGIMP>) return kern::ShapeKind::UGIMP;
  else if constexpr (std::is_same_v<S, kern::QuadraticBSpline>) return kern::ShapeKind::Quadratic;
  else return kern::ShapeKind::Cubic;
}

// Cells nx * ny = cells, as square as possible.
void grid_dims(std::size_t cells, int& nx, int& ny) {
  auto s = static_cast<std::size_t>(std::llround(std::sqrt(static_cast<double>(cells))));
  while (s > 1 && cells % s != 0) --s;
  nx = static_cast<int>(cells / s);
  ny = static_cast<int>(s);
}

// Stable sort by tile and cell, then physical permutation of every particle array.
// Returns false if a particle lies outside the grid.
bool sort_particles(const kern::GridGeom& g, Particles& P) {
  const std::size_t n = P.size();
  std::vector<std::uint32_t> key(n), order(n), cell_start(g.num_keys() + 1);
  std::vector<std::uint32_t> hist(static_cast<std::size_t>(omp_get_max_threads()) * g.num_keys());
  if (kern::sort_by_cell(g, positions(P).data(), n, key.data(), hist.data(), cell_start.data(), order.data()) >= 0)
    return false;
  std::vector<double> sd;
  std::vector<std::uint32_t> su;
  std::vector<std::uint8_t> sb;
  P.permute(order.data(), sd, su, sb);
  return true;
}

// Shared state of the kernel benchmarks for one particle count.
struct KernelState {
  kern::GridGeom g;
  Particles P;
  Grid grid;
  std::vector<std::uint32_t> key, order, cell_start, hist;
  std::vector<double> row_force;
  std::string error;  // non-empty when the state could not be built
};

std::unique_ptr<KernelState> build_kernel_state(std::size_t n) {
  auto s = std::make_unique<KernelState>();
  if (n < 4 || n % 4 != 0) {
    s->error = "particle count must be a positive multiple of 4 (4 particles per cell)";
    return s;
  }
  kern::GridGeom& g = s->g;
  grid_dims(n / 4, g.n[0], g.n[1]);
  g.h = kH;
  g.lo[0] = 0.0;
  g.lo[1] = 0.0;
  const Material mat = bench_material();
  Particles& P = s->P;
  P = fill_rectangle(g, kPpc, Box{{g.lo[0], g.lo[1]}, {g.lo[0] + g.length(0), g.lo[1] + g.length(1)}}, mat.rho0,
                     Vector{0.0, 0.0}, 0);
  if (P.size() != n) {
    s->error = "fill_rectangle made " + std::to_string(P.size()) + " particles, expected " + std::to_string(n);
    return s;
  }
  P.enable_affine(true);  // APIC matrix C
  // Jitter inside the sub-cell (stays inside its cell), random-ish state.
  std::mt19937_64 rng(12345 + n);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double d = kH / kPpc;
  for (std::size_t i = 0; i < n; ++i) {
    P.x[0][i] += 0.4 * d * u(rng);
    P.x[1][i] += 0.4 * d * u(rng);
    P.v[0][i] = 10.0 * u(rng);
    P.v[1][i] = 10.0 * u(rng);
    P.affine(0, 0)[i] = 1e3 * u(rng);
    P.affine(0, 1)[i] = 1e3 * u(rng);
    P.affine(1, 0)[i] = 1e3 * u(rng);
    P.affine(1, 1)[i] = 1e3 * u(rng);
    P.s[0][i] = 1e7 * u(rng);
    P.s[1][i] = 1e7 * u(rng);
    P.s[2][i] = 1e7 * u(rng);
    P.p[i] = 1e8 * u(rng);
    P.id[i] = static_cast<std::uint32_t>(i);
  }
  if (!sort_particles(g, P)) {
    s->error = "a particle lies outside the grid";
    return s;
  }
  // Binning of the sorted arrays: order is the identity, as right after a permute in the engine.
  s->key.resize(n);
  s->order.resize(n);
  s->cell_start.resize(g.num_keys() + 1);
  s->hist.resize(static_cast<std::size_t>(omp_get_max_threads()) * g.num_keys());
  kern::sort_by_cell(g, positions(P).data(), n, s->key.data(), s->hist.data(), s->cell_start.data(), s->order.data());
  s->grid = Grid(g, false);
  s->row_force.assign(kern::kRowSlots * static_cast<std::size_t>(g.size(1)), 0.0);
  return s;
}

KernelState& kernel_state(std::size_t n) {
  static std::map<std::size_t, std::unique_ptr<KernelState>> cache;
  auto& s = cache[n];
  if (!s) s = build_kernel_state(n);
  return *s;
}

kern::GridUpdateParams grid_params() {
  kern::GridUpdateParams q;
  q.dt = cfl_dt();
  q.walls = slip_box();
  q.mass_eps = 0.0;
  q.flip = false;
  return q;
}

// Grid state as after P2G and the grid update of one engine step with shape S.
template <class S>
void prepare_grid(KernelState& s) {
  auto G = s.grid.view();
  auto pv = s.P.view();
  kern::clear_grid(s.g, s.g.all_nodes(), G, true);
  kern::p2g_colored<S, true, kern::P2GWhat::All>(s.g, G, pv, s.order.data(), s.cell_start.data(), kLp);
  kern::grid_update(s.g, s.g.all_nodes(), G, grid_params(), s.row_force.data());
}

void set_rate(benchmark::State& state, std::size_t n) {
  state.counters["particle_steps_per_s"] =
      benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate);
}

// Returns nullptr (after SkipWithError) if the state could not be built.
KernelState* get_state(benchmark::State& state) {
  KernelState& s = kernel_state(static_cast<std::size_t>(state.range(0)));
  if (!s.error.empty()) {
    state.SkipWithError(s.error.c_str());
    return nullptr;
  }
  return &s;
}

// ---- benchmarks ----

void BM_Sort(benchmark::State& state) {
  KernelState* s = get_state(state);
  if (!s) return;
  const std::size_t n = s->P.size();
  const kern::GridGeom& g = s->g;
  for (auto _ : state) {
    const auto bad =
        kern::sort_by_cell(g, positions(s->P).data(), n, s->key.data(), s->hist.data(), s->cell_start.data(), s->order.data());
    benchmark::DoNotOptimize(bad);
    benchmark::ClobberMemory();
  }
  set_rate(state, n);
}

enum class P2GMode { Colored, Atomic, Serial };

template <class S, P2GMode Mode>
void BM_P2G(benchmark::State& state) {
  KernelState* s = get_state(state);
  if (!s) return;
  const std::size_t n = s->P.size();
  const kern::GridGeom& g = s->g;
  auto G = s->grid.view();
  auto pv = s->P.view();
  for (auto _ : state) {
    kern::clear_grid(g, g.all_nodes(), G, true);
    if constexpr (Mode == P2GMode::Colored)
      kern::p2g_colored<S, true, kern::P2GWhat::All>(g, G, pv, s->order.data(), s->cell_start.data(), kLp);
    else if constexpr (Mode == P2GMode::Atomic)
      kern::p2g_atomic<S, true, kern::P2GWhat::All>(g, G, pv, s->order.data(), n, kLp);
    else
      kern::p2g_serial<S, true, kern::P2GWhat::All>(g, G, pv, s->order.data(), n, kLp);
    benchmark::ClobberMemory();
  }
  set_rate(state, n);
}

template <class S>
void BM_GridUpdate(benchmark::State& state) {
  KernelState* s = get_state(state);
  if (!s) return;
  prepare_grid<S>(*s);
  const std::size_t n = s->P.size();
  const kern::GridGeom& g = s->g;
  auto G = s->grid.view();
  const auto q = grid_params();
  double* arrays[] = {G.v[0], G.v[1]};
  for (auto _ : state) {
    kern::grid_update(g, g.all_nodes(), G, q, s->row_force.data());
    kern::fill_periodic_ghosts(g, g.all_nodes(), arrays, 2);
    benchmark::ClobberMemory();
  }
  set_rate(state, n);
}

template <class S>
void BM_G2P(benchmark::State& state) {
  KernelState* s = get_state(state);
  if (!s) return;
  prepare_grid<S>(*s);
  const std::size_t n = s->P.size();
  const kern::GridGeom& g = s->g;
  auto G = s->grid.view();
  auto pv = s->P.view();
  // G2P overwrites velocities and the APIC matrix: keep the shared state as built.
  Particles& P = s->P;
  std::vector<double>* written[] = {&P.v[0], &P.v[1], &P.affine(0, 0), &P.affine(0, 1), &P.affine(1, 0),
                                    &P.affine(1, 1)};
  test::GradientArrays L(n);
  std::vector<std::vector<double>> saved;
  for (auto* v : written) saved.push_back(*v);
  // dt = 0: same arithmetic as a real step (x += dt v), but repeated gathers cannot walk the
  // particles off their cells or off the grid.
  const kern::G2PParams q{0.0, kLp, 0.0};
  for (auto _ : state) {
    kern::g2p<S, false, kern::G2PWhat::Full>(g, G, pv, n, q, L.view());
    benchmark::ClobberMemory();
  }
  for (std::size_t k = 0; k < saved.size(); ++k) written[k]->swap(saved[k]);
  set_rate(state, n);
}

// BM_Step: an elastic block at rest, with a small random velocity perturbation, inside a box
// of slip walls with a 2-cell gap on every side. The block side is sqrt(N/4) cells.
struct StepTemplate {
  kern::GridGeom g;
  Particles P;
  std::string error;
};

std::unique_ptr<StepTemplate> build_step_template(std::size_t n) {
  auto s = std::make_unique<StepTemplate>();
  if (n < 4 || n % 4 != 0) {
    s->error = "particle count must be a positive multiple of 4 (4 particles per cell)";
    return s;
  }
  constexpr int gap = 2;
  int bx, by;
  grid_dims(n / 4, bx, by);
  kern::GridGeom& g = s->g;
  g.h = kH;
  g.n[0] = bx + 2 * gap;
  g.n[1] = by + 2 * gap;
  const Material mat = bench_material();
  Particles& P = s->P;
  P = fill_rectangle(g, kPpc, Box{{gap * kH, gap * kH}, {(gap + bx) * kH, (gap + by) * kH}}, mat.rho0,
                     Vector{0.0, 0.0}, 0);
  if (P.size() != n) {
    s->error = "fill_rectangle made " + std::to_string(P.size()) + " particles, expected " + std::to_string(n);
    return s;
  }
  std::mt19937_64 rng(777 + n);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double dv = 1e-4 * wave_speed();  // ~0.6 m/s
  for (std::size_t i = 0; i < n; ++i) {
    P.v[0][i] = dv * u(rng);
    P.v[1][i] = dv * u(rng);
    P.id[i] = static_cast<std::uint32_t>(i);
  }
  if (!sort_particles(g, P)) s->error = "a particle lies outside the grid";
  return s;
}

StepTemplate& step_template(std::size_t n) {
  static std::map<std::size_t, std::unique_ptr<StepTemplate>> cache;
  auto& s = cache[n];
  if (!s) s = build_step_template(n);
  return *s;
}

// Elastic: linear EOS + elastic deviator. Shock: the full shock physics of a study run
// (Mie-Grueneisen, J2 radial return, artificial viscosity, energy equation with the
// transfer-dissipation heating of the APIC gather).
enum class Physics { Elastic, Shock };

template <class S, Physics Ph = Physics::Elastic>
std::unique_ptr<Simulation> make_simulation(const StepTemplate& t) {
  SolverConfig cfg;
  if constexpr (Ph == Physics::Shock) cfg.artificial_viscosity = true;
  cfg.shape = shape_kind<S>();
  cfg.ugimp_lp = kLp;
  cfg.transfer = Transfer::APIC;
  cfg.scheme = Scheme::USL;
  cfg.cfl = kCfl;
  cfg.walls = slip_box();
  const Material m = Ph == Physics::Shock ? shock_material() : bench_material();
  auto sim = std::make_unique<Simulation>(t.g, cfg, std::vector<Material>{m}, std::vector<int>{0}, t.P);
  sim->store_gradient(false);  // as in a run between its statistics
  return sim;
}

// Timed steps follow one untimed warm-up step, so the first timed step is not step 0: the
// engine permutes the particle arrays on steps 0, 20, 40, ... (permute_every = 20) and its
// first step also faults in the scratch arrays. Runs of >= 20 iterations thus include the
// permutation at the engine's rate; shorter runs (large N) mostly exclude it.
template <class S, Physics Ph = Physics::Elastic>
void BM_Step(benchmark::State& state) {
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  StepTemplate& t = step_template(n);
  if (!t.error.empty()) {
    state.SkipWithError(t.error.c_str());
    return;
  }
  PhaseTimes done, base;  // phase times of the timed steps; of the current sim's warm-up
  auto add = [](PhaseTimes& a, const PhaseTimes& b, double sign) {
    a.sort += sign * b.sort; a.p2g += sign * b.p2g; a.grid += sign * b.grid; a.g2p += sign * b.g2p;
    a.constitutive += sign * b.constitutive;
  };
  std::unique_ptr<Simulation> sim;
  auto fresh = [&]() -> bool {  // new simulation, one warm-up step; false on a StepError
    if (sim) {
      add(done, sim->phase_times(), 1.0);
      add(done, base, -1.0);
    }
    sim = make_simulation<S, Ph>(t);
    try {
      sim->step();
    } catch (const StepError& e) {
      state.SkipWithError(e.what());
      return false;
    }
    base = sim->phase_times();
    return true;
  };
  if (!fresh()) return;
  for (auto _ : state) {
    if (sim->steps() >= kStepRebuild) {
      state.PauseTiming();
      const bool ok = fresh();
      state.ResumeTiming();
      if (!ok) break;
    }
    try {
      sim->step();
    } catch (const StepError& e) {
      state.SkipWithError(e.what());
      break;
    }
  }
  add(done, sim->phase_times(), 1.0);
  add(done, base, -1.0);
  set_rate(state, n);
  // Seconds per step in each phase (the engine's own timers).
  using C = benchmark::Counter;
  state.counters["t_sort"] = C(done.sort, C::kAvgIterations);
  state.counters["t_p2g"] = C(done.p2g, C::kAvgIterations);
  state.counters["t_grid"] = C(done.grid, C::kAvgIterations);
  state.counters["t_g2p"] = C(done.g2p, C::kAvgIterations);
  state.counters["t_stress"] = C(done.constitutive, C::kAvgIterations);
}

// ---- registration ----

void sizes(benchmark::internal::Benchmark* b) {
  b->RangeMultiplier(4)->Range(1 << 16, 1 << 22)->UseRealTime()->Unit(benchmark::kMillisecond);
}

template <class F>
void reg(const std::string& name, F fn) {
  sizes(benchmark::RegisterBenchmark(name.c_str(), fn));
}

template <class S>
void register_shape(const std::string& family) {
  const std::string sh = std::string("<") + S::name + ">";
  if (family == "p2g") {
    reg("BM_P2G_Colored" + sh, BM_P2G<S, P2GMode::Colored>);
    reg("BM_P2G_Atomic" + sh, BM_P2G<S, P2GMode::Atomic>);
    reg("BM_P2G_Serial" + sh, BM_P2G<S, P2GMode::Serial>);
  } else if (family == "grid") {
    reg("BM_GridUpdate" + sh, BM_GridUpdate<S>);
  } else if (family == "g2p") {
    reg("BM_G2P" + sh, BM_G2P<S>);
  } else if (family == "step") {
    reg("BM_Step" + sh, BM_Step<S>);
    reg("BM_StepShock" + sh, BM_Step<S, Physics::Shock>);
  }
}

void register_all() {
  reg("BM_Sort", BM_Sort);  // the sort does not depend on the shape function
  for (const char* family : {"p2g", "grid", "g2p", "step"}) {
    register_shape<kern::Linear>(family);
    register_shape<kern::UGIMP>(family);
    register_shape<kern::QuadraticBSpline>(family);
    register_shape<kern::CubicBSpline>(family);
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("omp_max_threads", std::to_string(omp_get_max_threads()));
  const char* bind = std::getenv("OMP_PROC_BIND");
  benchmark::AddCustomContext("omp_proc_bind", bind ? bind : "");
  benchmark::AddCustomContext("particles_per_cell", std::to_string(kPpc * kPpc));
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
