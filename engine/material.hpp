// A material is assembled from parts chosen by name: an equation of state (pressure), a
// strength model (deviatoric stress), and thermal data (temperature, heating, conduction).
// with_material() maps the run-time choice onto the templated constitutive kernel, so a scene
// pays only for the parts it uses.
#pragma once
#include <string>
#include <vector>

#include "kernels/constitutive.hpp"

namespace smpm {

enum class EosKind { Linear, MieGruneisen };
enum class StrengthKind { None, Elastic, VonMises };
enum class TemperatureKind { Isentrope, Simple };

struct Material {
  std::string name;
  EosKind eos = EosKind::Linear;
  StrengthKind strength = StrengthKind::Elastic;
  double rho0 = 0.0;   // reference density [kg/m^3]
  double E = 0.0;      // Young's modulus [Pa]
  double nu = 0.0;     // Poisson's ratio [-]
  // Mie-Grueneisen
  double c0 = 0.0;      // bulk sound speed [m/s]
  double s = 0.0;       // Hugoniot slope dUs/dup [-]
  double gamma0 = 0.0;  // Grueneisen gamma at rho0 [-]
  // Tension limit (spall): a point whose pressure would fall below -spall_strength has
  // fractured: no pressure and no deviatoric stress until it is compressed again. 0: none.
  double spall_strength = 0.0;  // [Pa]
  // von Mises
  double Y0 = 0.0;      // initial yield stress [Pa]
  double H = 0.0;       // linear hardening modulus [Pa]: Y = Y0 + H eps_p
  // thermal
  double cv = 0.0;             // specific heat [J/(kg K)]
  double conductivity = 0.0;   // thermal conductivity [W/(m K)]
  double T0 = 300.0;           // initial temperature [K]
  double heat_fraction = 1.0;  // fraction of plastic work that heats (the rest is stored)
  TemperatureKind temperature = TemperatureKind::Isentrope;

  double shear_modulus() const { return E / (2.0 * (1.0 + nu)); }
  // Bulk modulus at rho0: from E and nu for the linear EOS, rho0 c0^2 for Mie-Grueneisen.
  double bulk_modulus() const {
    return eos == EosKind::MieGruneisen ? rho0 * c0 * c0 : E / (3.0 * (1.0 - 2.0 * nu));
  }
  bool needs_energy() const { return eos == EosKind::MieGruneisen; }
  bool plastic() const { return strength == StrengthKind::VonMises; }
  // Elastic strain energy per unit volume of a stress state (for materials without an energy
  // field: linear EOS, elastic or no strength).
  double strain_energy_density(double sxx, double syy, double sxy, double p) const {
    const double szz = -(sxx + syy);
    const double G = shear_modulus();
    return (G > 0 ? (sxx * sxx + syy * syy + szz * szz + 2.0 * sxy * sxy) / (4.0 * G) : 0.0) +
           p * p / (2.0 * bulk_modulus());
  }
  kern::MieGruneisenEos mie_gruneisen() const { return kern::MieGruneisenEos::make(rho0, c0, s, gamma0); }
};

// Names accepted in case files, for error messages.
inline const std::vector<std::string>& eos_names() {
  static const std::vector<std::string> v{"linear", "mie_gruneisen"};
  return v;
}
inline const std::vector<std::string>& strength_names() {
  static const std::vector<std::string> v{"none", "elastic", "von_mises"};
  return v;
}

// Calls f(eos, strength_part) with the strength part of `mat`.
template <class Eos, class F>
decltype(auto) with_strength(const Material& mat, const Eos& eos, F&& f) {
  switch (mat.strength) {
    case StrengthKind::None: return f(eos, kern::NoStrength{});
    case StrengthKind::Elastic: return f(eos, kern::ElasticStrength{mat.shear_modulus()});
    case StrengthKind::VonMises: break;
  }
  return f(eos, kern::VonMisesStrength{mat.shear_modulus(), mat.Y0, mat.H});
}

// Calls f(eos_part, strength_part) with the parts of `mat`.
template <class F>
decltype(auto) with_material(const Material& mat, F&& f) {
  if (mat.eos == EosKind::MieGruneisen) return with_strength(mat, mat.mie_gruneisen(), f);
  return with_strength(mat, kern::LinearEos{mat.rho0, mat.bulk_modulus()}, f);
}

// kern::constitutive_block with the parts of `mat`: the constitutive update of points
// [first, last). Compiled once per EOS part (engine/constitutive_linear.cpp,
// engine/constitutive_mie_gruneisen.cpp), apart from the engine's other code, so that the
// vectorized loops of every combination build in parallel and an edit elsewhere does not
// rebuild them.
kern::ConstitutiveResult constitutive_linear(const Material& mat, const kern::ParticleView& P,
                                             const kern::ConstitutiveState& S, const kern::Gradient& L,
                                             std::size_t first, std::size_t last, const kern::ConstitutiveParams& q,
                                             kern::Selection sel);
kern::ConstitutiveResult constitutive_mie_gruneisen(const Material& mat, const kern::ParticleView& P,
                                                    const kern::ConstitutiveState& S, const kern::Gradient& L,
                                                    std::size_t first, std::size_t last,
                                                    const kern::ConstitutiveParams& q, kern::Selection sel);
inline kern::ConstitutiveResult constitutive_block(const Material& mat, const kern::ParticleView& P,
                                                   const kern::ConstitutiveState& S, const kern::Gradient& L,
                                                   std::size_t first, std::size_t last,
                                                   const kern::ConstitutiveParams& q, kern::Selection sel) {
  return mat.eos == EosKind::MieGruneisen ? constitutive_mie_gruneisen(mat, P, S, L, first, last, q, sel)
                                          : constitutive_linear(mat, P, S, L, first, last, q, sel);
}

}  // namespace smpm
