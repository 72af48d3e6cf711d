// A dense column onto the rigid wall, run from a case file of cases/verify/ and measured against
// the exact Rankine-Hugoniot state of its EOS (docs/model.md, "Exact checks"). Defined once per
// dimension (tests/column_impact.cpp compiled with SMPM_DIM = 2 and 3), so that one test can run
// the same column in 2D and in 3D.
#pragma once
#include <string>
#include <vector>

namespace smpm::verify {

struct ColumnImpact {
  double Us = 0;                 // shock speed relative to the material ahead [m/s]
  double wall = 0;               // mean wall stress over the second half [Pa]
  double P = 0, rho = 0, T = 0;  // means behind the shock [Pa, kg/m^3, K]
  double energy_error = 0;       // (E_end - E_0) / E_0
  double energy_residual = 0;    // (E_end + removed at walls and contacts - E_0) / E_0
  double precursor_speed = 0, precursor_amplitude = 0;  // [m/s], [Pa]
  double exact_Us = 0, exact_P = 0, exact_rho = 0, exact_T = 0;  // the exact state
  bool finite = true;
  long particles = 0, steps = 0;
};

// The column of cases/verify/<file> with the overrides ("section.key=value").
template <int D>
ColumnImpact column_impact(const std::string& file, const std::vector<std::string>& overrides = {});

}  // namespace smpm::verify
