#include "kernels/dimension.hpp"
#include "engine/scene.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <unordered_map>

#include "engine/case_reader.hpp"
#include "engine/porous.hpp"
#include "kernels/tensor.hpp"
#include "kernels/transfer.hpp"

namespace SMPM_NS {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kDim = kern::kDim;

kern::Wall wall_kind(const std::string& s) {
  if (s == "slip") return kern::Wall::Slip;
  if (s == "noslip") return kern::Wall::NoSlip;
  return kern::Wall::None;
}

// Reads a material; with `check_only` set, only those keys must all be read (a library entry
// may carry keys the case's model choice does not use).
Material read_material(CaseReader r, const std::string& name, const toml::table* check_only = nullptr) {
  Material m;
  m.name = name;
  const std::string eos = r.choice("eos", model_names<EosModel>(), "linear");
  const std::string strength = r.choice("strength", model_names<StrengthModel>(), "elastic");
  m.eos = model_named<EosModel>(eos);
  m.strength = model_named<StrengthModel>(strength);
  m.rho0 = r.quantity("density", kDensity, 1e-6, 1e6);
  m.E = r.quantity("youngs_modulus", kStress, 1e-12, 1e15);
  m.nu = r.number("poisson_ratio", 0.0, 0.499);
  std::visit([&r](auto& model) { model.read(r); }, m.eos);
  std::visit([&r](auto& model) { model.read(r); }, m.strength);
  m.spall_strength = r.quantity("spall_strength", kStress, 0.0, 1e15, 0.0);
  m.cv = r.quantity("specific_heat", kSpecificHeat, 0.0, 1e8, 0.0);
  m.conductivity = r.quantity("thermal_conductivity", kConductivity, 0.0, 1e6, 0.0);
  m.T0 = r.quantity("initial_temperature", kTemperature, 0.0, 1e6, 300.0);
  m.heat_fraction = r.number("heat_fraction", 0.0, 1.0, 1.0);
  m.temperature = r.choice("temperature", {"isentrope", "simple"}, "isentrope") == "simple"
                      ? TemperatureKind::Simple
                      : TemperatureKind::Isentrope;
  if (!check_only) {
    r.finish();
  } else {
    for (const auto& [k, v] : *check_only) {
      const std::string key(k.str());
      if (key != "base" && !r.used(key))
        throw CaseError("case key '" + r.path() + "." + key + "' is not used by this material (eos '" +
                        eos + "', strength '" + strength + "'); check the spelling or remove it");
    }
  }
  return m;
}

// The materials library: `materials_file` (relative to the case file), by default the nearest
// materials.toml in the case file's directory or above it.
std::filesystem::path find_materials_file(CaseReader& top, const std::filesystem::path& case_path) {
  // a bare file name ("shockmpm check quickstart.toml") has an empty directory: the current one
  const std::filesystem::path case_dir = case_path.empty() ? std::filesystem::path(".") : case_path;
  if (top.has("materials_file")) {
    const auto p = case_dir / top.string("materials_file");
    if (!std::filesystem::exists(p))
      throw CaseError("case key 'materials_file': '" + p.string() + "' does not exist");
    return p;
  }
  for (auto d = std::filesystem::absolute(case_dir); !d.empty(); d = d.parent_path()) {
    if (std::filesystem::exists(d / "materials.toml")) return d / "materials.toml";
    if (d == d.parent_path()) break;
  }
  throw CaseError("a material names a 'base' but no materials.toml was found next to or above the case file; "
                  "set the top-level key 'materials_file'");
}

// A per-axis case key: the pattern with '?' replaced by the axis's name, axis_key(1, "?_range") =
// "y_range", axis_key(2, "periodic_?") = "periodic_z".
std::string axis_key(int a, const std::string& pattern) {
  std::string k = pattern;
  k.replace(k.find('?'), 1, kern::kAxisNames[a]);
  return k;
}

// A 2D case names no key of the third axis (its patterns as for axis_key): each is refused by
// name, not left as an unknown key.
void refuse_other_axes(CaseReader& r, std::initializer_list<const char*> patterns) {
  for (int a = kDim; a < 3; ++a)
    for (const char* p : patterns)
      if (r.has(axis_key(a, p)))
        throw CaseError("case key '" + (r.path().empty() ? "" : r.path() + ".") + axis_key(a, p) +
                        "' belongs to axis " + kern::kAxisNames[a] + ", which a case with grid.dimension = " +
                        std::to_string(kDim) + " does not have; set grid.dimension = 3 for a 3D case");
}

// A case key holding one value per axis (e.g. velocity_m_s = [0.0, -800.0] at D = 2, three
// values at D = 3) [SI]; `def`: its default (none: the key is required).
Vector read_vector(CaseReader& r, const std::string& key, const Quantity& q,
                   const std::optional<Vector>& def = std::nullopt) {
  const std::vector<double> a = def ? r.numbers(key, q, kDim, std::vector<double>(def->c, def->c + kDim))
                                    : r.numbers(key, q, kDim);
  Vector v;
  for (int d = 0; d < kDim; ++d) v[d] = a[d];
  return v;
}

// The values of v joined by ", ", each as `format` writes it: "1.5, 2".
template <class Format>
std::string join_axes(const Vector& v, Format format) {
  std::string s;
  for (int a = 0; a < kDim; ++a) s += (a ? ", " : "") + format(v[a]);
  return s;
}

// Whether p lies in the half-open box [lo, hi).
bool in_half_open(const Box& b, const Vector& p) {
  for (int a = 0; a < kDim; ++a)
    if (!(p[a] >= b.lo[a] && p[a] < b.hi[a])) return false;
  return true;
}

// Lattice of sub-cell centres: the point of lattice index i at lo + (i + 0.5) d per axis (lo the
// grid's origin, d = h / ppc), over the sites near `box`; a site holds a point where inside(its
// centre) is true. The points move at velocity v.
template <class Inside>
Particles fill_lattice(const kern::GridGeom& g, int ppc, const Box& box, double rho0, const Vector& v,
                       std::uint8_t body, Inside inside) {
  Particles P;
  const double d = g.h / ppc;
  Index first{}, last{};  // lattice indices per axis
  double vol = d, mass = rho0 * d;  // a point's volume d^D and mass
  for (int a = 0; a < kDim; ++a) {
    const double o = g.lo[a];
    first[a] = std::max(0L, static_cast<long>(std::floor((box.lo[a] - o) / d - 0.5)));
    last[a] = std::min(static_cast<long>(g.n[a]) * ppc - 1, static_cast<long>(std::ceil((box.hi[a] - o) / d)));
    if (a) {
      vol *= d;
      mass *= d;
    }
  }
  std::size_t n = 0;
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) P.resize(n);
    std::size_t k = 0;
    for_each_index(first, last, [&](const Index& i) {
      Vector c;  // the site's centre [m]
      for (int a = 0; a < kDim; ++a) c[a] = g.lo[a] + (i[a] + 0.5) * d;
      if (!inside(c)) return;
      if (pass == 1) {
        for (int a = 0; a < kDim; ++a) {
          P.x[a][k] = c[a];
          P.v[a][k] = v[a];
        }
        P.V[k] = vol;
        P.m[k] = mass;
        P.body[k] = body;
      }
      ++k;
    });
    n = k;
  }
  return P;
}

