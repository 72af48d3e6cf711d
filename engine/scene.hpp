// Scenes: a case file turned into a grid, solver settings, materials and filled bodies.
#pragma once
#include "kernels/dimension.hpp"
#include <filesystem>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "engine/diagnostics.hpp"
#include "engine/gauges.hpp"
#include "engine/geometry.hpp"
#include "engine/material.hpp"
#include "engine/particles.hpp"
#include "engine/porous.hpp"
#include "engine/simulation.hpp"

namespace SMPM_NS {

// What a run does besides stepping: when to stop, what to write and how often.
struct RunControl {
  double end_time = 0.0;           // [s]
  double snapshot_interval = 0.0;  // [s]; 0: first and last state only
  double diagnostics_interval = 0.0;  // [s]; rows of energy.csv and front.csv (0: every step)
  double progress_interval = 5.0;  // [s of wall time] between progress lines
  long max_steps = 0;              // 0: no limit
  double checkpoint_interval = 300.0;  // [s of wall time] between checkpoints (0: only at SIGINT/SIGTERM)
  double max_memory = 0.0;         // [bytes] a case needing more is refused before allocation
  double max_output = 0.0;         // [bytes] snapshot volume above which a case is refused
};

struct BodyInfo {
  std::string name;
  std::string material;
  std::size_t particles = 0;
  double area = 0.0;  // [m^2 per unit thickness], material area (points x point area)
  Vector velocity{};  // initial velocity [m/s]
  Box box;            // bounding rectangle [m]
  std::string shape = "rectangle";  // [[bodies]] shape: its outline, within that rectangle
  double porosity = 0.0;  // fraction of the dense body's points removed by voids
  long voids = 0;
  std::vector<Void> cut;  // its voids (a mirror copy: their mirror images)
  bool record_free_surface = false;  // its top surface's velocity goes to freesurface.csv
};

struct Scene {
  kern::GridGeom geom;
  SolverConfig solver;
  RunControl run;
  std::vector<Material> materials;
  std::vector<int> body_material;
  std::vector<BodyInfo> bodies;
  Particles particles;
  std::size_t target = 0;       // the body named "target", else body 0: diagnostics default to it
  std::vector<Region> regions;  // bands for series.csv (default: the study's I, II, III of the target)
  std::vector<Gauge> gauges;    // [[gauges]]: the points gauges.csv follows
  std::vector<FreeSurface> free_surfaces;  // bodies with record_free_surface: freesurface.csv
  toml::table resolved;  // the case with every default filled in
  std::string name;      // case file stem
};

// Builds a scene from a parsed case. Throws CaseError with the key, value and allowed range.
// Relative paths in the case (materials_file) are taken from case_dir.
Scene build_scene(const toml::table& doc, const std::string& name, const std::filesystem::path& case_dir);

// Fills the half-open box [lo, hi) with ppc points per cell along each axis of the grid lattice
// (points at sub-cell centres), all at velocity v, for bodies built in code (tests, benchmarks).
Particles fill_rectangle(const kern::GridGeom& g, int ppc, const Box& box, double rho0, const Vector& v,
                         std::uint8_t body);

}  // namespace SMPM_NS
