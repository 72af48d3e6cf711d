#include "engine/run.hpp"

#include <omp.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "engine/case_reader.hpp"
#include "engine/checkpoint.hpp"
#include "engine/diagnostics.hpp"
#include "engine/output.hpp"
#include "engine/provenance.hpp"
#include "engine/thermo.hpp"
#include "engine/timer.hpp"

namespace smpm {

namespace {

// series.csv and series.h5: one entry per column, in file order. The CSV header, each row, the
// HDF5 table's columns and units, and the checkpoint's keys ("series/<name>") all come from it.
struct SeriesColumn {
  const char* name;
  const char* unit;
  double (*value)(double t, std::size_t region, const RegionStats& st);
};
constexpr double kPerUs2 = 1e-12;  // 1/s^2 -> 1/us^2
constexpr SeriesColumn kSeriesColumns[] = {
    {"time_ns", "ns", [](double t, std::size_t, const RegionStats&) { return t * 1e9; }},
    {"region", "index into the regions attribute", [](double, std::size_t r, const RegionStats&) { return double(r); }},
    {"count", "1", [](double, std::size_t, const RegionStats& s) { return double(s.count); }},
    {"P_mean_GPa", "GPa", [](double, std::size_t, const RegionStats& s) { return s.P.mean * 1e-9; }},
    {"P_std_GPa", "GPa", [](double, std::size_t, const RegionStats& s) { return s.P.std * 1e-9; }},
    {"T_mean_K", "K", [](double, std::size_t, const RegionStats& s) { return s.T.mean; }},
    {"T_std_K", "K", [](double, std::size_t, const RegionStats& s) { return s.T.std; }},
    {"rho_mean_gcc", "g/cc", [](double, std::size_t, const RegionStats& s) { return s.rho.mean * 1e-3; }},
    {"rho_std_gcc", "g/cc", [](double, std::size_t, const RegionStats& s) { return s.rho.std * 1e-3; }},
    {"Uy_mean_ms", "m/s", [](double, std::size_t, const RegionStats& s) { return s.Uy.mean; }},
    {"Uy_std_ms", "m/s", [](double, std::size_t, const RegionStats& s) { return s.Uy.std; }},
    {"R2_mean_per_us2", "1/us^2", [](double, std::size_t, const RegionStats& s) { return s.R2 * kPerUs2; }},
    {"D2_mean_per_us2", "1/us^2", [](double, std::size_t, const RegionStats& s) { return s.D2 * kPerUs2; }},
    {"S2_mean_per_us2", "1/us^2", [](double, std::size_t, const RegionStats& s) { return s.S2 * kPerUs2; }},
    {"P_skew", "1", [](double, std::size_t, const RegionStats& s) { return s.P.skew; }},
    {"P_kurt", "1", [](double, std::size_t, const RegionStats& s) { return s.P.kurt; }},
    {"T_skew", "1", [](double, std::size_t, const RegionStats& s) { return s.T.skew; }},
    {"T_kurt", "1", [](double, std::size_t, const RegionStats& s) { return s.T.kurt; }},
    {"rho_skew", "1", [](double, std::size_t, const RegionStats& s) { return s.rho.skew; }},
    {"rho_kurt", "1", [](double, std::size_t, const RegionStats& s) { return s.rho.kurt; }},
    {"Uy_skew", "1", [](double, std::size_t, const RegionStats& s) { return s.Uy.skew; }},
    {"Uy_kurt", "1", [](double, std::size_t, const RegionStats& s) { return s.Uy.kurt; }},
    {"R_mean_per_us", "1/us", [](double, std::size_t, const RegionStats& s) { return s.R * 1e-6; }},
    {"D_mean_per_us", "1/us", [](double, std::size_t, const RegionStats& s) { return s.D * 1e-6; }},
    {"open_porosity", "1", [](double, std::size_t, const RegionStats& s) { return s.open; }},
};
constexpr std::size_t kSeriesRegionColumn = 1;  // written as the region's name in series.csv

// energy.csv: one entry per column, in file order (header and row)
struct EnergyRow {
  double t;
  Simulation::Energy e;
  std::array<double, 2> q;
  Simulation::Removed removed;
  double residual;
};
struct EnergyColumn {
  const char* name;
  double (*value)(const EnergyRow& r);
};
constexpr EnergyColumn kEnergyColumns[] = {
    {"time_ns", [](const EnergyRow& r) { return r.t * 1e9; }},
    {"kinetic_J_per_m", [](const EnergyRow& r) { return r.e.kinetic; }},
    {"internal_J_per_m", [](const EnergyRow& r) { return r.e.internal; }},
    {"total_J_per_m", [](const EnergyRow& r) { return r.e.total(); }},
    {"momentum_x_kg_m_s_per_m", [](const EnergyRow& r) { return r.q[0]; }},
    {"momentum_y_kg_m_s_per_m", [](const EnergyRow& r) { return r.q[1]; }},
    {"wall_removed_J_per_m", [](const EnergyRow& r) { return r.removed.wall; }},
    {"contact_removed_J_per_m", [](const EnergyRow& r) { return r.removed.contact; }},
    {"residual_J_per_m", [](const EnergyRow& r) { return r.residual; }},
};

// "a,b,c\n" from a column list's names
template <class Columns>
std::string csv_header(const Columns& cols) {
  std::string h;
  for (const auto& c : cols) {
    if (!h.empty()) h += ',';
    h += c.name;
  }
  h += '\n';
  return h;
}

// The signal that asked the run to stop (SIGINT or SIGTERM; 0: none): the run stops after the
// current step and writes its last state, as for a batch scheduler's SIGTERM.
std::atomic<int> g_stop_signal{0};
extern "C" void on_stop_signal(int sig) { g_stop_signal = sig; }

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
  auto vec = [&](const char* name, const char* units, const std::vector<double>& a, const std::vector<double>& b) {
    SnapshotField s{name, units, 2, std::vector<double>(2 * n)};
    for (std::size_t i = 0; i < n; ++i) {
      s.data[2 * i] = a[i];
      s.data[2 * i + 1] = b[i];
    }
    f.push_back(std::move(s));
  };
  auto scal = [&](const char* name, const char* units, auto get) {
    SnapshotField s{name, units, 1, std::vector<double>(n)};
    for (std::size_t i = 0; i < n; ++i) s.data[i] = get(i);
    f.push_back(std::move(s));
  };
  vec("position", "m", P.x, P.y);
  vec("velocity", "m/s", P.vx, P.vy);
  scal("pressure", "Pa", [&](std::size_t i) { return P.p[i]; });
  scal("density", "kg/m^3", [&](std::size_t i) { return P.m[i] / P.V[i]; });
  scal("stress_xx", "Pa", [&](std::size_t i) { return P.sxx[i] - P.p[i]; });
  scal("stress_yy", "Pa", [&](std::size_t i) { return P.syy[i] - P.p[i]; });
  scal("stress_xy", "Pa", [&](std::size_t i) { return P.sxy[i]; });
  scal("stress_zz", "Pa", [&](std::size_t i) { return -(P.sxx[i] + P.syy[i]) - P.p[i]; });
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
  for (std::size_t k = 0; k < scene.bodies.size(); ++k) {
    const auto& b = scene.bodies[k];
    toml::table bt{{"name", b.name}, {"material", b.material}, {"particles", static_cast<int64_t>(b.particles)},
                   {"area_m2", b.area}, {"velocity_m_s", toml::array{b.vx0, b.vy0}}, {"porosity", b.porosity},
                   {"voids", static_cast<int64_t>(b.voids)}};
    const Material& m = scene.materials[scene.body_material[k]];
    const double up = std::hypot(b.vx0, b.vy0);
    if (m.eos == EosKind::MieGruneisen && up > 0.0) {
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
    }
    bodies.push_back(std::move(bt));
  }
  t.insert("bodies", std::move(bodies));
  toml::array regions;  // the regions of series.csv, in its order
  for (const auto& r : scene.regions)
    regions.push_back(toml::table{{"name", r.name}, {"y_range_um", toml::array{r.y0 * 1e6, r.y1 * 1e6}},
                                  {"body", static_cast<int64_t>(r.body)}});
  t.insert("regions", std::move(regions));
  t.insert("case_resolved", scene.resolved);
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

// `check`'s lines on the followed points: each gauge (only their count beyond 20), each free surface.
void describe_points(std::ostream& o, const Scene& sc) {
  const Particles& P = sc.particles;
  if (!sc.gauges.empty()) o << "gauges          " << sc.gauges.size() << " (gauges.csv)\n";
  if (sc.gauges.size() <= 20)
    for (const auto& g : sc.gauges)
      o << "  gauge " << std::left << std::setw(10) << g.name << std::right << " point " << g.id << " of body "
        << sc.bodies[P.body[g.id]].name << " at (" << P.x[g.id] * 1e6 << ", " << P.y[g.id] * 1e6 << ") um\n";
  for (const auto& f : sc.free_surfaces)
    o << "free surface    body " << f.body_name << ": the " << f.ids.size() << " points of its top row at y = "
      << P.y[f.ids.front()] * 1e6 << " um (freesurface.csv)\n";
}

}  // namespace

std::string describe_scene(const Scene& sc) {
  std::ostringstream o;
  const auto& g = sc.geom;
  o << "case            " << sc.name << "\n";
  o << "grid            " << g.nx << " x " << g.ny << " cells of " << g.h * 1e6 << " um, x in [" << g.x0 * 1e6
    << ", " << (g.x0 + g.length_x()) * 1e6 << "] um, y in [" << g.y0 * 1e6 << ", " << (g.y0 + g.length_y()) * 1e6
    << "] um" << (g.periodic_x ? ", periodic in x" : "") << "\n";
  o << "particles       " << sc.particles.size() << "\n";
  for (const auto& b : sc.bodies)
    o << "  body " << std::left << std::setw(10) << b.name << std::right << " material " << b.material << ", "
      << b.particles << " particles, area " << b.area * 1e12 << " um^2"
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
    const double up = std::hypot(b.vx0, b.vy0);
    if (m.eos != EosKind::MieGruneisen || up <= 0.0) continue;
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

std::filesystem::path output_dir(const RunOptions& opt, const std::string& case_name) {
  return opt.out_dir.empty() ? std::filesystem::path("out") / case_name : opt.out_dir;
}

void check_output_dir(const std::filesystem::path& out, bool overwrite) {
  std::error_code ec;
  if (std::filesystem::exists(out, ec) && !std::filesystem::is_directory(out, ec))
    throw CaseError("output directory '" + out.string() + "' is a file; choose another --out");
  if (!overwrite && std::filesystem::exists(out / "run.json", ec))
    throw CaseError("output directory '" + out.string() + "' holds an earlier run (run.json); pass --overwrite to "
                    "replace its results, or choose another --out");
}

namespace {

// A CSV file of the run: a new run writes its header; a resumed one cuts the file back to its
// length at the checkpoint (rows written after it go) and appends.
void open_csv(std::ofstream& o, const std::filesystem::path& file, const char* header,
              const CheckpointReader* resume) {
  if (!resume) {
    o.open(file);
    o << header;
    return;
  }
  const auto key = "csv/" + file.filename().string();
  const auto length = static_cast<std::uintmax_t>(resume->integer(key));
  std::error_code ec;
  if (!std::filesystem::exists(file, ec) || std::filesystem::file_size(file, ec) < length)
    throw CaseError("cannot resume: " + file.string() + " is missing or shorter than at the checkpoint (" +
                    std::to_string(length) + " bytes)");
  std::filesystem::resize_file(file, length, ec);
  if (ec) throw OutputError("cannot cut " + file.string() + " back to its checkpoint length: " + ec.message());
  o.open(file, std::ios::app);
}

// The run loop; `resume`: the checkpoint it continues from (resume_run), or null for a new run.
RunSummary run_loop(Scene& scene, const RunOptions& opt, const CheckpointReader* resume) {
  if (opt.threads > 0) omp_set_num_threads(opt.threads);
  const int threads = omp_get_max_threads();
  const auto out = output_dir(opt, scene.name);
  // provenance: the first run's, and one entry per resume in "restarts"
  toml::table prov = provenance(opt.command_line, threads);
  if (resume) {
    toml::table first = toml::parse(resume->text("run/provenance"));
    if (!first.contains("restarts")) first.insert("restarts", toml::array{});
    // the bitwise claim holds for the same build: say when this one is another
    const toml::table* last = first["restarts"].as_array()->empty()
                                  ? &first
                                  : first["restarts"].as_array()->back().as_table();
    for (const char* k : {"git_commit", "git_dirty", "compiler", "cxx_flags", "build_type"})
      if (last && (*last)[k].value<std::string>() != prov[k].value<std::string>())
        std::fprintf(stderr, "warning: the checkpoint was written by another build (%s '%s', now '%s'): the run "
                     "goes on, but its steps may differ from an uninterrupted run's in the last bits\n", k,
                     (*last)[k].value_or(std::string("?")).c_str(), prov[k].value_or(std::string("?")).c_str());
    prov.insert("from_step", resume->integer("sim/steps"));
    first["restarts"].as_array()->push_back(std::move(prov));
    prov = std::move(first);
  }
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
  SnapshotWriter snaps(out / "fields");
  if (resume) snaps.adopt(resume->text("run/snapshots"));
  RunSummary s;
  // the compression front runs through the target: the body named "target", else body 0
  const std::size_t target = scene.target;
  // voids.csv: the void area left open in the target (and its share of each region's band),
  // at every snapshot; pixels a quarter of the point spacing (open_area)
  std::ofstream voids;
  if (scene.bodies[target].voids > 0) {
    open_csv(voids, out / "voids.csv", "time_ns,region,open_area_um2,open_fraction\n", resume);
    voids << std::setprecision(8);
  }
  auto write_voids = [&] {
    if (!voids.is_open()) return;
    Timed t(s.diagnostics_seconds);
    const auto& g = scene.geom;
    const double pixel = std::sqrt(scene.bodies[target].area / double(scene.bodies[target].particles)) / 3;  // [m]
    const double period = g.periodic_x ? g.length_x() : 0.0, x1 = g.x0 + g.length_x();
    const auto b = static_cast<std::uint8_t>(target);
    std::vector<Window> win{{g.x0, x1, -1e300, 1e300}};
    for (const auto& r : scene.regions) win.push_back({g.x0, x1, r.y0, r.y1});
    const auto a = open_area(sim.particles(), b, win, pixel, 0.75, period, g.x0);
    voids << sim.time() * 1e9 << ",target," << a[0] * 1e12 << ",nan\n";
    for (std::size_t k = 0; k < scene.regions.size(); ++k) {
      const auto& r = scene.regions[k];
      if (r.body != b) continue;
      voids << sim.time() * 1e9 << ',' << r.name << ',' << a[k + 1] * 1e12 << ',' << a[k + 1] / ((r.y1 - r.y0) * g.length_x()) << '\n';
    }
    flush_checked(voids, out / "voids.csv");
  };
  auto snapshot = [&] {
    {
      Timed t(s.output_seconds);
      snaps.write(snapshot_fields(sim), sim.particles().size(), sim.time(), sim.steps());
    }
    write_voids();
  };
  // regional statistics: series.csv every diagnostics interval, series.h5 with the same table
  std::ofstream series;
  open_csv(series, out / "series.csv", csv_header(kSeriesColumns).c_str(), resume);
  series << std::setprecision(8);
  std::vector<std::string> columns, units;
  for (const auto& c : kSeriesColumns) {
    columns.emplace_back(c.name);
    units.emplace_back(c.unit);
  }
  std::vector<std::vector<double>> table(columns.size());
  if (resume)
    for (std::size_t c = 0; c < columns.size(); ++c) resume->get("series/" + columns[c], table[c]);
  std::string region_names;
  for (const auto& r : scene.regions) region_names += (region_names.empty() ? "" : ",") + r.name;
  auto write_series = [&] {
    Timed t(s.diagnostics_seconds);
    const auto stats = region_stats(sim.particles(), scene.regions, sim.thermo(), sim.materials(), sim.body_material(),
                                    sim.gradient_current());
    for (std::size_t r = 0; r < stats.size(); ++r) {
      for (std::size_t c = 0; c < columns.size(); ++c) {
        const double v = kSeriesColumns[c].value(sim.time(), r, stats[r]);
        table[c].push_back(v);
        if (c == kSeriesRegionColumn) series << ',' << scene.regions[r].name;
        else series << (c ? "," : "") << v;
      }
      series << '\n';
    }
    flush_checked(series, out / "series.csv");
  };
  auto write_series_h5 = [&] {
    Timed t(s.output_seconds);
    std::string unit_list;
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c) unit_list += ", ";
      unit_list += columns[c];
      unit_list += ' ';
      unit_list += units[c];
    }
    write_table_h5(out / "series.h5", "series", columns, table,
                   {{"regions", region_names}, {"region_column", units[kSeriesRegionColumn]}, {"units", unit_list}});
  };
  const double vy0 = scene.bodies[target].vy0;
  std::ofstream front;
  if (vy0 != 0.0) {
    open_csv(front, out / "front.csv", "time_ns,front_y_um\n", resume);
    front << std::setprecision(10);
  }
  auto write_front = [&] {
    if (vy0 == 0.0) return;
    Timed t(s.diagnostics_seconds);
    const auto& g = scene.geom;
    const double y = front_position(sim.particles(), static_cast<std::uint8_t>(target), vy0, g.y0, g.h, g.ny, vy0 < 0);
    if (std::isfinite(y)) {
      front << sim.time() * 1e9 << ',' << y * 1e6 << '\n';
      flush_checked(front, out / "front.csv");
    }
  };
  std::ofstream energy;
  open_csv(energy, out / "energy.csv", csv_header(kEnergyColumns).c_str(), resume);
  const double E0 = resume ? resume->number("run/E0") : sim.energy().total();
  // gauges.csv and freesurface.csv: the points followed from t = 0 (engine/gauges.hpp), with
  // energy.csv's rows
  PointRecorder points(scene.gauges, scene.free_surfaces, sim.particles().size());
  if (resume) points.restore(*resume);
  std::ofstream gauges, surface;
  if (points.has_gauges()) {
    open_csv(gauges, out / "gauges.csv", kGaugeHeader, resume);
    gauges << std::setprecision(10);
  }
  if (points.has_surfaces()) {
    open_csv(surface, out / "freesurface.csv", kFreeSurfaceHeader, resume);
    surface << std::setprecision(10);
  }
  auto write_points = [&] {
    Timed t(s.diagnostics_seconds);
    if (gauges.is_open()) {
      points.gauge_rows(gauges, sim);
      flush_checked(gauges, out / "gauges.csv");
    }
    if (surface.is_open()) {
      points.surface_rows(surface, sim);
      flush_checked(surface, out / "freesurface.csv");
    }
  };
  energy << std::setprecision(12);
  const bool has_wall = scene.solver.walls.lo[1] != kern::Wall::None;
  std::ofstream wall;
  if (has_wall) {
    open_csv(wall, out / "wall.csv", "time_ns,wall_stress_GPa\n", resume);
    wall << std::setprecision(10);
  }
  auto write_energy = [&] {
    Timed t(s.diagnostics_seconds);
    EnergyRow row{sim.time(), sim.energy(), sim.momentum(), sim.removed(), 0.0};
    // residual: the scheme's own energy error, what is neither in the total nor removed as loss
    const double lost = sim.removed_is_heat() ? 0.0 : row.removed.wall + row.removed.contact;
    row.residual = row.e.total() + lost - E0;
    for (std::size_t c = 0; c < std::size(kEnergyColumns); ++c) energy << (c ? "," : "") << kEnergyColumns[c].value(row);
    energy << '\n';
    flush_checked(energy, out / "energy.csv");
  };
  s.status = "running";
  write_run_json(out / "run.json", scene, sim, s, threads, prov);
  const double t_resumed = sim.time();
  if (!opt.quiet) {
    const double dt0 = sim.stable_dt();
    // a resumed run: the steps still to go, at the dt of the step it resumes at
    const double left = scene.run.end_time - sim.time();
    std::printf("shockmpm %s: %zu particles, grid %d x %d cells of %.4g um, %.6g ns in about %.0f steps "
                "(dt %.3g ns at t = %.6g ns), %d threads, results in %s\n",
                scene.name.c_str(), sim.particles().size(), scene.geom.nx, scene.geom.ny, scene.geom.h * 1e6,
                left * 1e9, std::ceil(left / dt0), dt0 * 1e9, sim.time() * 1e9, threads, out.string().c_str());
    std::fflush(stdout);
  }
  g_stop_signal = 0;
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);