// ---- Body shapes ----

// A body's shape as read from its keys [m]: a rectangle's box, a disk's centre and radius.
struct ShapeParams {
  Box box;
  Vector centre{};
  double radius = 0.0;
};

// One value of [[bodies]] `shape`: the keys it reads, which lattice points it holds, its
// bounding box, and its outline (closed) rebuilt from the bounding box alone, which is all a
// mirror copy has: gauges are placed in the outline.
struct BodyShape {
  const char* name;
  ShapeParams (*read)(CaseReader& r);
  std::vector<std::string> size_keys;  // the keys that set its size, named when it needs too much memory
  bool (*inside)(const ShapeParams& s, const Vector& p);
  Box (*bbox)(const ShapeParams& s);
  bool (*outline)(const Box& box, const Vector& p);
};

ShapeParams read_rectangle(CaseReader& r) {
  ShapeParams s;
  for (int a = 0; a < kDim; ++a) std::tie(s.box.lo[a], s.box.hi[a]) = r.pair(axis_key(a, "?_range"), kLength, true);
  return s;
}
bool rectangle_inside(const ShapeParams& s, const Vector& p) { return in_half_open(s.box, p); }
Box rectangle_bbox(const ShapeParams& s) { return s.box; }
bool rectangle_outline(const Box& b, const Vector& p) { return in_box(b, p); }

// The keys of a rectangle's size: x_range, y_range, ...
std::vector<std::string> range_keys() {
  std::vector<std::string> keys;
  for (int a = 0; a < kDim; ++a) keys.push_back(axis_key(a, "?_range"));
  return keys;
}

ShapeParams read_disk(CaseReader& r) {
  ShapeParams s;
  s.centre = read_vector(r, "center", kLength);
  s.radius = r.quantity("radius", kLength, 0.0, kInf);
  return s;
}
bool disk_inside(const ShapeParams& s, const Vector& p) {
  double q = 0.0;  // squared distance from the centre [m^2]
  for (int a = 0; a < kDim; ++a) q += (p[a] - s.centre[a]) * (p[a] - s.centre[a]);
  return q < s.radius * s.radius;
}
Box disk_bbox(const ShapeParams& s) {
  Box b;
  for (int a = 0; a < kDim; ++a) {
    b.lo[a] = s.centre[a] - s.radius;
    b.hi[a] = s.centre[a] + s.radius;
  }
  return b;
}
// The disk inscribed in the box: radius half its extent along axis 0, centred on the box.
bool disk_outline(const Box& b, const Vector& p) {
  const double r = 0.5 * (b.hi[0] - b.lo[0]);
  double e[kDim];  // p - centre [m]
  for (int a = 0; a < kDim; ++a) e[a] = p[a] - (a == 0 ? b.lo[0] + r : 0.5 * (b.lo[a] + b.hi[a]));
  return kern::norm2(e) <= r * r;
}

const BodyShape kShapes[] = {
    {kDim == 2 ? "rectangle" : "box", read_rectangle, range_keys(), rectangle_inside, rectangle_bbox,
     rectangle_outline},
    {kDim == 2 ? "disk" : "sphere", read_disk, {"radius"}, disk_inside, disk_bbox, disk_outline},
};

std::vector<std::string> shape_names() {
  std::vector<std::string> names;
  for (const BodyShape& s : kShapes) names.emplace_back(s.name);
  return names;
}

const BodyShape& find_shape(const std::string& name) {
  for (const BodyShape& s : kShapes)
    if (name == s.name) return s;
  throw std::logic_error("no body shape named '" + name + "'");
}

// Whether p lies within a body's outline (its shape's, voids included).
bool in_outline(const BodyInfo& b, const Vector& p) { return find_shape(b.shape).outline(b.box, p); }

// ---- Case sections ----

// [run]
void read_run(CaseReader& top, Scene& s) {
  CaseReader r = top.table("run");
  s.run.end_time = r.quantity("end_time", kTime, 0.0, kInf);
  if (!(s.run.end_time > 0.0))
    throw CaseError("case key 'run.end_time': value 0 is out of range: the simulated time must be above 0 "
                    "(e.g. end_time_ns = 200)");
  s.run.snapshot_interval = r.quantity("snapshot_interval", kTime, 0.0, kInf, 0.0);
  s.run.diagnostics_interval = r.quantity("diagnostics_interval", kTime, 0.0, kInf, 0.0);
  s.run.progress_interval = r.number("progress_interval_s", 0.0, 1e6, 5.0);
  s.run.max_steps = r.integer("max_steps", 0, std::numeric_limits<long>::max(), 0);
  s.run.checkpoint_interval = r.number("checkpoint_interval_s", 0.0, 1e7, 300.0);
  // sizes are checked against these before anything is allocated (the grid in [grid], the
  // bodies' points in check_points, the snapshots' volume after the bodies)
  const double phys = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
  const double mem_default = phys > 0 ? 0.8 * phys / 1e9 : 16.0;
  s.run.max_memory = 1e9 * r.number("max_memory_gb", 1e-3, 1e6, mem_default);
  s.run.max_output = 1e9 * r.number("max_output_gb", 1e-3, 1e9, 20.0);
  r.finish();
}

// Bytes of the grid: about 14 arrays of 8 bytes per node and field (grid.hpp), two fields where
// faces separate; `cells` is the number of cells.
double grid_bytes(double cells) { return cells * 14 * 8 * 2; }

