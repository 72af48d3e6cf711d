#include "kernels/dimension.hpp"
#include "engine/gauges.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string_view>

#include "engine/checkpoint.hpp"
#include "engine/columns.hpp"
#include "engine/diagnostics.hpp"
#include "engine/simulation.hpp"

namespace SMPM_NS {

NearestPoint nearest_point(const Particles& P, const Vector& at, const std::vector<bool>& in_body) {
  NearestPoint best{P.size(), std::numeric_limits<double>::infinity()};
  double best2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (std::size_t{P.body[i]} >= in_body.size() || !in_body[P.body[i]]) continue;
    double e[kern::kDim];  // point - at [m]
    for (int d = 0; d < kern::kDim; ++d) e[d] = P.x[d][i] - at[d];
    const double d2 = kern::norm2(e);
    if (d2 < best2) {  // strict: the lowest index among equally near points
      best2 = d2;
      best.index = i;
    }
  }
  best.distance = std::sqrt(best2);
  return best;
}

std::vector<std::uint32_t> top_row(const Particles& P, std::uint8_t body, double spacing) {
  const std::vector<double>& pos = P.x[kImpactAxis];
  double top = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < P.size(); ++i)
    if (P.body[i] == body) top = std::max(top, pos[i]);
  std::vector<std::uint32_t> ids;
  for (std::size_t i = 0; i < P.size(); ++i)
    if (P.body[i] == body && pos[i] > top - 0.5 * spacing) ids.push_back(static_cast<std::uint32_t>(i));
  return ids;
}

PointRecorder::PointRecorder(std::vector<Gauge> gauges, std::vector<FreeSurface> surfaces, std::size_t n_points)
    : gauges_(std::move(gauges)), surfaces_(std::move(surfaces)), n_points_(n_points) {
  index();
}

void PointRecorder::index() {
  unique_.clear();
  for (const auto& g : gauges_) unique_.push_back(g.id);
  for (const auto& s : surfaces_) unique_.insert(unique_.end(), s.ids.begin(), s.ids.end());
  std::sort(unique_.begin(), unique_.end());
  unique_.erase(std::unique(unique_.begin(), unique_.end()), unique_.end());
  slot_.assign(unique_.empty() ? 0 : n_points_, -1);
  for (std::size_t k = 0; k < unique_.size(); ++k) slot_[unique_[k]] = static_cast<std::int32_t>(k);
  where_.assign(unique_.size(), 0);
}

void PointRecorder::locate(const Particles& P) {
  if (unique_.empty()) return;
  for (std::size_t i = 0; i < P.size(); ++i)
    if (const std::int32_t s = slot_[P.id[i]]; s >= 0) where_[static_cast<std::size_t>(s)] = i;
}

void PointRecorder::save(CheckpointWriter& w) const {
  std::vector<std::uint32_t> ids;
  for (const auto& g : gauges_) ids.push_back(g.id);
  for (const auto& s : surfaces_) ids.insert(ids.end(), s.ids.begin(), s.ids.end());
  w.put("points/ids", ids);
}

void PointRecorder::restore(const CheckpointReader& r) {
  if (!r.has("points/ids")) return;
  std::vector<std::uint32_t> ids;
  r.get("points/ids", ids);
  std::size_t n = gauges_.size();
  for (const auto& s : surfaces_) n += s.ids.size();
  const bool in_range = std::all_of(ids.begin(), ids.end(), [&](std::uint32_t id) { return id < n_points_; });
  if (ids.size() != n || !in_range)
    throw CheckpointError("checkpoint " + r.file().string() + ": record 'points/ids' holds " +
                          std::to_string(ids.size()) + " point ids" + (in_range ? "" : ", some beyond the particle count") +
                          ", the case follows " + std::to_string(n) + " (gauges and free-surface points): not a "
                          "checkpoint of this case");
  std::size_t k = 0;
  for (auto& g : gauges_) g.id = ids[k++];
  for (auto& s : surfaces_)
    for (auto& id : s.ids) id = ids[k++];
  index();
}

std::vector<GaugeSample> PointRecorder::sample(const Simulation& sim) {
  const Particles& P = sim.particles();
  locate(P);
  std::vector<GaugeSample> out;
  for (const auto& g : gauges_) {
    const std::size_t i = where_[static_cast<std::size_t>(slot_[g.id])];
    const int k = sim.body_material()[P.body[i]];
    GaugeSample smp;
    for (int d = 0; d < kern::kDim; ++d) {
      smp.pos[d] = P.x[d][i];
      smp.vel[d] = P.v[d][i];
    }
    // sigma = s - P 1: the pressure on the diagonal only
    for (int c = 0; c < smp.sigma.K; ++c) smp.sigma[c] = c < kern::kDim ? P.s[c][i] - P.p[i] : P.s[c][i];
    smp.P = P.p[i];
    smp.rho = P.m[i] / P.V[i];
    smp.T = particle_temperature(P, i, sim.thermo()[k], sim.materials()[k]);
    out.push_back(smp);
  }
  return out;
}

