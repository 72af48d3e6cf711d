// The constitutive updates of the EOS models at even (share 0) or odd (share 1) index in
// EosModel (see engine/material.hpp).
#include "kernels/dimension.hpp"
#include "engine/material.hpp"

namespace SMPM_NS {

template const ConstitutiveFn* constitutive_share<1>();

}  // namespace SMPM_NS