// [grid]: each axis's range a whole number of cells of cell_size, the grid's memory within
// run.max_memory
void read_grid(CaseReader& top, Scene& s) {
  CaseReader r = top.table("grid");
  const long dim = r.integer("dimension", 2, 3, 2);
  if (dim != kDim)
    throw CaseError("case key 'grid.dimension' = " + std::to_string(dim) + ": this engine is built for " +
                    std::to_string(kDim) + " axes");
  const double h = r.quantity("cell_size", kLength, 1e-12, kInf);
  Box range;
  for (int a = 0; a < kDim; ++a) std::tie(range.lo[a], range.hi[a]) = r.pair(axis_key(a, "?_range"), kLength, true);
  s.geom.h = h;
  Vector f{};  // cells along each axis, as read
  double cells = 1.0;
  bool too_many = false;
  std::string keys = "case keys 'grid.cell_size'", counts;
  for (int a = 0; a < kDim; ++a) {
    s.geom.lo[a] = range.lo[a];
    f[a] = (range.hi[a] - range.lo[a]) / h;
    cells *= f[a];
    too_many = too_many || !(f[a] <= 1e8);
    keys += ", 'grid." + axis_key(a, "?_range") + "'";
    counts += (a ? " x " : "") + format_number(f[a]);
  }
  if (!(grid_bytes(cells) <= s.run.max_memory) || too_many)
    throw CaseError(keys + ": a grid of " + counts + " cells of " + format_number(h * 1e6) + " um needs about " +
                    format_number(grid_bytes(cells) / 1e9) + " GB, more than 'run.max_memory_gb' = " +
                    format_number(s.run.max_memory / 1e9) + " (default 0.8 of this machine's memory); use larger cells "
                    "or a smaller domain, or raise run.max_memory_gb");
  constexpr const char* kExtent[] = {"width", "height", "depth"};
  for (int a = 0; a < kDim; ++a) {
    const int n = s.geom.n[a] = static_cast<int>(std::lround(f[a]));
    if (std::fabs(f[a] - n) > 1e-6 * f[a] || n < 1)
      throw CaseError("case key 'grid." + axis_key(a, "?_range") + "': " + kExtent[a] + " " +
                      format_number((range.hi[a] - range.lo[a]) * 1e6, 10) + " um is not a whole number of cells of "
                      "'grid.cell_size' " + format_number(h * 1e6, 10) + " um");
  }
  // periodic across the impact axis: x, and z in 3D
  for (int a = 0; a < kDim; ++a) {
    if (a == kImpactAxis) continue;
    const std::string key = axis_key(a, "periodic_?");
    s.geom.wrap[a] = r.boolean(key, false);
    if (s.geom.wrap[a] && s.geom.n[a] < 4)
      throw CaseError("case key 'grid." + key + "': a periodic grid needs at least 4 cells across, got " +
                      std::to_string(s.geom.n[a]));
  }
  s.geom.tile = static_cast<int>(r.integer("tile_cells", 4, kern::kMaxTile, kern::kMaxTile));
  refuse_other_axes(r, {"?_range", "periodic_?"});
  r.finish();
}

// [solver]
void read_solver(CaseReader& top, Scene& s) {
  CaseReader r = top.table("solver");
  const std::string shape = r.choice("shape", {"linear", "ugimp", "quadratic", "cubic"}, "quadratic");
  s.solver.shape = shape == "linear"   ? kern::ShapeKind::Linear
                   : shape == "ugimp"  ? kern::ShapeKind::UGIMP
                   : shape == "cubic"  ? kern::ShapeKind::Cubic
                                       : kern::ShapeKind::Quadratic;
  s.solver.transfer = r.choice("transfer", {"apic", "flip"}, "apic") == "flip" ? Transfer::FLIP : Transfer::APIC;
  s.solver.flip_alpha = r.number("flip_alpha", 0.0, 1.0, 0.99);
  s.solver.scheme = r.choice("scheme", {"usl", "musl"}, "usl") == "musl" ? Scheme::MUSL : Scheme::USL;
  const std::string sr = r.choice("strain_rate", {"auto", "midstep", "updated"}, "auto");
  s.solver.strain_rate = sr == "midstep" ? StrainRate::Midstep : sr == "updated" ? StrainRate::Updated : StrainRate::Auto;
  s.solver.cfl = r.number("cfl", 1e-6, 1.0, 0.4);
  s.solver.fixed_dt = r.quantity("dt", kTime, 0.0, kInf, 0.0);
  s.solver.permute_every = static_cast<int>(r.integer("permute_every", 0, 1000000, 20));
  s.solver.artificial_viscosity = r.boolean("artificial_viscosity", false);
  s.solver.av_linear = r.number("viscosity_linear", 0.0, 10.0, 0.06);
  s.solver.av_quadratic = r.number("viscosity_quadratic", 0.0, 10.0, 1.5);
  s.solver.heat_conduction = r.boolean("heat_conduction", false);
  s.solver.crack_closure = r.boolean("crack_closure", true);
  const Vector gravity = read_vector(r, "gravity", kAcceleration, Vector{});
  for (int a = 0; a < kDim; ++a) s.solver.gravity[a] = gravity[a];
  r.finish();
}

// [walls]: the kind of each side of the grid, by axis: its lower side, then its upper side.
void read_walls(CaseReader& top, Scene& s) {
  constexpr const char* kKeys[3][2] = {{"left", "right"}, {"bottom", "top"}, {"back", "front"}};
  CaseReader r = top.table("walls");
  const std::vector<std::string> kinds{"none", "slip", "noslip"};
  for (int a = 0; a < kDim; ++a) {
    s.solver.walls.lo[a] = wall_kind(r.choice(kKeys[a][0], kinds, "none"));
    s.solver.walls.hi[a] = wall_kind(r.choice(kKeys[a][1], kinds, "none"));
    if (s.geom.wrap[a] && (s.solver.walls.lo[a] != kern::Wall::None || s.solver.walls.hi[a] != kern::Wall::None))
      throw CaseError(std::string("case keys 'walls.") + kKeys[a][0] + "'/'walls." + kKeys[a][1] + "': a grid with " +
                      axis_key(a, "periodic_?") + " = true has no " + kKeys[a][0] + " or " + kKeys[a][1] +
                      " wall; set them to 'none'");
  }
  for (int a = kDim; a < 3; ++a)
    for (const char* k : kKeys[a])
      if (r.has(k))
        throw CaseError(std::string("case key 'walls.") + k + "' is a wall across axis " + kern::kAxisNames[a] +
                        ", which a case with grid.dimension = " + std::to_string(kDim) + " does not have");
  r.finish();
}

// [figures]: colour ranges of the maps that scripts/figures.py draws (the resolved case
// carries them to run.json); absent: from the data (1st-99th percentile of the snapshot)
void read_figures(CaseReader& top) {
  CaseReader r = top.table("figures");
  if (r.has("p_range")) r.pair("p_range", kStress, true);
  if (r.has("t_range")) r.pair("t_range", kTemperature, true);
  r.finish();
}