std::vector<double> PointRecorder::surface_velocity(const Simulation& sim) {
  const Particles& P = sim.particles();
  locate(P);
  std::vector<double> u;
  for (const auto& s : surfaces_) {
    double sum = 0.0;
    for (const std::uint32_t id : s.ids) sum += P.v[kImpactAxis][where_[static_cast<std::size_t>(slot_[id])]];
    u.push_back(s.ids.empty() ? 0.0 : sum / double(s.ids.size()));
  }
  return u;
}

namespace {

// gauges.csv: one row per gauge at a time
struct GaugeRow {
  double t;  // [s]
  std::string_view name;
  const GaugeSample& g;
};
// a component of a row's position [um], velocity [m/s] and stress [GPa] (components of the
// axes the engine has; the others are never listed)
template <int A>
double pos_um(const GaugeRow& r) {
  if constexpr (A < kern::kDim) return r.g.pos[A] * 1e6;
  else return 0.0;
}
template <int A>
double vel_m_s(const GaugeRow& r) {
  if constexpr (A < kern::kDim) return r.g.vel[A];
  else return 0.0;
}
template <int K>
double sigma_GPa(const GaugeRow& r) {
  if constexpr (K < kern::sym_size(kern::kDim)) return r.g.sigma[K] * 1e-9;
  else return 0.0;
}
// time, gauge, position and velocity by axis, stress by symmetric component (kernels/tensor.hpp's
// order: xx, yy, xy at D = 2; xx, yy, zz, xy, xz, yz at D = 3), P, rho, T
constexpr auto kGaugeColumns = [] {
  constexpr int D = kern::kDim, K = kern::sym_size(D);
  constexpr const char* kPos[] = {"x_um", "y_um", "z_um"};
  constexpr const char* kVel[] = {"vx_m_s", "vy_m_s", "vz_m_s"};
  constexpr const char* kSigma[2][6] = {
      {"sigma_xx_GPa", "sigma_yy_GPa", "sigma_xy_GPa"},
      {"sigma_xx_GPa", "sigma_yy_GPa", "sigma_zz_GPa", "sigma_xy_GPa", "sigma_xz_GPa", "sigma_yz_GPa"}};
  constexpr double (*kPosF[])(const GaugeRow&) = {pos_um<0>, pos_um<1>, pos_um<2>};
  constexpr double (*kVelF[])(const GaugeRow&) = {vel_m_s<0>, vel_m_s<1>, vel_m_s<2>};
  constexpr double (*kSigmaF[])(const GaugeRow&) = {sigma_GPa<0>, sigma_GPa<1>, sigma_GPa<2>,
                                                     sigma_GPa<3>, sigma_GPa<4>, sigma_GPa<5>};
  std::array<Column<GaugeRow>, 5 + 2 * D + K> c{};
  int i = 0;
  c[i++] = {"time_ns", "ns", [](const GaugeRow& r) { return r.t * 1e9; }};
  c[i++] = {"gauge", "name", nullptr, [](const GaugeRow& r) { return r.name; }};
  for (int a = 0; a < D; ++a) c[i++] = {kPos[a], "um", kPosF[a]};
  for (int a = 0; a < D; ++a) c[i++] = {kVel[a], "m/s", kVelF[a]};
  for (int k = 0; k < K; ++k) c[i++] = {kSigma[D - 2][k], "GPa", kSigmaF[k]};
  c[i++] = {"P_GPa", "GPa", [](const GaugeRow& r) { return r.g.P * 1e-9; }};
  c[i++] = {"rho_g_cc", "g/cc", [](const GaugeRow& r) { return r.g.rho * 1e-3; }};
  c[i++] = {"T_K", "K", [](const GaugeRow& r) { return r.g.T; }};
  return c;
}();

// freesurface.csv: one row per free surface at a time
struct SurfaceRow {
  double t;  // [s]
  std::string_view body;
  double u;  // [m/s]
};
constexpr Column<SurfaceRow> kSurfaceColumns[] = {
    {"time_ns", "ns", [](const SurfaceRow& r) { return r.t * 1e9; }},
    {"body", "name", nullptr, [](const SurfaceRow& r) { return r.body; }},
    {"u_fs_m_s", "m/s", [](const SurfaceRow& r) { return r.u; }},
};

}  // namespace

std::string PointRecorder::gauge_header() { return csv_header(kGaugeColumns); }
std::string PointRecorder::surface_header() { return csv_header(kSurfaceColumns); }

void PointRecorder::gauge_rows(std::ostream& o, const Simulation& sim) {
  const auto v = sample(sim);
  for (std::size_t k = 0; k < v.size(); ++k) csv_row(o, kGaugeColumns, GaugeRow{sim.time(), gauges_[k].name, v[k]});
}

void PointRecorder::surface_rows(std::ostream& o, const Simulation& sim) {
  const auto u = surface_velocity(sim);
  for (std::size_t k = 0; k < u.size(); ++k)
    csv_row(o, kSurfaceColumns, SurfaceRow{sim.time(), surfaces_[k].body_name, u[k]});
}

}  // namespace SMPM_NS
