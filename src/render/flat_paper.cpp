#include "hattr/render/flat_paper.hpp"

#include <algorithm>

namespace hattr::render {

double normalForce(const SurfaceContactParams& params, double penetration_m, double penetration_rate_m_per_s) noexcept {
  if (penetration_m <= 0.0) return 0.0;
  return std::max(0.0, params.stiffness_N_per_m * penetration_m + params.damping_N_s_per_m * penetration_rate_m_per_s);
}

void FlatPaper::render(const PenState& pen, double /*dt_s*/, ContactForces& out) noexcept {
  const double penetration = -pen.p_WT.z();
  const double normal = normalForce(params_, penetration, -pen.v_WT.z());
  out.in_contact = penetration > 0.0;
  out.f_on_pen_W = Vec3(0.0, 0.0, normal);
  out.f_on_paper_W = -out.f_on_pen_W;
}

}  // namespace hattr::render
