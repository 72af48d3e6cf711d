#include "kernels/dimension.hpp"
#include "engine/run.hpp"

#include <omp.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>
#include <string_view>

#include "engine/case_reader.hpp"
#include "engine/checkpoint.hpp"
#include "engine/columns.hpp"
#include "engine/diagnostics.hpp"
#include "engine/output.hpp"
#include "engine/provenance.hpp"
#include "engine/thermo.hpp"
#include "engine/timer.hpp"

namespace SMPM_NS {

namespace {

// series.csv and series.h5: one row per region at a time, one entry per column in file order. The
// CSV header, each row, the HDF5 table's columns and units, and the checkpoint's keys
// ("series/<name>") all come from kSeriesColumns.
struct SeriesRow {
  double t;  // [s]
  std::size_t region;
  std::string_view name;
  const RegionStats& s;
};
constexpr double kPerUs2 = 1e-12;  // 1/s^2 -> 1/us^2
constexpr Column<SeriesRow> kSeriesColumns[] = {
    {"time_ns", "ns", [](const SeriesRow& r) { return r.t * 1e9; }},
    {"region", "index into the regions attribute", [](const SeriesRow& r) { return double(r.region); },
     [](const SeriesRow& r) { return r.name; }},
    {"count", "1", [](const SeriesRow& r) { return double(r.s.count); }},
    {"P_mean_GPa", "GPa", [](const SeriesRow& r) { return r.s.P.mean * 1e-9; }},
    {"P_std_GPa", "GPa", [](const SeriesRow& r) { return r.s.P.std * 1e-9; }},
    {"T_mean_K", "K", [](const SeriesRow& r) { return r.s.T.mean; }},
    {"T_std_K", "K", [](const SeriesRow& r) { return r.s.T.std; }},
    {"rho_mean_gcc", "g/cc", [](const SeriesRow& r) { return r.s.rho.mean * 1e-3; }},
    {"rho_std_gcc", "g/cc", [](const SeriesRow& r) { return r.s.rho.std * 1e-3; }},
    {"Uy_mean_ms", "m/s", [](const SeriesRow& r) { return r.s.Uy.mean; }},
    {"Uy_std_ms", "m/s", [](const SeriesRow& r) { return r.s.Uy.std; }},
    {"R2_mean_per_us2", "1/us^2", [](const SeriesRow& r) { return r.s.R2 * kPerUs2; }},
    {"D2_mean_per_us2", "1/us^2", [](const SeriesRow& r) { return r.s.D2 * kPerUs2; }},
    {"S2_mean_per_us2", "1/us^2", [](const SeriesRow& r) { return r.s.S2 * kPerUs2; }},
    {"P_skew", "1", [](const SeriesRow& r) { return r.s.P.skew; }},
    {"P_kurt", "1", [](const SeriesRow& r) { return r.s.P.kurt; }},
    {"T_skew", "1", [](const SeriesRow& r) { return r.s.T.skew; }},
    {"T_kurt", "1", [](const SeriesRow& r) { return r.s.T.kurt; }},
    {"rho_skew", "1", [](const SeriesRow& r) { return r.s.rho.skew; }},
    {"rho_kurt", "1", [](const SeriesRow& r) { return r.s.rho.kurt; }},
    {"Uy_skew", "1", [](const SeriesRow& r) { return r.s.Uy.skew; }},
    {"Uy_kurt", "1", [](const SeriesRow& r) { return r.s.Uy.kurt; }},
    {"R_mean_per_us", "1/us", [](const SeriesRow& r) { return r.s.R * 1e-6; }},
    {"D_mean_per_us", "1/us", [](const SeriesRow& r) { return r.s.D * 1e-6; }},
    {"open_porosity", "1", [](const SeriesRow& r) { return r.s.open; }},
};
// the region column: its name in series.csv, its index in series.h5
constexpr std::size_t kSeriesRegionColumn = 1;

// energy.csv: one row per time
// Extensive quantities (energy, momentum, mass) are per unit depth at D = 2 (plane strain) and
// whole at D = 3; the columns' names and units say which.
constexpr int kDim = kern::kDim;
constexpr bool kPerDepth = kDim == 2;
constexpr const char* kEnergyUnit = kPerDepth ? "J/m" : "J";
struct EnergyRow {
  double t;  // [s]
  Simulation::Energy e;
  std::array<double, kDim> q;
  Simulation::Removed removed;
  double residual;  // [J/m] at D = 2, [J] at D = 3
};
constexpr auto kEnergyColumns = [] {
  std::array<Column<EnergyRow>, 7 + kDim> c{};
  int i = 0;
  c[i++] = {"time_ns", "ns", [](const EnergyRow& r) { return r.t * 1e9; }};
  c[i++] = {kPerDepth ? "kinetic_J_per_m" : "kinetic_J", kEnergyUnit, [](const EnergyRow& r) { return r.e.kinetic; }};
  c[i++] = {kPerDepth ? "internal_J_per_m" : "internal_J", kEnergyUnit,
            [](const EnergyRow& r) { return r.e.internal; }};
  c[i++] = {kPerDepth ? "total_J_per_m" : "total_J", kEnergyUnit, [](const EnergyRow& r) { return r.e.total(); }};
  constexpr const char* kMomentum[2][3] = {{"momentum_x_kg_m_s", "momentum_y_kg_m_s", "momentum_z_kg_m_s"},
                                           {"momentum_x_kg_m_s_per_m", "momentum_y_kg_m_s_per_m", ""}};
  constexpr const char* kMomentumUnit = kPerDepth ? "kg m/s per m" : "kg m/s";
  c[i++] = {kMomentum[kPerDepth][0], kMomentumUnit, [](const EnergyRow& r) { return r.q[0]; }};
  c[i++] = {kMomentum[kPerDepth][1], kMomentumUnit, [](const EnergyRow& r) { return r.q[1]; }};
  if constexpr (kDim == 3) c[i++] = {kMomentum[0][2], kMomentumUnit, [](const EnergyRow& r) { return r.q[kDim - 1]; }};
  c[i++] = {kPerDepth ? "wall_removed_J_per_m" : "wall_removed_J", kEnergyUnit,
            [](const EnergyRow& r) { return r.removed.wall; }};
  c[i++] = {kPerDepth ? "contact_removed_J_per_m" : "contact_removed_J", kEnergyUnit,
            [](const EnergyRow& r) { return r.removed.contact; }};
  c[i++] = {kPerDepth ? "residual_J_per_m" : "residual_J", kEnergyUnit, [](const EnergyRow& r) { return r.residual; }};
  return c;
}();

// front.csv: the compression front's position at a time
struct FrontRow {
  double t, at;  // [s], the front's position along the impact axis [m]
};
constexpr Column<FrontRow> kFrontColumns[] = {
    {"time_ns", "ns", [](const FrontRow& r) { return r.t * 1e9; }},
    {"front_y_um", "um", [](const FrontRow& r) { return r.at * 1e6; }},
};

// wall.csv: the bottom wall's normal stress at a time, its force over its area (at D = 2 the
// force per unit depth over its width)
struct WallRow {
  double t, force, area;  // [s], [N] ([N/m] at D = 2), [m^2] ([m] at D = 2)
};
constexpr Column<WallRow> kWallColumns[] = {
    {"time_ns", "ns", [](const WallRow& r) { return r.t * 1e9; }},
    {"wall_stress_GPa", "GPa", [](const WallRow& r) { return r.force / r.area * 1e-9; }},
};

// voids.csv: the void area (D = 2) or volume (D = 3) open in the target ("target") or one of its
// regions at a time
struct VoidsRow {
  double t;  // [s]
  std::string_view region;
  double area, fraction;  // [m^2] or [m^3], of the region's band (NaN for the whole target)
};
constexpr Column<VoidsRow> kVoidsColumns[] = {
    {"time_ns", "ns", [](const VoidsRow& r) { return r.t * 1e9; }},
    {"region", "name", nullptr, [](const VoidsRow& r) { return r.region; }},
    {kPerDepth ? "open_area_um2" : "open_volume_um3", kPerDepth ? "um^2" : "um^3",
     [](const VoidsRow& r) { return r.area * (kPerDepth ? 1e12 : 1e18); }},
    {"open_fraction", "1", [](const VoidsRow& r) { return r.fraction; }},
};

// An output that could not be written: the run ends "failed", exit 1 (RunSummary::output_failed).
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A CSV stream after a row: flushed whole (a killed run leaves no cut row) and checked.
void flush_checked(std::ofstream& o, const std::filesystem::path& file) {
  o.flush();
  if (!o) throw OutputError("cannot write " + file.string() + ": " + std::strerror(errno));
}

// What a run writes into its output directory (and nothing else is removed by --overwrite).
const char* const kOutputFiles[] = {"run.json", "case_resolved.toml", "energy.csv", "series.csv", "series.h5",
                                    "front.csv", "wall.csv", "voids.csv", "gauges.csv", "freesurface.csv"};
const char* const kOutputDirs[] = {"fields", "figures", "checkpoint"};

// Before a run writes: an earlier run's outputs (only with overwrite; a new run without it
// was refused by check_output_dir before the scene was built) and any partial .tmp file of a
// killed run go. A resumed run keeps its outputs (resume_run truncates them to its checkpoint).
void clear_output_dir(const std::filesystem::path& out, bool overwrite) {
  namespace fs = std::filesystem;
  for (const fs::path& d : {out, out / "fields", out / "checkpoint"}) {
    std::error_code ec;
    if (!fs::is_directory(d, ec)) continue;
    for (const auto& f : fs::directory_iterator(d))
      if (f.path().extension() == ".tmp") fs::remove(f.path());
  }
  if (!overwrite) return;
  for (const char* f : kOutputFiles) fs::remove(out / f);
  for (const char* d : kOutputDirs) fs::remove_all(out / d);
}

// One run at a time per output directory: an exclusive flock on DIR/.lock, held while the run
// writes (released by the kernel when the process ends, however it ends). A second run or a
// resume into the same directory is refused (exit 2) instead of mixing its rows into the first's.
class DirLock {
 public:
  explicit DirLock(const std::filesystem::path& dir) {
    const auto file = dir / ".lock";
    fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw OutputError("cannot create " + file.string() + ": " + std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw CaseError("output directory '" + dir.string() + "' is in use by another shockmpm run (it holds " +
                      file.string() + "); wait for it, stop it, or choose another --out");
    }
  }
  ~DirLock() { ::close(fd_); }
  DirLock(const DirLock&) = delete;
  DirLock& operator=(const DirLock&) = delete;