// [contact]; returns the void faces' reach [cells] (void_face_reach_cells; used with the bodies).
double read_contact(CaseReader& top, const toml::table& doc, Scene& s) {
  double void_reach_cells = 3.0;
  CaseReader r = top.table("contact");
  s.solver.contact = r.choice("mode", {"single_field", "multi_field"}, "single_field") == "multi_field";
  s.solver.friction = r.number("friction", 0.0, 10.0, 0.0);
  s.solver.contact_volume_fraction = r.number("volume_fraction", 0.0, 2.0, 1.0);
  if (s.solver.contact && s.solver.scheme != Scheme::USL)
    throw CaseError("case key 'contact.mode': 'multi_field' runs with solver.scheme = \"usl\" only");
  // void faces (checked against the bodies in check_contact): default 'separate' where a body
  // has voids and nothing rules it out
  bool porous = false;
  if (const toml::array* bs = doc.get_as<toml::array>("bodies"))
    for (const auto& b : *bs)
      if (const toml::table* t = b.as_table()) porous = porous || t->contains("voids");
  const bool can = porous && !s.solver.contact && s.solver.scheme == Scheme::USL;
  if (r.choice("void_faces", {"separate", "single_field"}, can ? "separate" : "single_field") == "separate") {
    s.solver.void_faces = VoidFaces::Separate;
    s.solver.void_face_volume_fraction = r.number("void_face_volume_fraction", 0.1, 2.0, 0.9);
    void_reach_cells = r.number("void_face_reach_cells", 0.5, 1000.0, 3.0);
    s.solver.void_face_merge = r.boolean("void_face_merge", true);
    const long nf = r.integer("void_face_fields", 2, 4, 2);
    if (nf == 3)
      throw CaseError("case key 'contact.void_face_fields' = 3: allowed are 2 (the faces split along the impact "
                      "direction) and 4 (split across it too, for voids a few cells wide)");
    if (nf == 4 && s.solver.transfer != Transfer::APIC)
      throw CaseError("case key 'contact.void_face_fields' = 4 runs with solver.transfer = \"apic\" only (the weld of "
                      "four fields takes APIC's scatter velocity); use 2 with FLIP");
    s.solver.void_face_fields = static_cast<int>(nf);
  } else {
    for (const char* k : {"void_face_volume_fraction", "void_face_reach_cells", "void_face_merge", "void_face_fields"})
      if (r.has(k))
        throw CaseError(std::string("case key 'contact.") + k + "' applies with contact.void_faces = \"separate\" only; "
                        "this case has \"single_field\"" + (can ? "" : " (the default here: no voids, two-body contact or MUSL)"));
  }
  r.finish();
  return void_reach_cells;
}

using MaterialIndex = std::unordered_map<std::string, int>;  // material name -> index in Scene::materials

// The materials library, parsed when a material first names a base.
struct Library {
  std::optional<toml::table> table;
  std::filesystem::path path;
};

// [materials.NAME] with base = "ENTRY": the library's entry, with this table's keys replacing
// the library's, whatever unit they are given in.
Material read_based_material(CaseReader& top, CaseReader& r, const std::string& mname, const toml::table& own,
                             const std::string& base, Library& lib, const std::filesystem::path& case_dir, Scene& s) {
  if (!lib.table) {
    lib.path = find_materials_file(top, case_dir);
    lib.table = parse_case_file(lib.path);
    s.resolved.insert_or_assign("materials_file_used", lib.path.string());
  }
  const toml::table* entry = lib.table->get_as<toml::table>(base);
  if (!entry) {
    std::string names;
    for (const auto& [lk, lv] : *lib.table) names += (names.empty() ? "'" : ", '") + std::string(lk.str()) + "'";
    throw CaseError("case key 'materials." + mname + ".base': '" + base + "' is not in " + lib.path.string() +
                    "; it has " + names);
  }
  toml::table merged = *entry;
  for (const auto& [ok, ov] : own) {
    const std::string key(ok.str());
    if (key == "base") continue;
    std::vector<std::string> drop;
    for (const auto& [lk, lv] : merged)
      if (CaseReader::stem(std::string(lk.str())) == CaseReader::stem(key)) drop.emplace_back(lk.str());
    for (const auto& d : drop) merged.erase(d);
    merged.insert_or_assign(ok, ov);
  }
  r.table(mname);  // marks the key read and creates its resolved table
  toml::table& out = *s.resolved["materials"][mname].as_table();
  out.insert_or_assign("base", base);
  CaseReader mr(merged, "materials." + mname, out);
  return read_material(mr, mname, &own);
}

// [materials.NAME]: each material's own keys, or a library entry (`base`) with its keys on top.
MaterialIndex read_materials(CaseReader& top, const toml::table& doc, const std::filesystem::path& case_dir, Scene& s) {
  MaterialIndex mat_index;
  CaseReader r = top.table("materials");
  const toml::table* mt = doc.get_as<toml::table>("materials");
  if (!mt || mt->empty()) throw CaseError("case table [materials] is required: add at least one [materials.NAME]");
  Library library;
  for (const auto& [k, v] : *mt) {
    const std::string mname(k.str());
    mat_index[mname] = static_cast<int>(s.materials.size());
    const toml::table* own = v.as_table();
    if (!own) throw CaseError("case key 'materials." + mname + "': expected a table [materials." + mname + "]");
    if (own->contains("base") && !own->get_as<std::string>("base"))
      throw CaseError("case key 'materials." + mname + ".base': expected the name of a library entry in quotes");
    if (const auto base = own->get_as<std::string>("base"))
      s.materials.push_back(read_based_material(top, r, mname, *own, base->get(), library, case_dir, s));
    else
      s.materials.push_back(read_material(r.table(mname), mname));
  }
  r.finish();
  return mat_index;
}

// What the bodies of a case share while they are read: one point lattice, the memory their
// points need, and the lattice sites they hold (bodies may not overlap).
struct BodyLattice {
  int ppc = 0;              // points per cell along each axis, the first body's (0 before it)
  double points = 0.0;      // points of the bodies read so far
  double grid_bytes = 0.0;  // the grid's share of run.max_memory [bytes]
  std::unordered_map<long long, std::size_t> taken;  // lattice site -> body
};

