// The constitutive update for materials with the Mie-Grueneisen EOS part (see engine/material.hpp).
#include "engine/material.hpp"

namespace smpm {

kern::ConstitutiveResult constitutive_mie_gruneisen(const Material& mat, const kern::ParticleView& P,
                                                    const kern::ConstitutiveState& S, const kern::Gradient& L,
                                                    std::size_t first, std::size_t last,
                                                    const kern::ConstitutiveParams& q, kern::Selection sel) {
  return with_strength(mat, mat.mie_gruneisen(), [&](const auto& eos, const auto& str) {
    return kern::constitutive_block(P, S, L, first, last, q, eos, str, sel);
  });
}

}  // namespace smpm
