// Lagrangian gauges and free-surface velocity (engine/gauges.hpp): the case keys and their
// errors, the points followed, their checkpoint record, and the symmetric plate impact of
// cases/verify/free_surface_1000.toml against the exact answers: the free surface jumps by 2 up,
// the gauges behind the shock read the Rankine-Hugoniot state of the code's EOS.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "engine/case_reader.hpp"
#include "engine/checkpoint.hpp"
#include "engine/gauges.hpp"
#include "engine/run.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"
#include "engine/thermo.hpp"

using namespace smpm;
namespace fs = std::filesystem;

namespace {

const std::string kVerify = std::string(SHOCKMPM_SOURCE_DIR) + "/cases/verify/";

Scene verify_scene(const std::vector<std::string>& sets = {}) {
  auto doc = parse_case_file(kVerify + "free_surface_1000.toml");
  apply_overrides(doc, sets);
  return build_scene(doc, "free_surface_1000", kVerify);
}

std::string error_of(const std::vector<std::string>& sets) {
  try {
    verify_scene(sets);
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// A CSV file as columns by header name (the text columns, gauge and body names, in `names`).
struct Csv {
  std::map<std::string, std::vector<double>> col;
  std::vector<std::string> names;
};
Csv read_csv(const fs::path& file, std::size_t name_column) {
  std::ifstream in(file);
  std::string line, cell;
  std::getline(in, line);
  std::vector<std::string> head;
  for (std::istringstream h(line); std::getline(h, cell, ',');) head.push_back(cell);
  Csv c;
  while (std::getline(in, line)) {
    std::istringstream r(line);
    for (std::size_t k = 0; std::getline(r, cell, ','); ++k)
      if (k == name_column) c.names.push_back(cell);
      else c.col[head.at(k)].push_back(std::stod(cell));
  }
  return c;
}

}  // namespace

TEST_CASE("gauge keys: errors name the key and the value", "[gauges][case]") {
  CHECK(error_of({}) == "");
  const auto outside = error_of({"gauges.flyer_mid.position_um=[11.0, 650.0]"});
  CHECK(has(outside, "case key 'gauges[1].position'"));
  CHECK(has(outside, "gauge 'flyer_mid' at [11, 650] um lies outside every body; allowed: a position within a body's outline"));
  CHECK(has(error_of({"gauges.plate.to_um=[11.0, 610.0]"}), "gauge 'plate_15' at [11, 610] um lies outside body 'target'"));
  CHECK(has(error_of({"gauges.plate.count=0"}), "case key 'gauges[0].count'"));
  CHECK(has(error_of({"gauges.plate.count=0"}), "value 0 is out of range: allowed 1 to 10000"));
  CHECK(has(error_of({"gauges.plate.body=\"plate\""}), "case key 'gauges[0].body': no body named 'plate'; defined: 'target', 'flyer'"));
  CHECK(has(error_of({"gauges.plate.position_um=[11.0, 200.0]"}), "give either 'position'"));
  CHECK(has(error_of({"gauges.flyer_mid.name=\"plate_3\""}), "gauge 'plate_3' is named twice"));
  CHECK(has(error_of({"gauges.flyer_mid.name=\"a,b\""}), "case key 'gauges[1].name': 'a,b' is not a gauge name"));
  // a misspelt key: named, with the spelling meant and the other form
  auto doc = parse_case_file(kVerify + "free_surface_1000.toml");
  doc["gauges"].as_array()->get(1)->as_table()->erase("position_um");
  doc["gauges"].as_array()->get(1)->as_table()->insert("positon_um", toml::array{11.0, -301.0});
  try {
    build_scene(doc, "t", kVerify);
    FAIL("a misspelt position was accepted");
  } catch (const CaseError& e) {
    CHECK(has(e.what(), "unknown key 'positon_um' in [gauges[1]]"));
    CHECK(has(e.what(), "did you mean 'position_um'?"));
    CHECK(has(e.what(), "or 'from', 'to' and 'count'"));
  }
  // the free surface: a body's top touched by another body, or by the top wall
  const auto flyer = error_of({"bodies.flyer.record_free_surface=true"});
  CHECK(has(flyer, "case key 'bodies[1].record_free_surface' = true (body 'flyer')"));
  CHECK(has(flyer, "its top surface at y = 0 um is not free: body 'target' lies on it"));
  const auto wall = error_of({"grid.y_range_um=[-700.0, 600.0]", "walls.top=\"slip\""});
  CHECK(has(wall, "case key 'bodies[0].record_free_surface' = true (body 'target')"));
  CHECK(has(wall, "it touches the grid's top wall (walls.top)"));
}

TEST_CASE("gauges follow the point nearest their position at t = 0 and the free surface is the top row", "[gauges]") {
  const Scene sc = verify_scene();
  const Particles& P = sc.particles;
  REQUIRE(sc.gauges.size() == 17);
  // the line: 151 + 12.5 k um, nearest lattice site (1.25 + 2.5 j um) 0.25 um below it
  for (int k = 0; k < 16; ++k) {
    const Gauge& g = sc.gauges[k];
    CHECK(g.name == "plate_" + std::to_string(k));
    CHECK(P.body[g.id] == 0);
    CHECK(P.x[0][g.id] == Approx(11.25e-6).margin(1e-15));
    CHECK(P.x[1][g.id] == Approx((151.25 + 12.5 * k) * 1e-6).margin(1e-15));
  }
  // without a body key: the flyer's point, and the resolved case names that body
  const Gauge& f = sc.gauges[16];
  CHECK(f.name == "flyer_mid");
  CHECK(P.body[f.id] == 1);
  CHECK(P.x[1][f.id] == Approx(-301.25e-6).margin(1e-15));
  CHECK(sc.resolved["gauges"][1]["body"].value_or(std::string()) == "flyer");
  CHECK(sc.resolved["gauges"][0]["count"].value_or(int64_t{0}) == 16);
  // the target's top row: 8 points (20 um at 2.5 um) at y = 598.75 um
  REQUIRE(sc.free_surfaces.size() == 1);
  CHECK(sc.free_surfaces[0].body_name == "target");
  REQUIRE(sc.free_surfaces[0].ids.size() == 8);
  for (const auto id : sc.free_surfaces[0].ids) CHECK(P.x[1][id] == Approx(598.75e-6).margin(1e-15));
  // a gauge in a void follows the nearest point of its body, on the void's surface
  const Scene porous = verify_scene({"bodies.target.voids.center_um=[11.0, 301.0]", "bodies.target.voids.radius_um=10.0",
                                     "contact.void_faces=\"single_field\""});
  const Particles& Q = porous.particles;
  const std::uint32_t in_void = porous.gauges[12].id;
  const double dist = std::hypot(Q.x[0][in_void] - 11e-6, Q.x[1][in_void] - 301e-6);
  CHECK(Q.body[in_void] == 0);
  CHECK(dist >= 10e-6);
  CHECK(dist < 10e-6 + 2.5e-6);
  // a recorder at t = 0 reads the chosen points' initial state
  Simulation sim(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
  PointRecorder rec(sc.gauges, sc.free_surfaces, P.size());
  const auto s = rec.sample(sim);
  CHECK(s[0].pos[1] == P.x[1][sc.gauges[0].id]);
  CHECK(s[0].vel[1] == -1000.0);
  CHECK(s[0].P == 0.0);
  CHECK(s[0].rho == Approx(2700.0).epsilon(1e-14));
  CHECK(s[0].T == Approx(300.0).epsilon(1e-6));  // T0 through the isentrope table (its interpolation)
  CHECK(s[16].vel[1] == 1000.0);
  CHECK(rec.surface_velocity(sim)[0] == -1000.0);
}

TEST_CASE("the followed ids round-trip through a checkpoint and one without them keeps the case's",
          "[gauges][checkpoint]") {
  const Scene sc = verify_scene();
  const auto file = fs::temp_directory_path() / "smpm_test_gauges_ckpt.bin";
  PointRecorder rec(sc.gauges, sc.free_surfaces, sc.particles.size());
  auto write = [&](const std::vector<std::uint32_t>* ids) {
    CheckpointWriter w(file);
    w.put("run/case_name", std::string("t"));
    if (ids) w.put("points/ids", *ids);
    w.commit();
  };
  // other ids (the points in reverse order of the particle array): taken, and followed
  std::vector<std::uint32_t> ids;
  for (std::size_t k = 0; k < 17 + 8; ++k) ids.push_back(static_cast<std::uint32_t>(sc.particles.size() - 1 - k));
  write(&ids);
  rec.restore(CheckpointReader(file));
  Simulation sim(sc.geom, sc.solver, sc.materials, sc.body_material, sc.particles);
  CHECK(rec.sample(sim)[0].pos[1] == sc.particles.x[1][ids[0]]);
  // without the record (a checkpoint written before it existed): the case's ids
  write(nullptr);
  PointRecorder fresh(sc.gauges, sc.free_surfaces, sc.particles.size());
  fresh.restore(CheckpointReader(file));
  CHECK(fresh.sample(sim)[0].pos[1] == sc.particles.x[1][sc.gauges[0].id]);
  // a record of another length: refused by name
  ids.pop_back();
  write(&ids);
  CHECK_THROWS_WITH(rec.restore(CheckpointReader(file)),
                    Catch::Contains("record 'points/ids' holds 24 point ids, the case follows 25"));
  fs::remove(file);
}

// The symmetric impact at +-1000 m/s (cases/verify/free_surface_1000.toml, h = 5 um, about 1 s).
//  (a) The free surface: at its initial -v until the shock arrives at t1 = L / Us (L = 600 um of
//      material at rest ahead of the shock; the surface moves towards it at v meanwhile; exactly,
//      until the foot of the captured front reaches it, 30 ns before t1 at 1e-7 m/s); then the
//      release doubles the particle-velocity jump: u_fs = -v + 2 up = +v, up = v in a symmetric
//      impact. Exact for a release path that mirrors the loading path. The code's EOS releases
//      along its isentrope, which lies above the Hugoniot: u = int c / rho drho along it from the
//      18.05 GPa state to P = 0 is 1006.1 m/s, so without strength the surface would move at
//      +1006.1 m/s (+0.3 % of the 2 up jump); strength moves the loading and the release paths by
//      about (4/3) Y / (rho c), some 10 m/s each, in opposite senses. Tolerance: 1 % of the jump,
//      20 m/s, which holds all of these. The plateau: from 20 ns after t1 (the front's rise over
//      about 3 cells and the surface's ringing) to the end, 220 ns, before the wave reflected at
//      the parted interface can return. At 1000 m/s the plastic shock (Us = 6684 m/s) outruns the
//      elastic precursor (6437 m/s): one wave arrives, not two. The arrival (u_fs crosses 0)
//      within 2 ns of t1: the front spreads over about 3 cells (2.2 ns at Us).
//  (b) The gauges behind the shock: P, rho, T of the exact Rankine-Hugoniot state of the code's
//      EOS (hugoniot()), with test_shock's tolerances for the same means (P 2 %, rho 1 %, T 5 %),
//      over the 16 gauges (two cycles of their rest position within a cell: one gauge reads within
//      +-6 % of P, the case file says why) from 10 ns after the shock passes each (y0 / Us) to t1,
//      before the release from the free surface can reach any of them. The flyer's gauge reads
//      the values of its mirror image plate_12 (y -> -y, vy -> -vy) to 1e-9.
namespace {

void check_free_surface(const fs::path& out, double v, double t1) {
  const Csv c = read_csv(out / "freesurface.csv", 1);
  const auto& t = c.col.at("time_ns");
  const auto& u = c.col.at("u_fs_m_s");
  REQUIRE(t.size() >= 200);  // a row every diagnostics_interval (1 ns) and the step that passes it
  double before = 0, plateau = 0, n = 0, arrival = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    CHECK(c.names[k] == "target");
    if (t[k] < t1 - 30) before = std::max(before, std::fabs(u[k] + v));
    if (arrival == 0 && u[k] > 0) arrival = t[k];
    if (t[k] >= t1 + 20) {
      plateau += u[k];
      n += 1;
    }
  }
  plateau /= n;
  WARN("free surface: " << plateau << " m/s over " << n << " rows from " << t1 + 20 << " ns (exact -v + 2 up = " << v
                        << ": jump " << plateau + v << " against 2 up = " << 2 * v << ", "
                        << 100 * ((plateau + v) / (2 * v) - 1) << " %); crosses 0 at " << arrival
                        << " ns (shock arrival L / Us = " << t1 << " ns); largest |u_fs + v| before: " << before);
  CHECK(before < 1e-9 * v);
  CHECK(std::fabs(plateau - v) < 0.01 * 2 * v);
  CHECK(std::fabs(arrival - t1) < 2.0);
}

void check_gauges(const fs::path& out, const HugoniotState& h, double t1) {
  const Csv g = read_csv(out / "gauges.csv", 1);
  std::map<std::string, std::vector<std::size_t>> rows;  // each gauge's rows, in time order
  for (std::size_t k = 0; k < g.names.size(); ++k) rows[g.names[k]].push_back(k);
  const auto& col = g.col;
  double P = 0, rho = 0, T = 0, m = 0, lo = 1e300, hi = 0;
  for (int j = 0; j < 16; ++j) {
    const auto& r = rows.at("plate_" + std::to_string(j));
    const double y0 = col.at("y_um")[r.front()] * 1e-6;
    double Pj = 0, mj = 0;
    for (const std::size_t k : r) {
      const double tk = col.at("time_ns")[k];
      if (tk < y0 / h.Us * 1e9 + 10 || tk > t1) continue;
      Pj += col.at("P_GPa")[k] * 1e9;
      rho += col.at("rho_g_cc")[k] * 1e3;
      T += col.at("T_K")[k];
      mj += 1;
    }
    P += Pj;
    m += mj;
    lo = std::min(lo, Pj / mj);
    hi = std::max(hi, Pj / mj);
  }
  P /= m, rho /= m, T /= m;
  WARN("16 gauges behind the shock (" << m << " rows): P " << P << " (exact " << h.P << ", " << 100 * (P / h.P - 1)
                                      << " %; one gauge's mean " << 100 * (lo / h.P - 1) << " to "
                                      << 100 * (hi / h.P - 1) << " %), rho " << rho << " (exact " << h.rho << ", "
                                      << 100 * (rho / h.rho - 1) << " %), T " << T << " (exact " << h.T << ", "
                                      << 100 * (T / h.T - 1) << " %)");
  CHECK(P == Approx(h.P).epsilon(0.02));
  CHECK(rho == Approx(h.rho).epsilon(0.01));
  CHECK(T == Approx(h.T).epsilon(0.05));
  // the mirror image
  const auto& a = rows.at("plate_12");
  const auto& b = rows.at("flyer_mid");
  REQUIRE(a.size() == b.size());
  for (std::size_t k = 0; k < a.size(); ++k)
    for (const char* c : {"y_um", "vy_m_s", "P_GPa", "rho_g_cc", "T_K"}) {
      const double sign = std::string(c) == "y_um" || std::string(c) == "vy_m_s" ? -1.0 : 1.0;
      CHECK(sign * col.at(c)[b[k]] == Approx(col.at(c)[a[k]]).epsilon(1e-9).margin(1e-9));
    }
}

}  // namespace

TEST_CASE("symmetric plate impact: free surface at -v + 2 up, gauges on the Hugoniot", "[verification][gauges]") {
  Scene sc = verify_scene();
  const auto out = fs::temp_directory_path() / "smpm_test_free_surface";
  fs::remove_all(out);
  REQUIRE(run_scene(sc, {out, 0, true, true, ""}).status == "completed");
  const double v = 1000.0;
  const HugoniotState h = hugoniot(sc.materials[0], v);
  check_free_surface(out, v, 600e-6 / h.Us * 1e9);
  check_gauges(out, h, 600e-6 / h.Us * 1e9);
  fs::remove_all(out);
}