// Points a body within `box` would hold, checked before any is made: about 200 bytes each
// (run.json, particle_bytes_per_particle) and 8 for the void cutter's lattice; the grid's share
// was checked with [grid]. `keys`: the keys that set the body's size.
void check_points(const Scene& s, BodyLattice& L, const std::string& keys, const Box& box) {
  const double d = s.geom.h / L.ppc;
  double pts = 1.0;
  for (int a = 0; a < kDim; ++a) pts *= (box.hi[a] - box.lo[a]) / d;
  L.points += pts;
  const double bytes = L.points * 208 + L.grid_bytes;
  if (!(bytes <= s.run.max_memory) || !(L.points < 4e9))
    throw CaseError("case keys '" + keys + "' with 'grid.cell_size' and 'points_per_cell': about " +
                    format_number(L.points) + " points need about " + format_number(bytes / 1e9) +
                    " GB, more than 'run.max_memory_gb' = " + format_number(s.run.max_memory / 1e9) +
                    " (default 0.8 of this machine's memory); use a smaller body or larger cells, or raise "
                    "run.max_memory_gb");
}

// [[bodies]] material: its index in Scene::materials.
int body_material(CaseReader& r, BodyInfo& info, const Scene& s, const MaterialIndex& mat_index) {
  info.material = r.string("material");
  auto it = mat_index.find(info.material);
  if (it == mat_index.end()) {
    std::string names;
    for (const auto& m : s.materials) names += (names.empty() ? "'" : ", '") + m.name + "'";
    throw CaseError("case key '" + r.path() + ".material': '" + info.material + "' is not a material of this case; defined: " + names);
  }
  return it->second;
}

// [[bodies]] mirror_of: the index of the earlier body this one mirrors, -1 for none.
long mirror_source(CaseReader& r, const Scene& s, const BodyInfo& info) {
  const std::string mirror = r.string("mirror_of", "");
  long src = -1;
  if (mirror.empty()) return src;
  std::string names;
  for (std::size_t k = 0; k < s.bodies.size(); ++k) {
    if (s.bodies[k].name == mirror) src = static_cast<long>(k);
    names += (names.empty() ? "'" : ", '") + s.bodies[k].name + "'";
  }
  if (src < 0)
    throw CaseError("case key '" + r.path() + ".mirror_of': '" + mirror + "' is not a body defined before this one" +
                    (names.empty() ? std::string() : "; defined: " + names));
  if (s.bodies[src].material != info.material)
    throw CaseError("case key '" + r.path() + ".material': a mirror copy has the material of '" + mirror + "' ('" +
                    s.bodies[src].material + "')");
  return src;
}

// A mirror copy of the earlier body `src` about the plane where the impact axis is
// mirror_plane_y (default: its lower edge): its points (positions, masses, volumes), bounding
// box, shape and voids reflected. Its points move at velocity v.
Particles mirror_body(CaseReader& r, const Scene& s, std::size_t src, std::uint8_t b, const Vector& v,
                      BodyInfo& info, Box& box) {
  constexpr int A = kImpactAxis;
  const BodyInfo& sb = s.bodies[src];
  const double plane = r.quantity("mirror_plane_y", kLength, -kInf, kInf, sb.box.lo[A]);
  Particles S;
  std::size_t first = 0;
  for (std::size_t k = 0; k < src; ++k) first += s.bodies[k].particles;
  S.resize(sb.particles);
  for (std::size_t i = 0; i < sb.particles; ++i) {
    const std::size_t j = first + i;
    for (int a = 0; a < kDim; ++a) S.x[a][i] = s.particles.x[a][j];
    S.m[i] = s.particles.m[j]; S.V[i] = s.particles.V[j];
  }
  Particles P = mirror(S, A, plane);
  for (std::size_t i = 0; i < P.size(); ++i) {
    for (int a = 0; a < kDim; ++a) P.v[a][i] = v[a];
    P.body[i] = b;
  }
  box = sb.box;
  box.lo[A] = 2 * plane - sb.box.hi[A];
  box.hi[A] = 2 * plane - sb.box.lo[A];
  info.porosity = sb.porosity;
  info.voids = sb.voids;
  info.shape = sb.shape;
  for (Void m : sb.cut) {
    m.c[A] = 2 * plane - m.c[A];
    info.cut.push_back(m);
  }
  return P;
}

// A body of [[bodies]] `shape` (default rectangle): its shape's keys and its points, at velocity v.
Particles fill_shape(CaseReader& r, const Scene& s, BodyLattice& L, double rho0, const Vector& v, std::uint8_t b,
                     BodyInfo& info, Box& box) {
  const BodyShape& shape = find_shape(r.choice("shape", shape_names(), kShapes[0].name));
  const ShapeParams p = shape.read(r);
  box = shape.bbox(p);
  info.shape = shape.name;
  std::string keys;
  for (const std::string& k : shape.size_keys) keys += (keys.empty() ? "" : "', '") + r.path() + "." + k;
  check_points(s, L, keys, box);
  return fill_lattice(s.geom, L.ppc, box, rho0, v, b, [&](const Vector& q) { return shape.inside(p, q); });
}

// [bodies.voids]: what to cut. Voids beyond 50 times those that would tile the body change
// nothing: a bound on the random ones.
VoidSpec read_voids(CaseReader& v, const Scene& s, int ppc, const Box& box) {
  VoidSpec spec;
  spec.radius = v.quantity("radius", kLength, 1e-12, kInf);
  spec.radius_spread = v.quantity("radius_spread", kLength, 0.0, spec.radius * (1 - 1e-12), 0.0);
  // a void smaller than the point spacing removes no point or one: a porosity target
  // would need millions of voids (and never end below half the spacing)
  const double spacing = s.geom.h / ppc, rmin = spec.radius - spec.radius_spread;
  if (rmin < spacing)
    throw CaseError("case key '" + v.path() + ".radius': " + format_number(spec.radius * 1e6) + " um" +
                    (spec.radius_spread > 0 ? " - radius_spread " + format_number(spec.radius_spread * 1e6) + " um" : "") +
                    " is below the point spacing " + format_number(spacing * 1e6) +
                    " um (grid.cell_size / points_per_cell); allowed: at least the spacing, or use smaller cells");
  double size = 1.0;  // of the bounding box [m^2 at D = 2, m^3 at D = 3]
  for (int a = 0; a < kDim; ++a) size *= box.hi[a] - box.lo[a];
  // voids of the smallest radius that would fill it: disks at D = 2, spheres at D = 3
  const double tiling = size / (kDim == 2 ? M_PI * rmin * rmin : 4.0 / 3.0 * M_PI * rmin * rmin * rmin);
  const long void_limit = static_cast<long>(std::min(1e8, 50.0 * tiling + 1000.0));
  if (int(v.has("porosity")) + int(v.has("count")) + int(v.has("center")) != 1)
    throw CaseError("case table [" + v.path() + "]: give exactly one of 'porosity' (target), 'count' (number of "
                    "random voids) and 'center' (one void there, e.g. center_um = " +
                    (kDim == 2 ? "[30.0, 50.0]" : "[30.0, 50.0, 30.0]") + ")");
  if (v.has("center")) {
    spec.centers.push_back({read_vector(v, "center", kLength), spec.radius});
  } else {
    if (v.has("porosity")) spec.porosity = v.number("porosity", 0.0, 0.95);
    else spec.count = v.integer("count", 0, void_limit);
    spec.max_voids = void_limit;
    spec.seed = static_cast<std::uint64_t>(v.integer("seed", 0, std::numeric_limits<long>::max(), 1));
  }
  v.finish();
  return spec;
}

