// The constitutive updates of the EOS models at even (share 0) or odd (share 1) index in
// EosModel (see engine/material.hpp).
#include "engine/material.hpp"

namespace smpm {

template const ConstitutiveFn* constitutive_share<0>();

}  // namespace smpm
