// Checkpoints (engine/checkpoint.hpp): the file format refuses anything but a whole file, and a
// Simulation restored from one takes bitwise the steps the saved one takes, at 1 and 2 threads,
// for the porous two-body case (two velocity fields, Coulomb friction, heat conduction) and the
// porous wall case (separated void faces, FLIP). The driver's resume (CSV, snapshots, SIGKILL)
// is tests/driver_restart.sh.
#include <catch2/catch.hpp>
#include <omp.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "engine/case_reader.hpp"
#include "engine/checkpoint.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"

using namespace smpm;
namespace fs = std::filesystem;

namespace {

fs::path temp_file(const std::string& name) { return fs::temp_directory_path() / ("smpm_test_ckpt_" + name); }

std::string error_of(const fs::path& f) {
  try {
    CheckpointReader r(f);
  } catch (const CheckpointError& e) {
    return e.what();
  }
  return "";
}

// Porous aluminium, 1000 m/s: onto a slip wall (one body) or against its mirror image (two).
constexpr const char* kTwoBody = R"(
[run]
end_time_ns = 100.0
[grid]
cell_size_um = 2.0
x_range_um = [0.0, 40.0]
y_range_um = [-60.0, 60.0]
periodic_x = true
[solver]
cfl = 0.3
artificial_viscosity = true
heat_conduction = true
[contact]
mode = "multi_field"
friction = 0.3
[materials.al]
base = "aluminium"
[[bodies]]
name = "target"
material = "al"
x_range_um = [0.0, 40.0]
y_range_um = [0.0, 40.0]
velocity_m_s = [100.0, -1000.0]
[bodies.voids]
radius_um = 5.0
porosity = 0.4
seed = 3
[[bodies]]
name = "flyer"
material = "al"
mirror_of = "target"
)";

constexpr const char* kWall = R"(
[run]
end_time_ns = 100.0
[grid]
cell_size_um = 2.0
x_range_um = [0.0, 40.0]
y_range_um = [0.0, 60.0]
periodic_x = true
[solver]
transfer = "flip"
cfl = 0.3
artificial_viscosity = true
[walls]
bottom = "slip"
[materials.al]
base = "aluminium"
[[bodies]]
name = "target"
material = "al"
x_range_um = [0.0, 40.0]
y_range_um = [0.0, 40.0]
velocity_m_s = [0.0, -1000.0]
[bodies.voids]
radius_um = 5.0
porosity = 0.4
seed = 3
)";

