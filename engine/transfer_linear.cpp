// The transfers of a step with the linear shape function (engine/transfer_step.hpp).
#include "kernels/dimension.hpp"
#include "engine/transfer_step_impl.hpp"

namespace SMPM_NS::transfer {
SMPM_TRANSFER_INSTANTIATE(kern::Linear)
}  // namespace SMPM_NS::transfer
