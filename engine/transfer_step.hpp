// The transfers of one step (P2G scatter; G2P gather with the constitutive update behind it),
// for one shape function each. Simulation calls them through kern::with_shape. Each shape's
// transfers are compiled in a translation unit of their own (engine/transfer_<shape>.cpp): the
// variants (transfer, scheme, contact) are many vectorized loops per shape, and in one
// file they were most of the engine's compile time.
#pragma once
#include "kernels/dimension.hpp"
#include <cstddef>
#include <cstdint>

#include "engine/solver_config.hpp"
#include "kernels/constitutive.hpp"
#include "kernels/transfer.hpp"

namespace SMPM_NS::transfer {

// What the transfers of a step read: the grid, the particles and their binning, the settings.
struct StepArgs {
  const kern::GridGeom& g;
  kern::GridView G;
  // with velocity fields when contact is on (Simulation::pview); e is never null where the
  // gather heats (USL, MUSL's APIC velocity pass): a scratch array without an energy field
  kern::ParticleView P;
  std::size_t n;
  const std::uint32_t* order;
  const std::uint32_t* cell_start;
  kern::NodeBox box;
  const SolverConfig& cfg;
};

// The constitutive update of a block of points [first, last) with their gradient L, which the
// last gather pass calls behind each block (kern::g2p_blocks): a reference to the engine's
// callable, one indirect call per block of kern::kGatherBlock points.
struct BlockUpdate {
  const void* ctx;
  void (*fn)(const void*, std::size_t, std::size_t, const kern::Gradient&, kern::ConstitutiveResult&);
  template <class F>
  static BlockUpdate of(const F& f) {
    return {&f, [](const void* c, std::size_t first, std::size_t last, const kern::Gradient& L,
                   kern::ConstitutiveResult& acc) { (*static_cast<const F*>(c))(first, last, L, acc); }};
  }
  void operator()(std::size_t first, std::size_t last, const kern::Gradient& L, kern::ConstitutiveResult& acc) const {
    fn(ctx, first, last, L, acc);
  }
};

// P2G: mass, momentum, internal force (and the contact fields), colored and atomic-free. The
// grid inside the box is cleared first; the periodic fold is the caller's (Grid::fold).
template <class Shape>
void scatter(const StepArgs& a);
// MUSL's first pass: the particles' velocities from the updated grid velocity (APIC: the
// heating gather, as USL's).
template <class Shape>
void gather_velocity(const StepArgs& a, const kern::G2PParams& q);
// MUSL's remap: the grid's momentum cleared and scattered again from the particles' new
// velocities (the fold and the velocity from it are the caller's).
template <class Shape>
void scatter_momentum(const StepArgs& a, double lp);
// The pass that forms L (USL's gather; MUSL's position pass over the remapped velocity), with
// `update` (the constitutive update) behind each block. scratch: see kern::g2p_blocks.
template <class Shape>
kern::ConstitutiveResult gather_and_update_stress(const StepArgs& a, const kern::G2PParams& q, double* scratch,
                                                  BlockUpdate update);

}  // namespace SMPM_NS::transfer
