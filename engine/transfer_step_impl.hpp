// Definitions of engine/transfer_step.hpp, included by engine/transfer_<shape>.cpp only, each of
// which instantiates them for its shape.
#pragma once
#include "kernels/dimension.hpp"
#include "engine/transfer_step.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/transfer.hpp"

namespace SMPM_NS::transfer {

template <class S>
void scatter(const StepArgs& a) {
  using kern::P2GWhat;
  kern::clear_grid(a.g, a.box, a.G, true);
  const bool apic = a.cfg.transfer == Transfer::APIC;
  const double lp = a.cfg.ugimp_lp;
  if (a.cfg.contact) {  // two bodies: normals from mass gradients
    if (apic) kern::p2g_colored<S, true, P2GWhat::All, true>(a.g, a.G, a.P, a.order, a.cell_start, lp);
    else kern::p2g_colored<S, false, P2GWhat::All, true>(a.g, a.G, a.P, a.order, a.cell_start, lp);
  } else if (a.cfg.fields() > 1) {  // void faces: a weld needs the volume only
    if (apic) kern::p2g_colored<S, true, P2GWhat::All, true, false>(a.g, a.G, a.P, a.order, a.cell_start, lp);
    else kern::p2g_colored<S, false, P2GWhat::All, true, false>(a.g, a.G, a.P, a.order, a.cell_start, lp);
  } else {
    if (apic) kern::p2g_colored<S, true, P2GWhat::All>(a.g, a.G, a.P, a.order, a.cell_start, lp);
    else kern::p2g_colored<S, false, P2GWhat::All>(a.g, a.G, a.P, a.order, a.cell_start, lp);
  }
}

template <class S>
void gather_velocity(const StepArgs& a, const kern::G2PParams& q) {
  using kern::G2PWhat;
  if (a.cfg.transfer == Transfer::FLIP) kern::g2p<S, true, G2PWhat::Velocity>(a.g, a.G, a.P, a.n, q);
  else kern::g2p<S, false, G2PWhat::Velocity, true>(a.g, a.G, a.P, a.n, q);  // heating, as USL's
}

template <class S>
void scatter_momentum(const StepArgs& a, double lp) {
  using kern::P2GWhat;
  kern::clear_grid(a.g, a.box, a.G, false);
  if (a.cfg.transfer == Transfer::APIC)
    kern::p2g_colored<S, true, P2GWhat::Momentum>(a.g, a.G, a.P, a.order, a.cell_start, lp);
  else
    kern::p2g_colored<S, false, P2GWhat::Momentum>(a.g, a.G, a.P, a.order, a.cell_start, lp);
}

template <class S>
kern::ConstitutiveResult gather_and_update_stress(const StepArgs& a, const kern::G2PParams& q, double* scratch,
                                                  BlockUpdate update) {
  using kern::G2PWhat;
  using Result = kern::ConstitutiveResult;
  const bool flip = a.cfg.transfer == Transfer::FLIP;
  if (a.cfg.scheme == Scheme::MUSL)
    return kern::g2p_blocks<S, false, G2PWhat::PositionGradient, false, false, Result>(a.g, a.G, a.P, a.n, q, scratch,
                                                                                      update);
  // USL: always the heating gather (a scene without an energy field heats a scratch array:
  // Simulation::transfer_args); the one without heating would be a fourth of these files'
  // compile time for scenes that are not the study's
  auto usl = [&](auto contact) {  // kern::g2p_particle's Contact: 0, 1 (void faces), 2 (two bodies)
    constexpr int C = decltype(contact)::value;
    if (flip) return kern::g2p_blocks<S, true, G2PWhat::Full, true, C, Result>(a.g, a.G, a.P, a.n, q, scratch, update);
    return kern::g2p_blocks<S, false, G2PWhat::Full, true, C, Result>(a.g, a.G, a.P, a.n, q, scratch, update);
  };
  if (a.cfg.contact) return usl(std::integral_constant<int, 2>{});
  if (a.cfg.fields() > 1) return usl(std::integral_constant<int, 1>{});
  return usl(std::integral_constant<int, 0>{});
}

}  // namespace SMPM_NS::transfer

// One shape's instantiation, inside namespace smpm::transfer: SMPM_TRANSFER_INSTANTIATE(kern::Linear).
#define SMPM_TRANSFER_INSTANTIATE(SHAPE)                                     \
  template void scatter<SHAPE>(const StepArgs&);                              \
  template void gather_velocity<SHAPE>(const StepArgs&, const kern::G2PParams&); \
  template void scatter_momentum<SHAPE>(const StepArgs&, double);             \
  template kern::ConstitutiveResult gather_and_update_stress<SHAPE>(const StepArgs&, const kern::G2PParams&, double*, \
                                                                    BlockUpdate);