  const double t_end = scene.run.end_time;
  const double eps = 1e-12 * std::max(t_end, 1e-30);
  double next_snap = 0.0, next_energy = 0.0;
  const double wall0 = omp_get_wtime();
  double last_progress = wall0, last_checkpoint = wall0;
  // particle-steps and wall seconds: the totals, and those of the runs before a resume
  double particle_steps = 0.0, steps_before = 0.0, wall_before = 0.0;
  const double n = static_cast<double>(sim.particles().size());
  const std::pair<const char*, std::ofstream*> csvs[] = {
      {"energy.csv", &energy}, {"series.csv", &series}, {"front.csv", &front}, {"wall.csv", &wall}, {"voids.csv", &voids},
      {"gauges.csv", &gauges}, {"freesurface.csv", &surface}};
  // the whole state at a step boundary, every output of the step written (engine/checkpoint.hpp);
  // the last two are kept
  auto write_checkpoint = [&] {
    Timed t(s.output_seconds);
    CheckpointWriter w(checkpoint_path(out, sim.steps()));
    w.put("run/case_name", scene.name);
    w.put("run/case_text", resolved_case_text(scene));
    {
      std::ostringstream p;
      p << prov;
      w.put("run/provenance", p.str());
    }
    sim.save(w);
    w.put("run/E0", E0);
    w.put("run/next_snap", next_snap);
    w.put("run/next_energy", next_energy);
    w.put("run/particle_steps", particle_steps);
    w.put("run/wall_seconds", wall_before + omp_get_wtime() - wall0);
    w.put("run/diagnostics_seconds", s.diagnostics_seconds);
    w.put("run/output_seconds", s.output_seconds);
    for (std::size_t c = 0; c < columns.size(); ++c) w.put("series/" + columns[c], table[c]);
    w.put("run/snapshots", snaps.index_text());
    if (points.has_gauges() || points.has_surfaces()) points.save(w);
    for (const auto& [name, o] : csvs)
      if (o->is_open()) w.put(std::string("csv/") + name, static_cast<std::int64_t>(o->tellp()));
    w.commit();
    const auto all = list_checkpoints(out);
    for (std::size_t k = 0; k + 2 < all.size(); ++k) std::filesystem::remove(all[k]);
  };
  try {
    if (resume) {
      next_snap = resume->number("run/next_snap");
      next_energy = resume->number("run/next_energy");
      particle_steps = steps_before = resume->number("run/particle_steps");
      wall_before = resume->number("run/wall_seconds");
      s.diagnostics_seconds = resume->number("run/diagnostics_seconds");
      s.output_seconds = resume->number("run/output_seconds");
    } else {
      snapshot();
      next_snap = scene.run.snapshot_interval > 0 ? scene.run.snapshot_interval : 2 * t_end + 1;
      write_energy();
      write_points();
      write_series();
      next_energy = scene.run.diagnostics_interval;
    }
    while (sim.time() < t_end - eps) {
      if (const int sig = g_stop_signal) {
        s.status = "interrupted";
        s.message = std::string("interrupted by ") + (sig == SIGTERM ? "SIGTERM" : "SIGINT") + " at step " +
                    std::to_string(sim.steps());
        write_checkpoint();
        s.message += "; checkpoint written: continue with `shockmpm resume " + out.string() + "`";
        break;
      }
      if (scene.run.max_steps > 0 && sim.steps() >= scene.run.max_steps) {
        s.status = "completed";
        s.message = "stopped at run.max_steps = " + std::to_string(scene.run.max_steps);
        break;
      }
      // L is stored on the particles only by the steps after which statistics are written (the
      // step's dt is this min, as in step())
      const double t_next = sim.time() + std::min(sim.stable_dt(), t_end - sim.time());
      sim.store_gradient(t_next >= next_energy - eps || t_next >= t_end - eps ||
                         (scene.run.max_steps > 0 && sim.steps() + 1 >= scene.run.max_steps));
      sim.step(t_end - sim.time());
      particle_steps += n;
      if (has_wall) {
        Timed t(s.diagnostics_seconds);
        wall << sim.time() * 1e9 << ',' << sim.wall_forces().bottom / scene.geom.length_x() * 1e-9 << '\n';
        flush_checked(wall, out / "wall.csv");  // every CSV row whole: a killed run leaves no cut row
      }
      if (sim.time() >= next_energy - eps) {
        write_energy();
        write_points();
        write_front();
        write_series();
        next_energy = sim.time() + scene.run.diagnostics_interval;
      }
      if (sim.time() >= next_snap - eps && sim.time() < t_end - eps) {
        snapshot();
        write_series_h5();
        next_snap += scene.run.snapshot_interval;
      }
      const double now = omp_get_wtime();
      if (scene.run.checkpoint_interval > 0 && now - last_checkpoint >= scene.run.checkpoint_interval) {
        write_checkpoint();
        last_checkpoint = omp_get_wtime();
      }
      if (!opt.quiet && now - last_progress >= scene.run.progress_interval) {
        last_progress = now;
        const double frac = sim.time() / t_end, el = now - wall0;  // el: this process's
        const double done = (sim.time() - t_resumed) / std::max(t_end - t_resumed, 1e-300);
        std::printf("step %8ld  t = %10.4g ns  dt = %9.3g ns  %5.1f %%  ETA %s  %.3g M particle-steps/s\n",
                    sim.steps(), sim.time() * 1e9, sim.last_dt() * 1e9, 100 * frac,
                    hms(el * (1 - done) / std::max(done, 1e-12)).c_str(), (particle_steps - steps_before) / el * 1e-6);
        std::fflush(stdout);
      }
    }
    if (s.status == "running") {
      s.status = "completed";
      s.message = "reached end_time";
    }
  } catch (const CheckpointError& e) {  // a checkpoint that could not be written
    s.status = "failed";
    s.message = e.what();
    s.output_failed = true;
  } catch (const StepError& e) {
    s.status = "failed";
    s.message = e.what();
  } catch (const std::exception& e) {  // an output (CSV, snapshot, series.h5) failed
    s.status = "failed";
    s.message = e.what();
    s.output_failed = true;
  }
  s.steps = sim.steps();
  s.end_time = sim.time();
  // final state, whatever happened; after an output failure each is still tried (the first
  // failure is the run's message)
  for (const auto& write : {std::function<void()>(write_energy), std::function<void()>(write_points),
                            std::function<void()>(write_series),
                            std::function<void()>(write_series_h5), std::function<void()>(snapshot)}) {
    try {
      write();
    } catch (const std::exception& e) {
      if (!s.output_failed) s.message = (s.status == "completed" ? "" : s.message + "; then ") + e.what();
      s.status = "failed";
      s.output_failed = true;
    }
  }
  // a completed run needs no checkpoint (its last state is the last snapshot)
  if (s.status == "completed") {
    std::error_code ec;
    std::filesystem::remove_all(out / "checkpoint", ec);
  }
  // wall time of the whole loop, first and last snapshots included (and of the runs before a resume)
  s.wall_seconds = wall_before + omp_get_wtime() - wall0;
  s.particle_steps_per_s = s.wall_seconds > 0 ? particle_steps / s.wall_seconds : 0.0;
  try {
    write_run_json(out / "run.json", scene, sim, s, threads, prov);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s (run.json could not record how the run ended: %s)\n", e.what(),
                 s.message.c_str());
    s.output_failed = true;
    if (s.status == "completed") s.status = "failed";
  }
  if (!opt.quiet) {
    std::printf("%s after %ld steps, t = %.6g ns, %.2f s wall, %.3g M particle-steps/s (%d threads)\n",
                s.status.c_str(), s.steps, s.end_time * 1e9, s.wall_seconds, s.particle_steps_per_s * 1e-6, threads);
    std::printf("results in %s\n", out.string().c_str());
  }
  // why a run stopped early goes to stderr, with --quiet too
  if (s.status != "completed") std::fprintf(stderr, "%s: %s\n", s.status.c_str(), s.message.c_str());
  return s;
}

}  // namespace

