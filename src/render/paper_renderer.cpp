#include "hattr/render/paper_renderer.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::render {

std::vector<std::string> clampToDevice(PaperParams& params, const DeviceLimits& limits, double rate_hz) {
  std::vector<std::string> changes =
      clampImpedance(params.contact.stiffness_N_per_m, params.contact.damping_N_s_per_m,
                     {.stiffness_name = "paper stiffness", .damping_name = "paper damping"}, limits, rate_hz);
  double no_damping = 0.0;
  for (auto& line : clampImpedance(params.tangential_stiffness_N_per_m, no_damping,
                                   {.stiffness_name = "friction proxy stiffness", .damping_name = "-"}, limits, rate_hz)) {
    changes.push_back(std::move(line));
  }
  return changes;
}

void validatePaperParams(const PaperParams& p) {
  const auto check = [](double value, double lo, double hi, const char* key) {
    HATTR_THROW_UNLESS(std::isfinite(value) && value >= lo && value <= hi, "{}: expected a number in [{}, {}], got {}",
                       key, lo, hi, value);
  };
  check(p.contact.stiffness_N_per_m, 1.0, 1e6, "paper.stiffness_N_per_m");
  check(p.contact.damping_N_s_per_m, 0.0, 1e4, "paper.damping_N_s_per_m");
  check(p.tangential_stiffness_N_per_m, 1.0, 1e6, "paper.tangential_stiffness_N_per_m");
  check(p.friction.static_coefficient, 0.0, 2.0, "friction.static");
  check(p.friction.dynamic_coefficient, 0.0, p.friction.static_coefficient, "friction.dynamic (<= friction.static)");
  check(p.texture.sigma, 0.0, 1.0, "texture.sigma");
  check(p.texture.correlation_length_m, 1e-6, 0.1, "texture.correlation_length_m");
  check(p.writing_angle_rad, 0.1, 1.5707963267948966, "writing angle [rad]");
}

PaperRenderer::PaperRenderer(const PaperParams& params, HeightField relief)
    : params_(params), relief_(std::move(relief)) {
  validatePaperParams(params_);
  if (params_.texture.sigma > 0.0) {
    texture_ = sharedGaussianField(
        GaussianFieldParams{.correlation_length_m = params_.texture.correlation_length_m, .seed = params_.texture.seed});
  }
}

void PaperRenderer::reset() noexcept {
  in_contact_ = false;
  detail_ = {};
}

std::pair<double, double> PaperRenderer::frictionAt(double x_m, double y_m) const noexcept {
  const double n = texture_ ? texture_->at(x_m, y_m) : 0.0;
  const double mu_s = std::max(0.0, params_.friction.static_coefficient + params_.texture.sigma * n);
  const double mu_d = std::clamp(params_.friction.dynamic_coefficient + params_.texture.sigma * n, 0.0, mu_s);
  return {mu_s, mu_d};
}

void PaperRenderer::render(const PenState& pen, double /*dt_s*/, ContactForces& out) noexcept {
  // Penetration below the mesh, measured along the force-shaded normal.
  const SurfacePoint surface = relief_.surfaceAt(pen.p_WT.x(), pen.p_WT.y());
  const Vec3& n = surface.normal_W;
  const double penetration = (surface.height_m - pen.p_WT.z()) * n.z();
  // On a table (a planar pen): touching while the device says the pen is on the paper (z = 0, not
  // lifted) and it reads a press; the tip then lies on the surface (it cannot sink into it).
  const bool on_table = params_.normal_from_pressure;
  const bool touching =
      on_table ? pen.has_pressure && pen.pressure_raw > 0.0 && pen.p_WT.z() <= 0.0 : penetration > 0.0;
  if (!touching) {
    in_contact_ = false;
    detail_ = {.proxy_W = pen.p_WT};
    out = {};
    return;
  }

  // Normal reaction K·δ + C·δ̇, never pulling the pen into the paper; on a table, the press.
  const double normal = on_table ? pen.pressure_raw : normalForce(params_.contact, penetration, -pen.v_WT.dot(n));

  const Vec3 tip = on_table ? Vec3(pen.p_WT.x(), pen.p_WT.y(), surface.height_m) : pen.p_WT;

  // The god-object proxy: on touch-down it sits on the surface above the tip.
  if (!in_contact_) {
    detail_.proxy_W = Vec3(pen.p_WT.x(), pen.p_WT.y(), surface.height_m);
    detail_.sliding = false;
    in_contact_ = true;
  }
  const auto [mu_s, mu_d] = frictionAt(detail_.proxy_W.x(), detail_.proxy_W.y());

  // Friction: a spring from the tip to the proxy in the tangent plane. It sticks inside the
  // static cone μs·Fn; once it breaks loose it slides on the dynamic cone μd·Fn, dragging
  // the proxy behind the tip, until the pull drops inside the dynamic cone again.
  const double kt = params_.tangential_stiffness_N_per_m;
  Vec3 offset = detail_.proxy_W - tip;
  offset -= offset.dot(n) * n;
  Vec3 friction = kt * offset;
  const double pull = friction.norm();
  // (A pen that stops while sliding leaves the pull on the dynamic cone up to rounding; the
  // relative margin makes it stick, as it should.)
  const double limit = detail_.sliding ? mu_d * normal * (1.0 + 1e-9) : mu_s * normal;
  detail_.sliding = pull > limit;
  if (detail_.sliding) {
    friction *= mu_d * normal / pull;
    const Vec3 proxy = tip + friction / kt;
    detail_.proxy_W = Vec3(proxy.x(), proxy.y(), relief_.heightAt(proxy.x(), proxy.y()));
  }

  // θ from the device's tilt, else the configured writing angle: F_r = F·sin θ.
  const double theta = pen.has_tilt && pen.altitude_rad > 0.05 ? pen.altitude_rad : params_.writing_angle_rad;
  detail_.normal_N = normal;
  detail_.axial_N = normal / altitude_sine_.of(theta);
  detail_.mu_static = mu_s;
  detail_.mu_dynamic = mu_d;

  out.in_contact = true;
  out.f_on_pen_W = normal * n + friction;
  out.f_on_paper_W = -out.f_on_pen_W;
  if (on_table) out.f_on_pen_W.z() = 0.0;  // the table gives the normal itself
}

}  // namespace hattr::render