// [bodies.voids]: random overlapping circular (D = 2) or spherical (D = 3) voids (docs/model.md,
// "Porous sample") cut from P.
void cut_body_voids(CaseReader& r, const Scene& s, int ppc, const Box& box, Particles& P, BodyInfo& info) {
  CaseReader v = r.table("voids");
  const VoidSpec spec = read_voids(v, s, ppc, box);
  const auto res = cut_voids(P, s.geom.h / ppc, grid_origin(s.geom), box, spec, periods(s.geom));
  if (spec.porosity >= 0.0 && res.porosity < spec.porosity)
    throw CaseError("case key '" + v.path() + ".porosity': " + format_number(spec.porosity) + " not reached with " +
                    std::to_string(res.voids) + " voids (reached " + format_number(res.porosity) +
                    "); allowed: a porosity these voids can cut, or larger voids");
  info.porosity = res.porosity;
  info.voids = res.voids;
  info.cut = res.cut;
}

// A body lies within the grid (to round-off) and holds at least one point.
void check_in_grid(const CaseReader& r, const Scene& s, const BodyInfo& info, const Box& box, const Particles& P) {
  const double tol = 1e-6 * s.geom.h;  // round-off of x0 + n h
  bool out = false;
  std::string extent;
  for (int a = 0; a < kDim; ++a) {
    const double g0 = s.geom.lo[a], g1 = g0 + s.geom.n[a] * s.geom.h;
    out = out || box.lo[a] < g0 - tol || box.hi[a] > g1 + tol;
    extent += (a ? " x [" : "[") + std::to_string(g0) + ", " + std::to_string(g1) + "]";
  }
  if (out) throw CaseError("case body '" + r.path() + "' (" + info.name + ") extends outside the grid " + extent + " m");
  if (P.size() == 0) throw CaseError("case body '" + r.path() + "' (" + info.name + ") holds no points: it is smaller than the point spacing");
}

// Marks the lattice sites of body b's points taken; a site another body holds is an overlap.
void claim_sites(const std::vector<CaseReader>& bodies, std::size_t b, const Scene& s, BodyLattice& L, const Particles& P) {
  const double d = s.geom.h / L.ppc;
  for (std::size_t i = 0; i < P.size(); ++i) {
    // the site's key: its lattice index along each axis in 64 / kDim bits, the last axis highest
    long long key = 0;
    Vector at;  // [m]
    for (int a = kDim - 1; a >= 0; --a) {
      at[a] = P.x[a][i];
      key = key * (1LL << (64 / kDim)) + std::llround((at[a] - s.geom.lo[a]) / d - 0.5);
    }
    auto [pos, fresh] = L.taken.emplace(key, b);
    if (!fresh)
      throw CaseError("case bodies '" + bodies[pos->second].path() + "' and '" + bodies[b].path() + "' overlap near (" +
                      join_axes(at, [](double value) { return std::to_string(value); }) + ") m");
  }
}

// [[bodies]] entry b: a shape filled with points, or a mirror copy of an earlier body.
void read_body(std::vector<CaseReader>& bodies, std::size_t b, Scene& s, const MaterialIndex& mat_index,
               BodyLattice& L) {
  CaseReader& r = bodies[b];
  BodyInfo info;
  info.name = r.string("name", "body" + std::to_string(b));
  const int material = body_material(r, info, s, mat_index);
  const int ppc = static_cast<int>(r.integer("points_per_cell", 1, 8, 2));
  if (L.ppc && ppc != L.ppc)
    throw CaseError("case key '" + r.path() + ".points_per_cell': " + std::to_string(ppc) +
                    " differs from the first body's " + std::to_string(L.ppc) + "; all bodies share one point lattice");
  L.ppc = ppc;
  const long src = mirror_source(r, s, info);
  Vector v0{};  // the velocity's default: a mirror copy's is its source's, reflected
  if (src >= 0) {
    v0 = s.bodies[src].velocity;
    v0[kImpactAxis] = -v0[kImpactAxis];
  }
  const Vector v = read_vector(r, "velocity", kVelocity, v0);
  const auto id = static_cast<std::uint8_t>(b);
  Box box;
  Particles P = src >= 0 ? mirror_body(r, s, static_cast<std::size_t>(src), id, v, info, box)
                         : fill_shape(r, s, L, s.materials[material].rho0, v, id, info, box);
  if (src < 0 && r.has("voids")) cut_body_voids(r, s, ppc, box, P, info);
  info.record_free_surface = r.boolean("record_free_surface", false);
  refuse_other_axes(r, {"?_range"});
  r.finish();
  info.box = box;
  check_in_grid(r, s, info, box, P);
  claim_sites(bodies, b, s, L, P);
  const double d = s.geom.h / ppc;
  info.particles = P.size();
  info.velocity = v;
  info.area = static_cast<double>(P.size());
  for (int a = 0; a < kDim; ++a) info.area *= d;
  s.body_material.push_back(material);
  s.bodies.push_back(info);
  s.particles.append(P);
}

// Snapshots: about 18 values of 8 bytes per point each (engine/run.cpp, snapshot_fields), within
// run.max_output.
void check_snapshots(const Scene& s) {
  if (!(s.run.snapshot_interval > 0.0)) return;
  const double snaps = std::floor(s.run.end_time / s.run.snapshot_interval) + 2.0;
  const double bytes = snaps * double(s.particles.size()) * 18 * 8;
  if (!(bytes <= s.run.max_output))
    throw CaseError("case key 'run.snapshot_interval': " + format_number(s.run.snapshot_interval * 1e9) + " ns over " +
                    format_number(s.run.end_time * 1e9) + " ns writes " + format_number(snaps) + " snapshots of " +
                    std::to_string(s.particles.size()) + " points, about " + format_number(bytes / 1e9) +
                    " GB, more than 'run.max_output_gb' = " + format_number(s.run.max_output / 1e9) +
                    "; allowed: an interval of at least " +
                    format_number(s.run.end_time * 1e9 * double(s.particles.size()) * 144 / s.run.max_output) +
                    " ns, or raise run.max_output_gb");
}

