// The transfers of a step with the quadratic shape function (engine/transfer_step.hpp).
#include "engine/transfer_step_impl.hpp"

namespace smpm::transfer {
SMPM_TRANSFER_INSTANTIATE(kern::QuadraticBSpline)
}  // namespace smpm::transfer
