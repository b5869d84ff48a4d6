#pragma once
/// The simplest world: a flat sheet of paper at z = 0 as a spring–damper surface. The
/// normal force K·δ + C·δ̇ (δ = penetration) acts along +z and never pulls the pen into the
/// paper. No friction, texture or relief: those are the full paper renderer's.

#include "hattr/core/pen_state.hpp"
#include "hattr/core/world_renderer.hpp"

namespace hattr::render {

struct SurfaceContactParams {
  double stiffness_N_per_m = 800.0;   ///< K
  double damping_N_s_per_m = 1.0;     ///< C
};

/// Normal force magnitude for penetration δ [m] (> 0 inside) and its rate δ̇ [m/s]:
/// max(0, K·δ + C·δ̇) inside, 0 outside. Servo-thread safe.
double normalForce(const SurfaceContactParams& params, double penetration_m, double penetration_rate_m_per_s) noexcept;

class FlatPaper final : public WorldRenderer {
 public:
  explicit FlatPaper(SurfaceContactParams params = {}) : params_(params) {}
  void render(const PenState& pen, double dt_s, ContactForces& out) noexcept override;

 private:
  SurfaceContactParams params_;
};

}  // namespace hattr::render
