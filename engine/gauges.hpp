// Lagrangian gauges and free-surface velocity: material points chosen at t = 0 and followed
// through the run, as a gauge embedded in a sample and a velocity interferometer (VISAR) on its
// free rear surface record them. A point is named by its id (Particles::id, its index at t = 0),
// so the arrays' permutation does not lose it; a resumed run follows the same ids (PointRecorder
// stores them in its checkpoint).
#pragma once
#include "kernels/dimension.hpp"
#include <cstddef>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "engine/geometry.hpp"
#include "engine/particles.hpp"
#include "kernels/tensor.hpp"

namespace smpm {
class CheckpointWriter;
class CheckpointReader;
}  // namespace smpm

namespace SMPM_NS {

class Simulation;

// A gauge: the material point nearest a position at t = 0 (case table [[gauges]]).
struct Gauge {
  std::string name;
  std::uint32_t id = 0;  // the followed point (Particles::id)
};

// A body whose top (max y) surface is free: its top row of points at t = 0 ([[bodies]]
// record_free_surface).
struct FreeSurface {
  std::string body_name;
  std::vector<std::uint32_t> ids;  // the points of its top row (top_row), ascending
};

// The point nearest `at` among those of the bodies b with in_body[b], and its distance [m]; among
// equally near points the one of lowest index. index = P.size() when no point qualifies. At t = 0,
// when index and id coincide, the index is the point's id.
struct NearestPoint {
  std::size_t index = 0;
  double distance = 0.0;
};
NearestPoint nearest_point(const Particles& P, const Vector& at, const std::vector<bool>& in_body);

// The points of `body` in its top row: along the impact axis (y) within half a point spacing of the body's highest point
// (the surface lies half a spacing above that row, so these are the points within one spacing of
// it), as indices in ascending order (ids at t = 0).
std::vector<std::uint32_t> top_row(const Particles& P, std::uint8_t body, double spacing);

// One gauge's values: position [m], velocity [m/s], Cauchy stress without the artificial viscous
// pressure (sigma = s - P 1, tension positive: compression makes sigma_xx, sigma_yy negative) [Pa],
// EOS pressure P (compression positive) [Pa], density [kg/m^3], temperature [K] (T0 where the
// material carries no energy); the snapshots' definitions (engine/run.cpp, snapshot_fields).
struct GaugeSample {
  Vector pos, vel;
  kern::Sym<kern::kDim> sigma;  // components in kernels/tensor.hpp's order
  double P, rho, T;
};

// The followed points of a run: finds them in the current particle order (one pass over the
// points per call) and writes the rows of gauges.csv and freesurface.csv.
class PointRecorder {
 public:
  // n_points: the particle count (ids are below it)
  PointRecorder(std::vector<Gauge> gauges, std::vector<FreeSurface> surfaces, std::size_t n_points);
  bool has_gauges() const { return !gauges_.empty(); }
  bool has_surfaces() const { return !surfaces_.empty(); }
  // The record "points/ids": every gauge's id, then every surface's ids, in the case's order.
  void save(CheckpointWriter& w) const;
  // Takes the ids of a checkpoint that has the record (one without it, written before the record
  // existed, keeps the ids chosen from the case's t = 0 state); a record of another length is
  // refused (CheckpointError naming the file and the record).
  void restore(const CheckpointReader& r);
  std::vector<GaugeSample> sample(const Simulation& sim);
  // Mean velocity along the impact axis (y) of each surface's points [m/s], summed in id order (any thread count, any
  // particle order: the same bits).
  std::vector<double> surface_velocity(const Simulation& sim);
  // The CSV headers (README, "Output") and the rows at the simulation's time, from the column
  // lists of engine/gauges.cpp: `time_ns,gauge,x_um,...,T_K` and `time_ns,body,u_fs_m_s`.
  static std::string gauge_header();
  static std::string surface_header();
  void gauge_rows(std::ostream& o, const Simulation& sim);
  void surface_rows(std::ostream& o, const Simulation& sim);

 private:
  void index();                             // slot_ and where_ from the ids
  void locate(const Particles& P);          // where_: current index of every followed id
  std::vector<Gauge> gauges_;
  std::vector<FreeSurface> surfaces_;
  std::vector<std::uint32_t> unique_;       // the followed ids, ascending, once each
  std::vector<std::int32_t> slot_;          // per id: its position in unique_, or -1
  std::vector<std::size_t> where_;          // per unique_ entry: its current particle index
  std::size_t n_points_ = 0;
};

}  // namespace SMPM_NS