 private:
  int fd_ = -1;
};

// Peak resident set size of the process [bytes] (Linux reports KiB).
long long peak_rss_bytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<long long>(u.ru_maxrss) * 1024;
}

std::string hms(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--:--";
  const long t = std::lround(s);
  char b[32];
  std::snprintf(b, sizeof b, "%02ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  return b;
}

std::vector<SnapshotField> snapshot_fields(const Simulation& sim) {
  const auto& thermo = sim.thermo();
  const Particles& P = sim.particles();
  const std::size_t n = P.size();
  std::vector<SnapshotField> f;
  auto vec = [&](const char* name, const char* units, const std::vector<double>(&a)[kern::kDim]) {
    SnapshotField s{name, units, kern::kDim, std::vector<double>(kern::kDim * n)};
    for (std::size_t i = 0; i < n; ++i)
      for (int d = 0; d < kern::kDim; ++d) s.data[kern::kDim * i + d] = a[d][i];
    f.push_back(std::move(s));
  };
  auto scal = [&](const std::string& name, const char* units, auto get) {
    SnapshotField s{name, units, 1, std::vector<double>(n)};
    for (std::size_t i = 0; i < n; ++i) s.data[i] = get(i);
    f.push_back(std::move(s));
  };
  vec("position", "m", P.x);
  vec("velocity", "m/s", P.v);
  scal("pressure", "Pa", [&](std::size_t i) { return P.p[i]; });
  scal("density", "kg/m^3", [&](std::size_t i) { return P.m[i] / P.V[i]; });
  // total stress s - p I by symmetric component; at D = 2 also the out-of-plane s_zz - p
  for (int k = 0; k < kSym; ++k) {
    const int r = kern::sym_row(kern::kDim, k), c = kern::sym_col(kern::kDim, k);
    const std::string name = std::string("stress_") + kern::kAxisNames[r] + kern::kAxisNames[c];
    if (r == c) scal(name, "Pa", [&, k](std::size_t i) { return P.s[k][i] - P.p[i]; });
    else scal(name, "Pa", [&, k](std::size_t i) { return P.s[k][i]; });
  }
  if constexpr (kern::kDim == 2) {
    scal("stress_zz", "Pa", [&](std::size_t i) { return -(P.s[0][i] + P.s[1][i]) - P.p[i]; });
  } else {
    // the same stress as one tensor for ParaView (Tensor6: xx, xy, xz, yy, yz, zz)
    SnapshotField t{"stress", "Pa", 6, std::vector<double>(6 * n)};
    constexpr int kRow[6] = {0, 0, 0, 1, 1, 2}, kCol[6] = {0, 1, 2, 1, 2, 2};
    for (int j = 0; j < 6; ++j) {
      const int k = kern::sym_index(kern::kDim, kRow[j], kCol[j]);
      const bool diag = kRow[j] == kCol[j];
      for (std::size_t i = 0; i < n; ++i) t.data[6 * i + j] = P.s[k][i] - (diag ? P.p[i] : 0.0);
    }
    f.push_back(std::move(t));
  }
  if (!P.e.empty()) {
    scal("energy", "J/kg", [&](std::size_t i) { return P.e[i]; });
    scal("temperature", "K", [&](std::size_t i) {
      const int k = sim.body_material()[P.body[i]];
      return particle_temperature(P, i, thermo[k], sim.materials()[k]);
    });
  }
  if (!P.epsp.empty()) scal("plastic_strain", "1", [&](std::size_t i) { return P.epsp[i]; });
  if (!P.q.empty()) scal("viscous_pressure", "Pa", [&](std::size_t i) { return P.q[i]; });
  scal("body", "1", [&](std::size_t i) { return double(P.body[i]); });
  // the velocity field a point scatters to (void faces, two-body contact): 0 or 1
  if (!P.field.empty()) scal("field", "1", [&](std::size_t i) { return double(P.field[i]); });
  scal("id", "1", [&](std::size_t i) { return double(P.id[i]); });
  return f;
}

// run.json's entry of body k: its setup and, for a Mie-Gruneisen body in motion, the exact
// Hugoniot states its stop from that speed reaches.
toml::table body_json(const Scene& scene, std::size_t k) {
  const auto& b = scene.bodies[k];
  toml::array velocity;
  for (int a = 0; a < kDim; ++a) velocity.push_back(b.velocity[a]);
  toml::table bt{{"name", b.name}, {"material", b.material}, {"particles", static_cast<int64_t>(b.particles)},
                 {kPerDepth ? "area_m2" : "volume_m3", b.area}, {"velocity_m_s", velocity}, {"porosity", b.porosity},
                 {"voids", static_cast<int64_t>(b.voids)}};
  const Material& m = scene.materials[scene.body_material[k]];
  const double up = magnitude(b.velocity);
  if (!m.has_hugoniot() || up <= 0.0) return bt;
  // the exact dense Hugoniot state for a stop from this speed (wall or symmetric impact)
  const auto h = hugoniot(m, up);
  if (h.in_range)
    bt.insert("dense_hugoniot", toml::table{{"up_m_s", h.up}, {"Us_m_s", h.Us}, {"P_Pa", h.P},
                                            {"rho_kg_m3", h.rho}, {"e_J_kg", h.e}, {"T_K", h.T},
                                            {"T_simple_K", h.T_simple}});
  else
    bt.insert("dense_hugoniot", toml::table{{"beyond_range", true}, {"largest_up_m_s", h.up}});
  if (b.porosity > 0.0) {
    // complete compaction: the front a converged porous run approaches (docs/verification.md)
    const auto c = porous_hugoniot(m, up, b.porosity);
    if (c.in_range)
      bt.insert("compacted_hugoniot", toml::table{{"up_m_s", c.up}, {"Us_m_s", c.Us},
                                                  {"front_speed_wall_frame_m_s", c.Us - c.up}, {"P_Pa", c.P},
                                                  {"rho_kg_m3", c.rho}, {"e_J_kg", c.e}, {"T_K", c.T}});
    else
      bt.insert("compacted_hugoniot", toml::table{{"not_found", true}});
  }
  return bt;
}

// A JSON file written whole: to FILE.tmp, then renamed (a killed run leaves the previous one).
void write_json_file(const std::filesystem::path& file, const toml::table& t) {
  const auto tmp = file.string() + ".tmp";
  {
    std::ofstream o(tmp);
    o << toml::json_formatter{t} << "\n";
    o.flush();
    if (!o) {
      const std::string why = std::strerror(errno);
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw OutputError("cannot write " + tmp + ": " + why);
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) throw OutputError("cannot rename " + tmp + " to " + file.string() + ": " + ec.message());
}

void write_run_json(const std::filesystem::path& file, const Scene& scene, const Simulation& sim,
                    const RunSummary& s, int threads, const toml::table& prov) {
  toml::table t;
  t.insert("version", SHOCKMPM_VERSION);
  t.insert("provenance", prov);
  t.insert("case", scene.name);
  t.insert("status", s.status);
  t.insert("message", s.message);
  t.insert("threads", threads);
  t.insert("particles", static_cast<int64_t>(sim.particles().size()));
  t.insert("nodes", static_cast<int64_t>(sim.grid().geom.num_nodes()));
  t.insert("active_nodes", sim.mean_active_nodes());  // per step, the grid passes' box (mean)
  t.insert("steps", static_cast<int64_t>(s.steps));
  t.insert("end_time_s", s.end_time);
  t.insert("wall_seconds", s.wall_seconds);
  t.insert("particle_steps_per_s", s.particle_steps_per_s);
  t.insert("resident_bytes", static_cast<int64_t>(sim.bytes()));
  t.insert("particle_bytes_per_particle",
           double(sim.particles().bytes()) / double(std::max<std::size_t>(1, sim.particles().size())));
  t.insert("peak_rss_bytes", static_cast<int64_t>(peak_rss_bytes()));
  toml::array fields;
  for (const auto& f : sim.particles().fields_in_use()) fields.push_back(f);
  t.insert("particle_fields", std::move(fields));
  const auto& pt = sim.phase_times();
  // the step's phases, then the run loop's diagnostics (energy, front, wall, series rows) and
  // output (snapshots, series.h5, run.json); wall_seconds covers all of them
  t.insert("phase_seconds", toml::table{{"sort", pt.sort}, {"p2g", pt.p2g}, {"grid", pt.grid},
                                        {"contact", pt.contact}, {"g2p", pt.g2p}, {"constitutive", pt.constitutive},
                                        {"heat", pt.heat}, {"diagnostics", s.diagnostics_seconds},
                                        {"output", s.output_seconds}});
  toml::array bodies;
  for (std::size_t k = 0; k < scene.bodies.size(); ++k) bodies.push_back(body_json(scene, k));
  t.insert("bodies", std::move(bodies));
  toml::array regions;  // the regions of series.csv, in its order
  for (const auto& r : scene.regions)
    regions.push_back(toml::table{{"name", r.name}, {"y_range_um", toml::array{r.lo * 1e6, r.hi * 1e6}},
                                  {"body", static_cast<int64_t>(r.body)}});
  t.insert("regions", std::move(regions));
  t.insert("case_resolved", scene.resolved);
  write_json_file(file, t);
}

// "(x, y) um": point i's position, in o's number format
std::ostream& put_position_um(std::ostream& o, const Particles& P, std::size_t i) {
  o << "(";
  for (int d = 0; d < kern::kDim; ++d) o << (d ? ", " : "") << P.x[d][i] * 1e6;
  return o << ") um";
}

// `check`'s lines on the followed points: each gauge (only their count beyond 20), each free surface.
void describe_points(std::ostream& o, const Scene& sc) {
  const Particles& P = sc.particles;
  if (!sc.gauges.empty()) o << "gauges          " << sc.gauges.size() << " (gauges.csv)\n";
  if (sc.gauges.size() <= 20)
    for (const auto& g : sc.gauges) {
      o << "  gauge " << std::left << std::setw(10) << g.name << std::right << " point " << g.id << " of body "
        << sc.bodies[P.body[g.id]].name << " at ";
      put_position_um(o, P, g.id) << "\n";
    }
  for (const auto& f : sc.free_surfaces)
    o << "free surface    body " << f.body_name << ": the " << f.ids.size() << " points of its top row at "
      << kern::kAxisNames[kImpactAxis] << " = " << P.x[kImpactAxis][f.ids.front()] * 1e6 << " um (freesurface.csv)\n";
}

}  // namespace

std::string describe_scene(const Scene& sc) {
  std::ostringstream o;
  const auto& g = sc.geom;
  o << "case            " << sc.name << "\n";
  o << "grid            ";
  for (int a = 0; a < kDim; ++a) o << (a ? " x " : "") << g.n[a];
  o << " cells of " << g.h * 1e6 << " um";
  for (int a = 0; a < kDim; ++a)
    o << ", " << kern::kAxisNames[a] << " in [" << g.lo[a] * 1e6 << ", " << (g.lo[a] + g.length(a)) * 1e6 << "]"
      << (a == kDim - 1 ? " um" : "");
  for (int a = 0; a < kDim; ++a)
    if (g.wrap[a]) o << ", periodic in " << kern::kAxisNames[a];
  o << "\n";
  o << "particles       " << sc.particles.size() << "\n";
  for (const auto& b : sc.bodies)
    o << "  body " << std::left << std::setw(10) << b.name << std::right << " material " << b.material << ", "
      << b.particles << " particles, " << (kPerDepth ? "area " : "volume ") << b.area * (kPerDepth ? 1e12 : 1e18)
      << (kPerDepth ? " um^2" : " um^3")
      << (b.voids ? ", porosity " + std::to_string(b.porosity) + " (" + std::to_string(b.voids) + " voids)" : "")
      << "\n";
  describe_points(o, sc);
  if (sc.solver.void_faces == VoidFaces::Separate)
    o << "void faces      " << sc.solver.void_face_fields << " velocity fields, welded at " << sc.solver.void_face_volume_fraction
      << " of a cell" << (sc.solver.void_face_merge ? ", merged once closed" : "") << "\n";
  Simulation sim(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
  const double dt = sim.stable_dt();
  o << "time step       " << dt * 1e9 << " ns (" << (sc.solver.fixed_dt > 0 ? "fixed" : "CFL at t = 0") << ")\n";
  o << "end time        " << sc.run.end_time * 1e9 << " ns, about " << std::llround(std::ceil(sc.run.end_time / dt))
    << " steps\n";
  for (std::size_t k = 0; k < sc.bodies.size(); ++k) {
    const auto& b = sc.bodies[k];
    const Material& m = sc.materials[sc.body_material[k]];
    const double up = magnitude(b.velocity);
    if (!m.has_hugoniot() || up <= 0.0) continue;
    const auto h = hugoniot(m, up);
    if (!h.in_range) {
      o << "  " << b.name << " stopped from " << up << " m/s: beyond the range of the EOS's dense Hugoniot "
        << "(it reaches up = " << h.up << " m/s at " << h.rho / m.rho0 << " rho0); no exact state\n";
      continue;
    }
    o << "  " << b.name << " stopped from " << up << " m/s (dense Hugoniot): Us " << h.Us << " m/s, P "
      << h.P * 1e-9 << " GPa, rho " << h.rho << " kg/m^3, T " << h.T << " K (T0 + e/cv: " << h.T_simple << " K)\n";
    if (b.porosity > 0.0) {
      const auto c = porous_hugoniot(m, up, b.porosity);
      if (c.in_range)
        o << "  " << b.name << " fully compacted from porosity " << b.porosity << ": front " << c.Us - c.up
          << " m/s in the wall frame, P " << c.P * 1e-9 << " GPa, rho " << c.rho << " kg/m^3, T " << c.T << " K\n";
      else
        o << "  " << b.name << " fully compacted from porosity " << b.porosity << ": no state found (the EOS has no "
          << "compacted Hugoniot state with P > 0 between rho00 and 4 rho0 here); run.json says not_found\n";
    }
  }
  o << "memory          " << std::fixed << std::setprecision(1) << sim.bytes() / 1048576.0 << " MiB resident ("
    << std::setprecision(0) << double(sim.particles().bytes()) / std::max<std::size_t>(1, sc.particles.size())
    << " bytes per particle)\n";
  return o.str();
}

std::string resolved_case_text(const Scene& scene) {
  toml::table t = scene.resolved;
  std::ostringstream o;
  o << "# The case as run by shockmpm " << SHOCKMPM_VERSION << ", every default filled in; it runs again as it is.\n";
  if (const auto* lib = t.get_as<std::string>("materials_file_used"))
    o << "# Materials library read: " << lib->get() << "\n";
  t.erase("materials_file_used");
  t.erase("materials_file");  // the materials are written whole below: the file needs no library
  // each material is written whole: the library entry it started from is a comment, so the file
  // needs no library next to it
  if (auto* mats = t.get_as<toml::table>("materials"))
    for (auto&& [name, m] : *mats)
      if (auto* mt = m.as_table())
        if (const auto* base = mt->get_as<std::string>("base")) {
          o << "# materials." << name.str() << ": from the library entry '" << base->get() << "'\n";
          mt->erase("base");
        }
  o << "\n" << t << "\n";
  return o.str();
}

namespace {

// A CSV file of the run, written a whole row at a time.
class CsvFile {
 public:
  // A new run writes the header; a resumed one cuts the file back to its length at the checkpoint
  // (rows written after it go) and appends. precision: significant digits of its numbers.
  void open(const std::filesystem::path& file, const std::string& header, int precision,
            const CheckpointReader* resume) {
    file_ = file;
    if (!resume) {
      o_.open(file);
      o_ << header;
    } else {
      const auto length = static_cast<std::uintmax_t>(resume->integer(key()));
      std::error_code ec;
      if (!std::filesystem::exists(file, ec) || std::filesystem::file_size(file, ec) < length)
        throw CaseError("cannot resume: " + file.string() + " is missing or shorter than at the checkpoint (" +
                        std::to_string(length) + " bytes)");
      std::filesystem::resize_file(file, length, ec);
      if (ec) throw OutputError("cannot cut " + file.string() + " back to its checkpoint length: " + ec.message());
      o_.open(file, std::ios::app);
    }
    o_ << std::setprecision(precision);
  }
  bool is_open() const { return o_.is_open(); }
  std::ostream& stream() { return o_; }
  template <class Columns, class Row>
  void row(const Columns& cols, const Row& r) {
    csv_row(o_, cols, r);
  }
  // After a write: the rows flushed whole (a killed run leaves no cut row) and checked.
  void flush() { flush_checked(o_, file_); }
  // The file's length [bytes] at a checkpoint, to which a resume cuts it back.
  void save(CheckpointWriter& w) {
    if (is_open()) w.put(key(), static_cast<std::int64_t>(o_.tellp()));
  }

 private:
  std::string key() const { return "csv/" + file_.filename().string(); }
  std::filesystem::path file_;
  std::ofstream o_;
};

// Every output of a run but run.json and case_resolved.toml. The constructor opens them (a resumed
// run: cut back to the checkpoint and reopened); each write_* writes the rows of the simulation's
// current state and flushes them; save() puts their state into a checkpoint. The seconds spent
// go to the summary's diagnostics_seconds (CSV rows) and output_seconds (snapshots, series.h5).
class RunOutputs {
 public:
  RunOutputs(const Scene& scene, const Simulation& sim, const std::filesystem::path& out, RunSummary& s,
             const CheckpointReader* resume);
  void write_energy();     // energy.csv
  void write_points();     // gauges.csv and freesurface.csv
  void write_front();      // front.csv (a target at rest has none)
  void write_series();     // series.csv, and the rows of series.h5's table
  void write_series_h5();  // series.h5, the table so far
  void write_wall();       // wall.csv (a bottom wall only), after every step
  void snapshot();         // fields/snap_<step>.h5, then voids.csv (a target with voids only)
  double E0() const { return E0_; }
  // The series table, the snapshot index, the followed points and every CSV file's length.
  void save(CheckpointWriter& w);

 private:
  void write_voids();
  const Scene& scene_;
  const Simulation& sim_;
  std::filesystem::path out_;
  RunSummary& s_;
  SnapshotWriter snaps_;
  // the compression front runs through the target: the body named "target", else body 0
  std::size_t target_;
  double u0_;  // the target's initial velocity along the impact axis [m/s]
  CsvFile voids_, series_, front_, energy_, gauges_, surface_, wall_;
  std::vector<std::vector<double>> table_;  // series.h5: one vector per column of kSeriesColumns
  double E0_ = 0.0;                         // total energy at t = 0 [J/m]
  PointRecorder points_;
};

RunOutputs::RunOutputs(const Scene& scene, const Simulation& sim, const std::filesystem::path& out, RunSummary& s,
                       const CheckpointReader* resume)
    : scene_(scene), sim_(sim), out_(out), s_(s), snaps_(out / "fields"), target_(scene.target),
      u0_(scene.bodies[scene.target].velocity[kImpactAxis]), table_(std::size(kSeriesColumns)),
      points_(scene.gauges, scene.free_surfaces, sim.particles().size()) {
  if (resume) snaps_.adopt(resume->text("run/snapshots"));
  // voids.csv: the void area left open in the target (and its share of each region's band), at
  // every snapshot
  if (scene.bodies[target_].voids > 0) voids_.open(out / "voids.csv", csv_header(kVoidsColumns), 8, resume);
  // regional statistics: series.csv every diagnostics interval, series.h5 with the same table
  series_.open(out / "series.csv", csv_header(kSeriesColumns), 8, resume);
  if (resume)
    for (std::size_t c = 0; c < table_.size(); ++c)
      resume->get(std::string("series/") + kSeriesColumns[c].name, table_[c]);
  if (u0_ != 0.0) front_.open(out / "front.csv", csv_header(kFrontColumns), 10, resume);
  energy_.open(out / "energy.csv", csv_header(kEnergyColumns), 12, resume);
  E0_ = resume ? resume->number("run/E0") : sim.energy().total();
  // gauges.csv and freesurface.csv: the points followed from t = 0 (engine/gauges.hpp), with
  // energy.csv's rows
  if (resume) points_.restore(*resume);
  if (points_.has_gauges()) gauges_.open(out / "gauges.csv", PointRecorder::gauge_header(), 10, resume);
  if (points_.has_surfaces()) surface_.open(out / "freesurface.csv", PointRecorder::surface_header(), 10, resume);
  if (scene.solver.walls.lo[kImpactAxis] != kern::Wall::None)
    wall_.open(out / "wall.csv", csv_header(kWallColumns), 10, resume);
}

void RunOutputs::write_energy() {
  Timed t(s_.diagnostics_seconds);
  EnergyRow row{sim_.time(), sim_.energy(), sim_.momentum(), sim_.removed(), 0.0};
  // residual: the scheme's own energy error, what is neither in the total nor removed as loss
  const double lost = sim_.removed_is_heat() ? 0.0 : row.removed.wall + row.removed.contact;
  row.residual = row.e.total() + lost - E0_;
  energy_.row(kEnergyColumns, row);
  energy_.flush();
}

void RunOutputs::write_points() {
  Timed t(s_.diagnostics_seconds);
  if (gauges_.is_open()) {
    points_.gauge_rows(gauges_.stream(), sim_);
    gauges_.flush();
  }
  if (surface_.is_open()) {
    points_.surface_rows(surface_.stream(), sim_);
    surface_.flush();
  }
}

void RunOutputs::write_front() {
  if (u0_ == 0.0) return;
  Timed t(s_.diagnostics_seconds);
  const auto& g = scene_.geom;
  const int a = kImpactAxis;
  const double at =
      front_position(sim_.particles(), static_cast<std::uint8_t>(target_), u0_, g.lo[a], g.h, g.n[a], u0_ < 0);
  if (std::isfinite(at)) {
    front_.row(kFrontColumns, FrontRow{sim_.time(), at});
    front_.flush();
  }
}

void RunOutputs::write_series() {
  Timed t(s_.diagnostics_seconds);
  const auto stats = region_stats(sim_.particles(), scene_.regions, sim_.thermo(), sim_.materials(),
                                  sim_.body_material(), sim_.gradient_current());
  for (std::size_t r = 0; r < stats.size(); ++r) {
    const SeriesRow row{sim_.time(), r, scene_.regions[r].name, stats[r]};
    for (std::size_t c = 0; c < table_.size(); ++c) table_[c].push_back(kSeriesColumns[c].value(row));
    series_.row(kSeriesColumns, row);
  }
  series_.flush();
}

void RunOutputs::write_series_h5() {
  Timed t(s_.output_seconds);
  const auto columns = column_names(kSeriesColumns), units = column_units(kSeriesColumns);
  std::string unit_list, region_names;
  for (std::size_t c = 0; c < columns.size(); ++c)
    unit_list += (c ? ", " : "") + columns[c] + ' ' + units[c];
  for (const auto& r : scene_.regions) region_names += (region_names.empty() ? "" : ",") + r.name;
  write_table_h5(out_ / "series.h5", "series", columns, table_,
                 {{"regions", region_names}, {"region_column", units[kSeriesRegionColumn]}, {"units", unit_list}});
}

void RunOutputs::write_wall() {
  if (!wall_.is_open()) return;
  Timed t(s_.diagnostics_seconds);
  double area = 1.0;  // the wall's: the grid's extent across the impact axis
  for (int a = 0; a < kDim; ++a)
    if (a != kImpactAxis) area *= scene_.geom.length(a);
  wall_.row(kWallColumns, WallRow{sim_.time(), sim_.wall_forces().lo[kImpactAxis], area});
  wall_.flush();
}

// voids.csv: pixels a third of the target's point spacing (open_area), windows the whole
// target and each of its regions' bands
void RunOutputs::write_voids() {
  if (!voids_.is_open()) return;
  Timed t(s_.diagnostics_seconds);
  const auto& g = scene_.geom;
  const auto& body = scene_.bodies[target_];
  const double pixel = point_size(body.area / double(body.particles)) / 3;  // [m]
  const auto b = static_cast<std::uint8_t>(target_);
  // the windows: the grid's lateral extent, along the impact axis all of it or a region's band
  Window all;
  double lateral = 1.0;  // the lateral extent's length (D = 2) or area (D = 3) [m, m^2]
  for (int d = 0; d < kern::kDim; ++d) {
    all.lo[d] = d == kImpactAxis ? -1e300 : g.lo[d];
    all.hi[d] = d == kImpactAxis ? 1e300 : g.lo[d] + g.length(d);
    if (d != kImpactAxis) lateral *= g.length(d);
  }
  std::vector<Window> win{all};
  for (const auto& r : scene_.regions) {
    Window w = all;
    w.lo[kImpactAxis] = r.lo;
    w.hi[kImpactAxis] = r.hi;
    win.push_back(w);
  }
  const auto a = open_area(sim_.particles(), b, win, pixel, kCoverRadius, periods(g), grid_origin(g));
  voids_.row(kVoidsColumns, VoidsRow{sim_.time(), "target", a[0], std::numeric_limits<double>::quiet_NaN()});
  for (std::size_t k = 0; k < scene_.regions.size(); ++k) {
    const auto& r = scene_.regions[k];
    if (r.body != b) continue;
    voids_.row(kVoidsColumns, VoidsRow{sim_.time(), r.name, a[k + 1], a[k + 1] / ((r.hi - r.lo) * lateral)});
  }
  voids_.flush();
}

void RunOutputs::snapshot() {
  {
    Timed t(s_.output_seconds);
    snaps_.write(snapshot_fields(sim_), sim_.particles().size(), sim_.time(), sim_.steps());
  }
  write_voids();
}

void RunOutputs::save(CheckpointWriter& w) {
  for (std::size_t c = 0; c < table_.size(); ++c) w.put(std::string("series/") + kSeriesColumns[c].name, table_[c]);
  w.put("run/snapshots", snaps_.index_text());
  if (points_.has_gauges() || points_.has_surfaces()) points_.save(w);
  for (CsvFile* f : {&energy_, &series_, &front_, &wall_, &voids_, &gauges_, &surface_}) f->save(w);
}

// The provenance run.json carries: this run's, or for a resumed run the first run's with one
// entry per resume in "restarts".
toml::table run_provenance(const RunOptions& opt, int threads, const CheckpointReader* resume) {
  toml::table prov = provenance(opt.command_line, threads);
  if (!resume) return prov;
  toml::table first = toml::parse(resume->text("run/provenance"));
  if (!first.contains("restarts")) first.insert("restarts", toml::array{});
  // the bitwise claim holds for the same build: say when this one is another
  const toml::table* last =
      first["restarts"].as_array()->empty() ? &first : first["restarts"].as_array()->back().as_table();
  for (const char* k : {"git_commit", "git_dirty", "compiler", "cxx_flags", "build_type"})
    if (last && (*last)[k].value<std::string>() != prov[k].value<std::string>())
      std::fprintf(stderr, "warning: the checkpoint was written by another build (%s '%s', now '%s'): the run "
                   "goes on, but its steps may differ from an uninterrupted run's in the last bits\n", k,
                   (*last)[k].value_or(std::string("?")).c_str(), prov[k].value_or(std::string("?")).c_str());
  prov.insert("from_step", resume->integer("sim/steps"));
  first["restarts"].as_array()->push_back(std::move(prov));
  return first;
}

// A run from its first (or resumed) state to its end: the step loop, which steps the simulation
// and then writes the outputs that are due, the checkpoints and progress lines, and the final
// state and run.json however the loop ends.
class RunLoop {
 public:
  RunLoop(const Scene& scene, const RunOptions& opt, Simulation& sim, const std::filesystem::path& out,
          toml::table prov, int threads, const CheckpointReader* resume)
      : scene_(scene), opt_(opt), sim_(sim), out_(out), prov_(std::move(prov)), threads_(threads),
        outputs_(scene, sim, out, s_, resume), t_end_(scene.run.end_time),
        eps_(1e-12 * std::max(t_end_, 1e-30)), n_(static_cast<double>(sim.particles().size())) {}
  RunSummary run(const CheckpointReader* resume);

 private:
  void start(const CheckpointReader* resume);
  void step_loop();
  bool stop_requested();
  void step();
  void write_checkpoint();
  void print_start() const;
  void print_progress(double now);
  void finish();

  const Scene& scene_;
  const RunOptions& opt_;
  Simulation& sim_;
  std::filesystem::path out_;
  toml::table prov_;
  int threads_;
  RunSummary s_;
  RunOutputs outputs_;
  const double t_end_, eps_;  // [s]
  const double n_;            // particles
  double t_resumed_ = 0.0;    // the simulation's time when this process took over [s]
  double next_snap_ = 0.0, next_energy_ = 0.0;  // [s]
  double wall0_ = 0.0, last_progress_ = 0.0, last_checkpoint_ = 0.0;  // omp_get_wtime() [s]
  // particle-steps and wall seconds: the totals, and those of the runs before a resume
  double particle_steps_ = 0.0, steps_before_ = 0.0, wall_before_ = 0.0;
};

RunSummary RunLoop::run(const CheckpointReader* resume) {
  s_.status = "running";
  write_run_json(out_ / "run.json", scene_, sim_, s_, threads_, prov_);
  t_resumed_ = sim_.time();
  if (!opt_.quiet) print_start();
  watch_stop_signals();
  wall0_ = last_progress_ = last_checkpoint_ = omp_get_wtime();
  try {
    start(resume);
    step_loop();
  } catch (const CheckpointError& e) {  // a checkpoint that could not be written
    s_.status = "failed";
    s_.message = e.what();
    s_.output_failed = true;
  } catch (const StepError& e) {
    s_.status = "failed";
    s_.message = e.what();
  } catch (const std::exception& e) {  // an output (CSV, snapshot, series.h5) failed
    s_.status = "failed";
    s_.message = e.what();
    s_.output_failed = true;
  }
  finish();
  return s_;
}

void RunLoop::print_start() const {
  const double dt0 = sim_.stable_dt();
  // a resumed run: the steps still to go, at the dt of the step it resumes at
  const double left = scene_.run.end_time - sim_.time();
  std::string cells;
  for (int a = 0; a < kDim; ++a) cells += (a ? " x " : "") + std::to_string(scene_.geom.n[a]);
  std::printf("shockmpm %s: %zu particles, grid %s cells of %.4g um, %.6g ns in about %.0f steps "
              "(dt %.3g ns at t = %.6g ns), %d threads, results in %s\n",
              scene_.name.c_str(), sim_.particles().size(), cells.c_str(), scene_.geom.h * 1e6, left * 1e9,
              std::ceil(left / dt0), dt0 * 1e9, sim_.time() * 1e9, threads_, out_.string().c_str());
  std::fflush(stdout);
}

// A new run writes its t = 0 rows and snapshot; a resumed one takes the loop's state from the
// checkpoint (its outputs of that moment are written already).
void RunLoop::start(const CheckpointReader* resume) {
  if (resume) {
    next_snap_ = resume->number("run/next_snap");
    next_energy_ = resume->number("run/next_energy");
    particle_steps_ = steps_before_ = resume->number("run/particle_steps");
    wall_before_ = resume->number("run/wall_seconds");
    s_.diagnostics_seconds = resume->number("run/diagnostics_seconds");
    s_.output_seconds = resume->number("run/output_seconds");
    return;
  }
  outputs_.snapshot();
  next_snap_ = scene_.run.snapshot_interval > 0 ? scene_.run.snapshot_interval : 2 * t_end_ + 1;
  outputs_.write_energy();
  outputs_.write_points();
  outputs_.write_series();
  next_energy_ = scene_.run.diagnostics_interval;
}

// Step, then write what is due: wall.csv every step; energy, gauges, front and series rows every
// diagnostics interval; a snapshot and series.h5 every snapshot interval (the last one is
// finish()'s); a checkpoint every checkpoint interval of wall time.
void RunLoop::step_loop() {
  while (sim_.time() < t_end_ - eps_) {
    if (stop_requested()) break;
    step();
    outputs_.write_wall();
    if (sim_.time() >= next_energy_ - eps_) {
      outputs_.write_energy();
      outputs_.write_points();
      outputs_.write_front();
      outputs_.write_series();
      next_energy_ = sim_.time() + scene_.run.diagnostics_interval;
    }
    if (sim_.time() >= next_snap_ - eps_ && sim_.time() < t_end_ - eps_) {
      outputs_.snapshot();
      outputs_.write_series_h5();
      next_snap_ += scene_.run.snapshot_interval;
    }
    const double now = omp_get_wtime();
    if (scene_.run.checkpoint_interval > 0 && now - last_checkpoint_ >= scene_.run.checkpoint_interval) {
      write_checkpoint();
      last_checkpoint_ = omp_get_wtime();
    }
    if (!opt_.quiet && now - last_progress_ >= scene_.run.progress_interval) print_progress(now);
  }
  if (s_.status == "running") {
    s_.status = "completed";
    s_.message = "reached end_time";
  }
}

// A stop signal (a checkpoint is written) or run.max_steps ends the loop before end_time.
bool RunLoop::stop_requested() {
  if (const int sig = stop_signal()) {
    s_.status = "interrupted";
    s_.message = std::string("interrupted by ") + (sig == SIGTERM ? "SIGTERM" : "SIGINT") + " at step " +
                 std::to_string(sim_.steps());
    write_checkpoint();
    s_.message += "; checkpoint written: continue with `shockmpm resume " + out_.string() + "`";
    return true;
  }
  if (scene_.run.max_steps > 0 && sim_.steps() >= scene_.run.max_steps) {
    s_.status = "completed";
    s_.message = "stopped at run.max_steps = " + std::to_string(scene_.run.max_steps);
    return true;
  }
  return false;
}

void RunLoop::step() {
  // the gradient measures are stored only by the steps after which statistics are written (the
  // step's dt is this min, as in step())
  const double t_next = sim_.time() + std::min(sim_.stable_dt(), t_end_ - sim_.time());
  sim_.store_gradient(t_next >= next_energy_ - eps_ || t_next >= t_end_ - eps_ ||
                      (scene_.run.max_steps > 0 && sim_.steps() + 1 >= scene_.run.max_steps));
  sim_.step(t_end_ - sim_.time());
  particle_steps_ += n_;
}

// The whole state at a step boundary, every output of the step written (engine/checkpoint.hpp);
// the last two are kept.
void RunLoop::write_checkpoint() {
  Timed t(s_.output_seconds);
  CheckpointWriter w(checkpoint_path(out_, sim_.steps()));
  w.put("run/case_name", scene_.name);
  w.put("run/case_text", resolved_case_text(scene_));
  {
    std::ostringstream p;
    p << prov_;
    w.put("run/provenance", p.str());
  }
  sim_.save(w);
  w.put("run/E0", outputs_.E0());
  w.put("run/next_snap", next_snap_);
  w.put("run/next_energy", next_energy_);
  w.put("run/particle_steps", particle_steps_);
  w.put("run/wall_seconds", wall_before_ + omp_get_wtime() - wall0_);
  w.put("run/diagnostics_seconds", s_.diagnostics_seconds);
  w.put("run/output_seconds", s_.output_seconds);
  outputs_.save(w);
  w.commit();
  const auto all = list_checkpoints(out_);
  for (std::size_t k = 0; k + 2 < all.size(); ++k) std::filesystem::remove(all[k]);
}

void RunLoop::print_progress(double now) {
  last_progress_ = now;
  const double frac = sim_.time() / t_end_, el = now - wall0_;  // el: this process's
  const double done = (sim_.time() - t_resumed_) / std::max(t_end_ - t_resumed_, 1e-300);
  std::printf("step %8ld  t = %10.4g ns  dt = %9.3g ns  %5.1f %%  ETA %s  %.3g M particle-steps/s\n", sim_.steps(),
              sim_.time() * 1e9, sim_.last_dt() * 1e9, 100 * frac,
              hms(el * (1 - done) / std::max(done, 1e-12)).c_str(), (particle_steps_ - steps_before_) / el * 1e-6);
  std::fflush(stdout);
}

// The final state, whatever happened, and run.json saying how the run ended.
void RunLoop::finish() {
  s_.steps = sim_.steps();
  s_.end_time = sim_.time();
  // after an output failure each is still tried (the first failure is the run's message)
  for (auto write : {&RunOutputs::write_energy, &RunOutputs::write_points, &RunOutputs::write_series,
                     &RunOutputs::write_series_h5, &RunOutputs::snapshot}) {
    try {
      (outputs_.*write)();
    } catch (const std::exception& e) {
      if (!s_.output_failed) s_.message = (s_.status == "completed" ? "" : s_.message + "; then ") + e.what();
      s_.status = "failed";
      s_.output_failed = true;
    }
  }
  // a completed run needs no checkpoint (its last state is the last snapshot)
  if (s_.status == "completed") {
    std::error_code ec;
    std::filesystem::remove_all(out_ / "checkpoint", ec);
  }
  // wall time of the whole loop, first and last snapshots included (and of the runs before a resume)
  s_.wall_seconds = wall_before_ + omp_get_wtime() - wall0_;
  s_.particle_steps_per_s = s_.wall_seconds > 0 ? particle_steps_ / s_.wall_seconds : 0.0;
  try {
    write_run_json(out_ / "run.json", scene_, sim_, s_, threads_, prov_);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s (run.json could not record how the run ended: %s)\n", e.what(),
                 s_.message.c_str());
    s_.output_failed = true;
    if (s_.status == "completed") s_.status = "failed";
  }
  if (!opt_.quiet) {
    std::printf("%s after %ld steps, t = %.6g ns, %.2f s wall, %.3g M particle-steps/s (%d threads)\n",
                s_.status.c_str(), s_.steps, s_.end_time * 1e9, s_.wall_seconds, s_.particle_steps_per_s * 1e-6,
                threads_);
    std::printf("results in %s\n", out_.string().c_str());
  }
  // why a run stopped early goes to stderr, with --quiet too
  if (s_.status != "completed") std::fprintf(stderr, "%s: %s\n", s_.status.c_str(), s_.message.c_str());
}

// The run; `resume`: the checkpoint it continues from (resume_run), or null for a new run.
RunSummary run_loop(Scene& scene, const RunOptions& opt, const CheckpointReader* resume) {
  if (opt.threads > 0) omp_set_num_threads(opt.threads);
  const int threads = omp_get_max_threads();
  const auto out = output_dir(opt, scene.name);
  toml::table prov = run_provenance(opt, threads, resume);
  Simulation sim(scene.geom, scene.solver, scene.materials, scene.body_material, std::move(scene.particles));
  if (resume) sim.restore(*resume);
  // a run owns its output directory: an earlier run's results there go (--overwrite), now
  // that this one is built and about to write its own
  std::filesystem::create_directories(out);
  const DirLock lock(out);
  clear_output_dir(out, opt.overwrite && !resume);
  if (!resume) {
    std::ofstream c(out / "case_resolved.toml");
    c << resolved_case_text(scene);
    flush_checked(c, out / "case_resolved.toml");
  }
  RunLoop loop(scene, opt, sim, out, std::move(prov), threads, resume);
  return loop.run(resume);
}

}  // namespace

RunSummary run_scene(Scene& scene, const RunOptions& opt) { return run_loop(scene, opt, nullptr); }

RunSummary resume_run(const std::filesystem::path& out, const ResumePoint& point, const RunOptions& opt) {
  Scene scene = build_scene(point.doc, point.name, out);
  RunOptions o = opt;
  o.out_dir = out;
  o.overwrite = false;
  if (!opt.quiet)
    std::printf("resuming %s from %s (step %lld)\n", scene.name.c_str(), point.reader->file().string().c_str(),
                static_cast<long long>(point.reader->integer("sim/steps")));
  return run_loop(scene, o, point.reader.get());
}

}  // namespace SMPM_NS

namespace smpm {

// The entry points of the engine built for kern::kDim axes (engine/driver.hpp).
template <>
RunSummary Engine<kern::kDim>::run(const toml::table& doc, const std::string& name,
                                   const std::filesystem::path& case_dir, const RunOptions& opt) {
  Scene scene = build_scene(doc, name, case_dir);
  return run_scene(scene, opt);
}
template <>
std::string Engine<kern::kDim>::check(const toml::table& doc, const std::string& name,
                                      const std::filesystem::path& case_dir) {
  return describe_scene(build_scene(doc, name, case_dir));
}
template <>
RunSummary Engine<kern::kDim>::resume(const std::filesystem::path& dir, const ResumePoint& point,
                                      const RunOptions& opt) {
  return resume_run(dir, point, opt);
}

}  // namespace smpm