// [contact] against the bodies. Void faces: the two faces of each void in separate velocity
// fields, welded where they meet (kern::grid_contact), so that gaps narrower than a cell close.
void check_contact(Scene& s, double void_reach_cells) {
  if (s.solver.contact && s.bodies.size() != 2)
    throw CaseError("case key 'contact.mode': 'multi_field' gives each of exactly two bodies its own velocity "
                    "field; this case has " + std::to_string(s.bodies.size()) + " bodies");
  if (s.solver.void_faces != VoidFaces::Separate) return;
  std::vector<Void> voids;
  for (const auto& b : s.bodies) voids.insert(voids.end(), b.cut.begin(), b.cut.end());
  if (voids.empty())
    throw CaseError("case key 'contact.void_faces': 'separate' needs a body with voids ([bodies.voids]); this case has none");
  if (s.solver.contact)
    throw CaseError("case key 'contact.void_faces': 'separate' and contact.mode = 'multi_field' would need four velocity "
                    "fields (not implemented); use a symmetric case with one field per side, or void_faces = 'single_field'");
  if (s.solver.scheme != Scheme::USL)
    throw CaseError("case key 'contact.void_faces': 'separate' runs with solver.scheme = \"usl\" only");
  Vector impact{};  // the unit direction of the impact axis
  impact[kImpactAxis] = 1.0;
  assign_void_sides(s.particles, voids, impact, void_reach_cells * s.geom.h, periods(s.geom),
                    s.solver.void_face_fields);
}

// [[bodies]]; returns the points per cell they share. The body named "target" (else body 0)
// becomes Scene::target.
int read_bodies(CaseReader& top, Scene& s, const MaterialIndex& mat_index, double void_reach_cells) {
  auto bodies = top.tables("bodies");
  if (bodies.empty()) throw CaseError("case array [[bodies]] is required: add at least one body");
  if (bodies.size() > 255) throw CaseError("case array [[bodies]]: at most 255 bodies, got " + std::to_string(bodies.size()));
  BodyLattice L;
  double cells = 1.0;
  for (int a = 0; a < kDim; ++a) cells *= double(s.geom.n[a]);
  L.grid_bytes = grid_bytes(cells);
  for (std::size_t b = 0; b < bodies.size(); ++b) read_body(bodies, b, s, mat_index, L);
  s.solver.ugimp_lp = 0.5 / L.ppc;
  check_snapshots(s);
  check_contact(s, void_reach_cells);
  for (std::size_t b = 0; b < s.bodies.size(); ++b)
    if (s.bodies[b].name == "target") s.target = b;
  return L.ppc;
}

// [[regions]]: bands across the full width, heights along the impact axis measured from the
// impact plane y = 0
void read_regions(CaseReader& top, Scene& s) {
  // a band's width for its open porosity, over the lateral axes: the grid's along a periodic
  // axis, else the body's
  auto band_width = [&](std::size_t b) {
    double w = 1.0;
    for (int a = 0; a < kDim; ++a)
      if (a != kImpactAxis) w *= s.geom.wrap[a] ? s.geom.length(a) : s.bodies[b].box.hi[a] - s.bodies[b].box.lo[a];
    return w;
  };
  auto regions = top.tables("regions");
  if (regions.empty()) {
    // the study's bands, for a target reaching 1000 um above the impact plane or more; a
    // shorter target gets the same bands scaled by its height / 1000 um, so that they stay
    // inside it and apart (a 400 um target: I 40-360, II 40-240, III 40-120 um)
    const double f = std::clamp(s.bodies[s.target].box.hi[kImpactAxis] / 1000e-6, 1e-6, 1.0);
    for (auto [name, a, b] : {std::tuple{"I", 100e-6, 900e-6}, {"II", 100e-6, 600e-6}, {"III", 100e-6, 300e-6}})
      s.regions.push_back({name, f * a, f * b, static_cast<std::uint8_t>(s.target), band_width(s.target)});
  }
  for (auto& r : regions) {
    Region g;
    g.name = r.string("name");
    std::tie(g.lo, g.hi) = r.pair(axis_key(kImpactAxis, "?_range"), kLength, true);
    const std::string body = r.string("body", s.bodies[s.target].name);
    bool found = false;
    for (std::size_t b = 0; b < s.bodies.size(); ++b)
      if (s.bodies[b].name == body) {
        g.body = static_cast<std::uint8_t>(b);
        found = true;
      }
    if (!found) throw CaseError("case key '" + r.path() + ".body': no body named '" + body + "'");
    r.finish();
    g.width = band_width(g.body);
    s.regions.push_back(g);
  }
}

// [[bodies]] record_free_surface: the body's top row at t = 0 (engine/gauges.hpp, top_row). Its top
// must be free: no point of another body within a point spacing above the row, no top wall there.
void add_free_surfaces(Scene& s, double d) {
  constexpr int A = kImpactAxis;
  const Particles& P = s.particles;
  const double grid_top = s.geom.lo[A] + s.geom.length(A);
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    if (!s.bodies[b].record_free_surface) continue;
    FreeSurface f{s.bodies[b].name, top_row(P, static_cast<std::uint8_t>(b), d)};
    // the row's box: its top along the impact axis (hi[A]) and its lateral extent
    Box row;
    for (int a = 0; a < kDim; ++a) {
      row.lo[a] = kInf;
      row.hi[a] = -kInf;
    }
    for (const std::uint32_t i : f.ids)
      for (int a = 0; a < kDim; ++a) {
        row.lo[a] = std::min(row.lo[a], P.x[a][i]);
        row.hi[a] = std::max(row.hi[a], P.x[a][i]);
      }
    const double top = row.hi[A];
    const std::string key = "case key 'bodies[" + std::to_string(b) + "].record_free_surface' = true (body '" +
                            s.bodies[b].name + "'): its top surface at y = " +
                            format_number(std::round((top + 0.5 * d) * 1e12) * 1e-6 + 0.0) +  // [um], round-off cut
                            " um is not free: ";
    // a point of another body within 1.5 spacings above the top, within a spacing of the row's
    // lateral extent
    auto on_top = [&](std::size_t i) {
      bool on = P.body[i] != static_cast<std::uint8_t>(b);
      for (int a = 0; a < kDim; ++a) {
        const double q = P.x[a][i];
        on = on && (a == A ? q > top && q < top + 1.5 * d : q > row.lo[a] - d && q < row.hi[a] + d);
      }
      return on;
    };
    for (std::size_t i = 0; i < P.size(); ++i)
      if (on_top(i))
        throw CaseError(key + "body '" + s.bodies[P.body[i]].name + "' lies on it; allowed on a body whose top "
                        "(max y) surface nothing touches");
    if (s.solver.walls.hi[A] != kern::Wall::None && top + 1.5 * d > grid_top)
      throw CaseError(key + "it touches the grid's top wall (walls.top); allowed on a body whose top (max y) surface "
                      "nothing touches");
    s.free_surfaces.push_back(std::move(f));
  }
}

