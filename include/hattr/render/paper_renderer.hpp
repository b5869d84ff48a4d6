#pragma once
/// The virtual writing testbed (the paper's section 3) as the world the servo loop renders:
/// a spring–damper paper surface over a height-field mesh, static and dynamic (Coulomb)
/// friction with stick–slip through a god-object proxy, and a Gaussian stochastic friction
/// texture. Parameters are checked against what the device renders stably at its rate and
/// clamped with a report. See docs/rendering.md.

#include <memory>
#include <string>
#include <vector>

#include "hattr/core/pen_state.hpp"
#include "hattr/core/world_renderer.hpp"
#include "hattr/core/device_limits.hpp"
#include "hattr/core/passivity.hpp"
#include "hattr/core/sine_memo.hpp"
#include "hattr/render/flat_paper.hpp"
#include "hattr/render/gaussian_field.hpp"
#include "hattr/render/height_field.hpp"

namespace hattr::render {

struct FrictionParams {
  double static_coefficient = 0.30;   ///< μs
  double dynamic_coefficient = 0.20;  ///< μd (<= μs)
};

struct TextureParams {
  double sigma = 0.03;                    ///< standard deviation of μ over the paper (0: no texture)
  double correlation_length_m = 5e-4;     ///< ℓ of the texture field
  std::uint64_t seed = 1;
};

struct PaperParams {
  SurfaceContactParams contact{.stiffness_N_per_m = 600.0, .damping_N_s_per_m = 0.1};
  double tangential_stiffness_N_per_m = 500.0;  ///< stiffness of the friction proxy's spring
  FrictionParams friction;
  TextureParams texture;
  double writing_angle_rad = 1.0471975511965976;  ///< θ when the device has no tilt (60°)
  /// How thick the paper (and its pad) is [m]: a tip deeper than this under the surface has
  /// fallen through it, a physical event of the trial (docs/realtime.md, "Physical events").
  /// The paper's spring still pushes back there; the recording is what says it happened.
  double thickness_m = 0.003;
  /// A planar device (2 DOF, the open pen): the real table holds the pen up, so the normal
  /// reaction is the pen's measured press (PenState::pressure_raw, newtons, while the device
  /// reports the tip on the paper, z <= 0, and not lifted), not a spring; the
  /// rendered force is the in-plane part (friction, texture, and the relief's tilt of the normal),
  /// while the force on the paper keeps the normal. Set from the device's limits (session), not
  /// from a world file.
  bool normal_from_pressure = false;
};

/// Clamps paper parameters to the device's passive bounds (hattr::clampImpedance). Returns
/// one line per change ("paper stiffness 3000 N/m -> 1000 N/m: ..."); empty when none.
std::vector<std::string> clampToDevice(PaperParams& params, const DeviceLimits& limits, double rate_hz);

/// What the renderer did at the last tick (for tests, the studio and analysis).
struct ContactDetail {
  bool sliding = false;          ///< the proxy slid (dynamic friction) rather than stuck
  double normal_N = 0.0;         ///< F_r, the normal reaction
  double axial_N = 0.0;          ///< F = F_r / sin θ, the force along the pen
  double mu_static = 0.0;        ///< μs at the proxy (texture included)
  double mu_dynamic = 0.0;       ///< μd at the proxy
  Vec3 proxy_W = Vec3::Zero();   ///< the god-object on the surface
};

class PaperRenderer final : public WorldRenderer {
 public:
  /// Takes the parameters as given (call clampToDevice first) and a height field (flat by
  /// default). Builds the texture field (allocation here). Throws InputError for values out
  /// of range (see docs/rendering.md).
  PaperRenderer(const PaperParams& params, HeightField relief = {});

  void render(const PenState& pen, double dt_s, ContactForces& out) noexcept override;
  void reset() noexcept override;

  [[nodiscard]] const ContactDetail& detail() const noexcept { return detail_; }
  [[nodiscard]] const PaperParams& params() const noexcept { return params_; }
  [[nodiscard]] const HeightField& relief() const noexcept { return relief_; }
  /// μs and μd at a place (texture included).
  [[nodiscard]] std::pair<double, double> frictionAt(double x_m, double y_m) const noexcept;

 private:
  PaperParams params_;
  HeightField relief_;
  std::shared_ptr<const CorrelatedGaussianField> texture_;  ///< sharedGaussianField: read only
  ContactDetail detail_;
  bool in_contact_ = false;
  SineMemo altitude_sine_;  ///< sin θ: the altitude changes seldom
};

/// Checks every parameter; throws InputError naming the first problem.
void validatePaperParams(const PaperParams& params);

}  // namespace hattr::render
