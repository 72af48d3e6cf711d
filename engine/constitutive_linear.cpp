// The constitutive update for materials with the linear EOS part (see engine/material.hpp).
#include "engine/material.hpp"

namespace smpm {

kern::ConstitutiveResult constitutive_linear(const Material& mat, const kern::ParticleView& P,
                                             const kern::ConstitutiveState& S, const kern::Gradient& L,
                                             std::size_t first, std::size_t last, const kern::ConstitutiveParams& q,
                                             kern::Selection sel) {
  return with_strength(mat, kern::LinearEos{mat.rho0, mat.bulk_modulus()}, [&](const auto& eos, const auto& str) {
    return kern::constitutive_block(P, S, L, first, last, q, eos, str, sel);
  });
}

}  // namespace smpm