// The positions of one [[gauges]] table: `position` (one gauge, named `name`) or `count` gauges
// evenly from `from` to `to` (named <name>_<k>, k from 0; count 1: at `from`).
std::vector<std::pair<std::string, Vector>> gauge_positions(CaseReader& r, const std::string& name) {
  const bool line = r.has("from") || r.has("to") || r.has("count");
  const std::string either = "give either 'position' (one gauge, e.g. position_um = [10.0, 200.0]) or 'from', 'to' "
                             "and 'count' (a line of gauges named " + name + "_<k>, e.g. from_um = [10.0, 100.0], "
                             "to_um = [10.0, 400.0], count = 4)";
  if (line && r.has("position"))
    throw CaseError("case table [" + r.path() + "] (gauge '" + name + "'): " + either + ", not both");
  std::vector<std::pair<std::string, Vector>> at;
  if (!line) {
    try {
      at.emplace_back(name, read_vector(r, "position", kLength));
    } catch (const CaseError& e) {  // missing or misspelt: say what else would do
      throw CaseError(std::string(e.what()) + "; " + either);
    }
    return at;
  }
  const Vector from = read_vector(r, "from", kLength), to = read_vector(r, "to", kLength);
  const long n = r.integer("count", 1, 10000);
  for (long k = 0; k < n; ++k) {
    const double f = n > 1 ? double(k) / double(n - 1) : 0.0;
    Vector p;
    for (int a = 0; a < kDim; ++a) p[a] = from[a] + f * (to[a] - from[a]);
    at.emplace_back(name + "_" + std::to_string(k), p);
  }
  return at;
}

// [[gauges]]: each gauge follows the point nearest its position at t = 0, of the body named by
// `body`, else of the bodies whose outline holds the position (in_outline: a gauge in a void
// follows the nearest point of its body); a position outside that body's outline, or every
// body's, is refused. The resolved case names the body when all the table's points lie in one.
void read_gauges(CaseReader& top, Scene& s) {
  auto tables = top.tables("gauges");
  std::vector<std::string> names;
  for (std::size_t t = 0; t < tables.size(); ++t) {
    CaseReader& r = tables[t];
    const std::string name = r.string("name", "gauge" + std::to_string(t));
    if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-") !=
                            std::string::npos)
      throw CaseError("case key '" + r.path() + ".name': '" + name + "' is not a gauge name (a column of gauges.csv): "
                      "allowed are letters, digits, '_', '-' and '.'");
    int body = -1;
    if (r.has("body")) {
      const std::string b = r.string("body");
      std::string defined;
      for (std::size_t k = 0; k < s.bodies.size(); ++k) {
        if (s.bodies[k].name == b) body = static_cast<int>(k);
        defined += (defined.empty() ? "'" : ", '") + s.bodies[k].name + "'";
      }
      if (body < 0) throw CaseError("case key '" + r.path() + ".body': no body named '" + b + "'; defined: " + defined);
    }
    const std::string keys = r.has("position") ? "case key '" + r.path() + ".position'"
                                               : "case keys '" + r.path() + ".from', '" + r.path() + ".to'";
    std::vector<int> in_body;
    for (const auto& [gname, at] : gauge_positions(r, name)) {
      std::vector<bool> holds(s.bodies.size(), false);
      for (std::size_t k = 0; k < s.bodies.size(); ++k)
        holds[k] = (body < 0 || body == static_cast<int>(k)) && in_outline(s.bodies[k], at);
      const auto near = nearest_point(s.particles, at, holds);
      if (near.index == s.particles.size())
        throw CaseError(keys + ": gauge '" + gname + "' at [" +
                        join_axes(at, [](double value) { return format_number(value * 1e6); }) + "] um lies outside " +
                        (body < 0 ? std::string("every body") : "body '" + s.bodies[body].name + "'") +
                        "; allowed: a position within a body's outline (x_range and y_range, or the disk)");
      if (std::find(names.begin(), names.end(), gname) != names.end())
        throw CaseError("case key '" + r.path() + ".name': gauge '" + gname + "' is named twice (gauges.csv tells "
                        "gauges apart by name)");
      names.push_back(gname);
      s.gauges.push_back({gname, static_cast<std::uint32_t>(near.index)});
      in_body.push_back(s.particles.body[near.index]);
    }
    r.finish();
    if (body < 0 && std::all_of(in_body.begin(), in_body.end(), [&](int b) { return b == in_body.front(); }))
      s.resolved["gauges"][t].as_table()->insert_or_assign("body", s.bodies[in_body.front()].name);
  }
}

}  // namespace

Particles fill_rectangle(const kern::GridGeom& g, int ppc, const Box& box, double rho0, const Vector& v,
                         std::uint8_t body) {
  return fill_lattice(g, ppc, box, rho0, v, body, [&](const Vector& p) { return in_half_open(box, p); });
}

Scene build_scene(const toml::table& doc, const std::string& name, const std::filesystem::path& case_dir) {
  Scene s;
  s.name = name;
  CaseReader top(doc, "", s.resolved);
  read_run(top, s);
  read_grid(top, s);
  read_solver(top, s);
  read_walls(top, s);
  read_figures(top);
  const double void_reach_cells = read_contact(top, doc, s);
  const MaterialIndex mat_index = read_materials(top, doc, case_dir, s);
  const int ppc = read_bodies(top, s, mat_index, void_reach_cells);
  read_regions(top, s);
  add_free_surfaces(s, s.geom.h / ppc);
  read_gauges(top, s);
  top.finish();
  return s;
}

}  // namespace SMPM_NS
