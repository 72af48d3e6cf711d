// Temperature from density and specific internal energy, and the Hugoniot of a material,
// both computed from the code's own EOS part (kern::MieGruneisenEos).
//
// Temperature (docs/model.md, "Heating and temperature"). Isentrope-referenced (default): the
// isentrope through (rho0, T0) has T_s(V) = T0 exp(gamma0 (1 - V/V0)) (rho Gamma constant) and
// energy e_s(V) from de = -P dV along it, integrated once (RK4, tabulated); then
// T = T_s(V) + (e - e_s(V)) / cv: cold compression energy is recoverable and does not heat.
// "simple": T = T0 + e / cv, which counts cold compression energy as heat (about twice the shock
// heating of dense Al at 1 km/s).
#pragma once
#include "kernels/dimension.hpp"
#include <vector>

#include "engine/material.hpp"

namespace SMPM_NS {

class Thermo {
 public:
  explicit Thermo(const Material& m);
  // [K]; `stored` [J/kg] is internal energy that is not heat (plastic work kept as cold work
  // when heat_fraction < 1).
  double temperature(double rho, double e, double stored = 0.0) const;
  double isentrope_energy(double rho) const;        // e_s [J/kg]
  double isentrope_temperature(double rho) const;   // T_s [K]
  // Range of the isentrope table in rho/rho0; outside it e_s is extrapolated linearly in eta.
  static constexpr double kEtaMin = -1.0, kEtaMax = 0.75;  // eta = 1 - rho0/rho

 private:
  Material m_;
  std::vector<double> es_;  // e_s at eta = kEtaMin + i d
  double gamma0_ = 0.0;     // Grueneisen gamma at rho0 of the EOS's Mie-Grueneisen form
  double rho_spall_ = 0.0;  // density where the cold pressure reaches -spall_strength (0: none)
  double d_ = 0.0;
};

// State behind a steady shock with particle-velocity jump up into material at rest at
// (rho0, e = 0), from the Rankine-Hugoniot relations and the code's EOS.
struct HugoniotState {
  double up = 0, Us = 0;   // [m/s]
  double P = 0;            // [Pa]
  double rho = 0;          // [kg/m^3]
  double e = 0;            // [J/kg] = up^2 / 2
  double T = 0;            // [K], isentrope-referenced
  double T_simple = 0;     // [K], T0 + e / cv
  // false: up is beyond what the EOS's Hugoniot reaches below 4 rho0 (the range of the isentrope
  // table, engine/thermo.cpp) or its singular compression; the state is then that of the largest
  // up reached, and callers must say so instead of reporting it as exact
  bool in_range = true;
};
HugoniotState hugoniot(const Material& m, double up);
// The same for a porous body of this porosity fully compacted by the shock: material at rest at
// (rho00 = (1 - porosity) rho0, P = 0, e = 0) jumps to a void-free state on the EOS,
// e = P (1/rho00 - 1/rho) / 2 (the P-alpha limit of complete compaction). Us - up is then the
// compaction front's speed in the frame of a wall that stopped the material. With a large
// Gruneisen parameter the compacted state is hot enough to lie below rho0 (the porous Hugoniot's
// anomaly); the root on the branch P > 0 nearest full density is returned. With gamma0 = 2
// (aluminium) porosity 0.5 is degenerate (P <= 0 everywhere: in_range false); near it the state
// sits at rho0 and the front is the snowplow speed up rho00 / (rho0 - rho00).
HugoniotState porous_hugoniot(const Material& m, double up, double porosity);

}  // namespace SMPM_NS
