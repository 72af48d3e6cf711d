// The number of axes the engine is built for. The engine's sources are compiled once per
// dimension (CMakeLists.txt: smpm_engine2 with SMPM_DIM=2, smpm_engine3 with SMPM_DIM=3), each
// build inside its own inline namespace, smpm::d2 or smpm::d3, so that both link into one
// driver; the driver picks one by the case's [grid] dimension (engine/driver.hpp, Engine<D>).
// The kernels are templates on D; kern::kDim is the D they are instantiated for.
#pragma once

#ifndef SMPM_DIM
#define SMPM_DIM 2
#endif
#if SMPM_DIM == 2
#define SMPM_DIM_NS d2
#elif SMPM_DIM == 3
#define SMPM_DIM_NS d3
#else
#error "SMPM_DIM must be 2 or 3"
#endif
// The engine's namespace for this dimension: namespace SMPM_NS { ... } and SMPM_NS::kern.
#define SMPM_NS smpm::inline SMPM_DIM_NS
