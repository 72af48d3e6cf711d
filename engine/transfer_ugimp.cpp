// The transfers of a step with the ugimp shape function (engine/transfer_step.hpp).
#include "engine/transfer_step_impl.hpp"

namespace smpm::transfer {
SMPM_TRANSFER_INSTANTIATE(kern::UGIMP)
}  // namespace smpm::transfer
