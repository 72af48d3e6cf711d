// A material is assembled from parts chosen by name: an equation of state (pressure),
// a strength model (deviatoric stress). with_material() maps the run-time choice onto the
// templated constitutive kernel, so a scene pays only for the parts it uses.
#pragma once
#include <string>
#include <vector>

#include "kernels/constitutive.hpp"

namespace smpm {

enum class EosKind { Linear };
enum class StrengthKind { Elastic };

struct Material {
  std::string name;
  EosKind eos = EosKind::Linear;
  StrengthKind strength = StrengthKind::Elastic;
  double rho0 = 0.0;   // reference density [kg/m^3]
  double E = 0.0;      // Young's modulus [Pa]
  double nu = 0.0;     // Poisson's ratio [-]

  double bulk_modulus() const { return E / (3.0 * (1.0 - 2.0 * nu)); }
  double shear_modulus() const { return E / (2.0 * (1.0 + nu)); }
  // Elastic strain energy per unit volume of a particle's stress state (linear elastic parts).
  double strain_energy_density(double sxx, double syy, double sxy, double p) const {
    const double szz = -(sxx + syy);
    return (sxx * sxx + syy * syy + szz * szz + 2.0 * sxy * sxy) / (4.0 * shear_modulus()) +
           p * p / (2.0 * bulk_modulus());
  }
};

// Names accepted in case files, for error messages.
inline const std::vector<std::string>& eos_names() {
  static const std::vector<std::string> v{"linear"};
  return v;
}
inline const std::vector<std::string>& strength_names() {
  static const std::vector<std::string> v{"elastic"};
  return v;
}

template <class F>
decltype(auto) with_material(const Material& mat, F&& f) {
  const kern::LinearEos eos{mat.rho0, mat.bulk_modulus()};
  const kern::ElasticStrength str{mat.shear_modulus()};
  return f(eos, str);
}

}  // namespace smpm