RunSummary run_scene(Scene& scene, const RunOptions& opt) { return run_loop(scene, opt, nullptr); }

RunSummary resume_run(const std::filesystem::path& out, const RunOptions& opt) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(out, ec)) throw CaseError("cannot resume: '" + out.string() + "' is not a directory");
  if (fs::exists(out / "run.json", ec)) {
    std::ifstream j(out / "run.json");
    std::stringstream text;
    text << j.rdbuf();
    std::string t = text.str();
    t.erase(std::remove_if(t.begin(), t.end(), [](unsigned char c) { return std::isspace(c); }), t.end());
    if (t.find("\"status\":\"completed\"") != std::string::npos)
      throw CaseError("cannot resume: the run in '" + out.string() + "' completed (run.json); nothing to continue");
  }
  const auto all = list_checkpoints(out);
  if (all.empty())
    throw CaseError("cannot resume: '" + out.string() + "' holds no checkpoint (checkpoint/ckpt_*.bin); a run writes "
                    "one every run.checkpoint_interval_s of wall time and when SIGINT or SIGTERM stops it");
  // the newest whole checkpoint (a damaged one is named and the one before it tried)
  std::unique_ptr<CheckpointReader> r;
  for (auto it = all.rbegin(); it != all.rend() && !r; ++it) {
    try {
      r = std::make_unique<CheckpointReader>(*it);
    } catch (const CheckpointError& e) {
      std::fprintf(stderr, "warning: %s; trying the one before\n", e.what());
    }
  }
  if (!r) throw CaseError("cannot resume: no checkpoint in '" + (out / "checkpoint").string() + "' is whole");
  toml::table doc;
  try {
    doc = toml::parse(r->text("run/case_text"));
  } catch (const toml::parse_error& e) {
    throw CheckpointError("checkpoint " + r->file().string() + ": its case does not parse: " +
                          std::string(e.description()));
  }
  Scene scene = build_scene(doc, r->text("run/case_name"), out);
  RunOptions o = opt;
  o.out_dir = out;
  o.overwrite = false;
  if (!opt.quiet)
    std::printf("resuming %s from %s (step %lld)\n", scene.name.c_str(), r->file().string().c_str(),
                static_cast<long long>(r->integer("sim/steps")));
  return run_loop(scene, o, r.get());
}

}  // namespace smpm