// Runs `first` steps, saves, runs `then` more; a second Simulation built from the scene restores
// the checkpoint and runs `then` steps: every particle array and scalar must be bitwise equal.
void check_restart(const char* text, int threads, int first, int then) {
  omp_set_num_threads(threads);
  Scene sc = build_scene(toml::parse(text), "t", SHOCKMPM_SOURCE_DIR "/cases");
  Simulation a(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
  for (int s = 0; s < first; ++s) {
    a.store_gradient(s % 7 == 0);  // as the driver: gradient measures stored only before statistics
    a.step();
  }
  const auto file = temp_file("sim.bin");
  {
    CheckpointWriter w(file);
    a.save(w);
    w.commit();
  }
  Simulation b(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
  b.restore(CheckpointReader(file));
  REQUIRE(b.steps() == a.steps());
  REQUIRE(b.time() == a.time());
  for (int s = 0; s < then; ++s) {
    a.store_gradient(s % 5 == 0);
    b.store_gradient(s % 5 == 0);
    a.step();
    b.step();
  }
  Particles &A = a.particles(), &B = b.particles();
  REQUIRE(A.fields_in_use() == B.fields_in_use());
  std::vector<std::string> differ;
  A.each_array([&](const char* name, const auto& x) {
    B.each_array([&](const char* nb, const auto& y) {
      if constexpr (std::is_same_v<decltype(x), decltype(y)>)
        if (std::string(name) == nb && x != y) differ.push_back(name);
    });
  });
  INFO("threads " << threads);
  CHECK(differ.empty());
  for (const auto& d : differ) UNSCOPED_INFO("differs: " << d);
  CHECK(a.time() == b.time());
  CHECK(a.steps() == b.steps());
  CHECK(a.stable_dt() == b.stable_dt());
  CHECK(a.energy().total() == b.energy().total());
  CHECK(a.removed().wall == b.removed().wall);
  CHECK(a.removed().contact == b.removed().contact);
  CHECK(a.wall_forces().lo[1] == b.wall_forces().lo[1]);
  // a checkpoint of another case is refused, naming what differs
  Scene other = build_scene(toml::parse(kWall), "t", SHOCKMPM_SOURCE_DIR "/cases");
  if (other.particles.size() != sc.particles.size() || other.solver.transfer != sc.solver.transfer) {
    Simulation c(other.geom, other.solver, other.materials, other.body_material, other.particles);
    CHECK_THROWS_WITH(c.restore(CheckpointReader(file)), Catch::Contains("not a checkpoint of this case"));
  }
  fs::remove(file);
  // a checkpoint whose scalars carry other names is refused, naming them (the last record of a
  // name is the one read)
  const auto renamed = temp_file("renamed.bin");
  {
    CheckpointWriter w(renamed);
    a.save(w);
    w.put("sim/scalar_names", std::string("time [s];"));
    w.commit();
  }
  Simulation d(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
  CHECK_THROWS_WITH(d.restore(CheckpointReader(renamed)), Catch::Contains("holds the scalars 'time [s];'"));
  fs::remove(renamed);
}

}  // namespace

TEST_CASE("checkpoint files: records round-trip; a cut or damaged file is refused", "[checkpoint]") {
  const auto f = temp_file("format.bin");
  const std::vector<double> d{1.5, -0.0, 1e-300, 3.0};
  const std::vector<std::uint32_t> u{7, 8, 9};
  const std::vector<std::uint8_t> b{1, 2, 3, 4, 5};
  {
    CheckpointWriter w(f);
    w.put("d", d);
    w.put("u", u);
    w.put("b", b);
    w.put("x", 2.5);
    w.put("i", std::int64_t{-42});
    w.put("t", std::string("case text\nwith lines"));
    w.put("empty", std::vector<double>{});
    w.commit();
  }
  REQUIRE_FALSE(fs::exists(f.string() + ".tmp"));
  {
    CheckpointReader r(f);
    std::vector<double> d2;
    std::vector<std::uint32_t> u2;
    std::vector<std::uint8_t> b2, e2;
    r.get("d", d2);
    r.get("u", u2);
    r.get("b", b2);
    CHECK(d2 == d);
    CHECK(u2 == u);
    CHECK(b2 == b);
    CHECK(r.number("x") == 2.5);
    CHECK(r.integer("i") == -42);
    CHECK(r.text("t") == "case text\nwith lines");
    std::vector<double> e;
    r.get("empty", e);
    CHECK(e.empty());
    CHECK_THROWS_WITH(r.number("missing"), Catch::Contains("has no record 'missing'"));
    CHECK_THROWS_WITH(r.text("d"), Catch::Contains("record 'd' is a double array, expected a text"));
  }
  const auto size = fs::file_size(f);
  const auto g = temp_file("damaged.bin");
  for (std::uintmax_t cut : {std::uintmax_t{0}, std::uintmax_t{5}, size / 2, size - 1}) {
    fs::copy_file(f, g, fs::copy_options::overwrite_existing);
    fs::resize_file(g, cut);
    INFO("cut to " << cut << " of " << size << " bytes");
    CHECK_THAT(error_of(g), Catch::Contains("is not a whole shockmpm checkpoint"));
  }
  for (std::uintmax_t at : {std::uintmax_t{20}, size / 2, size - 3}) {  // one byte flipped
    fs::copy_file(f, g, fs::copy_options::overwrite_existing);
    std::fstream s(g, std::ios::in | std::ios::out | std::ios::binary);
    s.seekg(static_cast<std::streamoff>(at));
    const char c = static_cast<char>(s.get());
    s.seekp(static_cast<std::streamoff>(at));
    s.put(static_cast<char>(c ^ 0x10));
    s.close();
    INFO("byte " << at << " of " << size << " flipped");
    CHECK_THAT(error_of(g), Catch::Contains("is not a whole shockmpm checkpoint"));
  }
  CHECK_THAT(error_of(temp_file("absent.bin")), Catch::Contains("cannot open checkpoint"));
  fs::remove(f);
  fs::remove(g);
}

TEST_CASE("an uncommitted checkpoint leaves no file", "[checkpoint]") {
  const auto f = temp_file("uncommitted.bin");
  {
    CheckpointWriter w(f);
    w.put("d", std::vector<double>(100, 1.0));
  }
  CHECK_FALSE(fs::exists(f));
  CHECK_FALSE(fs::exists(f.string() + ".tmp"));
}

TEST_CASE("restart is bitwise: porous two-body with friction and heat conduction", "[checkpoint][restart]") {
  for (int t : {1, 2}) check_restart(kTwoBody, t, 23, 25);
}

TEST_CASE("restart is bitwise: porous onto the wall, separated void faces, FLIP", "[checkpoint][restart]") {
  for (int t : {1, 2}) check_restart(kWall, t, 23, 25);
}
