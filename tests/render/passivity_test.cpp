// The pen, held at rest by a hand pressing it on the paper, through the real servo loop and
// the simulated device: no energy may appear over 60 s of simulated time.

#include <gtest/gtest.h>

#include "hattr/device/simulated_device.hpp"
#include "hattr/render/paper_renderer.hpp"
#include "hattr/servo/servo_loop.hpp"

namespace hattr::render {
namespace {

struct EnergyTrace {
  double max_early_J = 0.0;  // kinetic energy, seconds 1–2
  double max_late_J = 0.0;   // kinetic energy, seconds 50–60
  double final_J = 0.0;
  double max_late_depth_m = 0.0;
};

EnergyTrace holdPenOnPaper(const PaperParams& paper_params, const device::SimulatedPenParams& pen_params) {
  device::StillHand hand(device::HandCommand{.p_target_W = Vec3(0.003, -0.002, 0.0), .press_N = 1.0, .pen_down = true});
  device::SimulatedPenParams pen = pen_params;
  pen.start_position_W = Vec3(0.003, -0.002, 0.001);
  device::SimulatedDevice device(pen, &hand);
  PaperRenderer paper(paper_params, HeightField::paperGrain(0.02, 64, 1e-5, 5e-4, 9));
  servo::ServoLoop loop(device, servo::ServoConfig{});
  loop.setWorld(&paper);
  EnergyTrace trace;
  TickSample drained;
  for (int tick = 0; tick < 60'000; ++tick) {
    loop.runSimulated(1);
    while (loop.samples().tryPop(drained)) {
    }
    const double t = tick * 1e-3;
    const double kinetic = 0.5 * pen.mass_kg * device.trueVelocity().squaredNorm();
    if (t >= 1.0 && t < 2.0) trace.max_early_J = std::max(trace.max_early_J, kinetic);
    if (t >= 50.0) {
      trace.max_late_J = std::max(trace.max_late_J, kinetic);
      trace.max_late_depth_m = std::max(trace.max_late_depth_m, -device.truePosition().z());
    }
    trace.final_J = kinetic;
  }
  return trace;
}

TEST(Passivity, PenPressedOnThePaperGainsNoEnergyOver60Seconds) {
  PaperParams params;  // defaults: textured friction, grain relief, passive on the default pen
  const EnergyTrace trace = holdPenOnPaper(params, device::SimulatedPenParams{});
  std::cout << "[ info ] kinetic energy: s1–2 max " << trace.max_early_J << " J, s50–60 max " << trace.max_late_J
            << " J, final " << trace.final_J << " J\n";
  EXPECT_LE(trace.max_late_J, trace.max_early_J);
  EXPECT_LT(trace.final_J, 1e-12);
  // Resting depth is about (press·sin θ)/K = 1.44 mm at the default 600 N/m.
  EXPECT_LT(trace.max_late_depth_m, 2e-3);
}

TEST(Passivity, TheSameCheckCatchesANonPassivePaper) {
  // Far beyond Colgate's bound (K·T/2 = 2.5 N·s/m against b = 0.05): the check must fail.
  PaperParams params;
  params.contact = {.stiffness_N_per_m = 5000.0, .damping_N_s_per_m = 0.0};
  device::SimulatedPenParams pen;
  pen.damping_N_s_per_m = 0.05;
  pen.hand.damping_N_s_per_m = 0.0;
  const EnergyTrace trace = holdPenOnPaper(params, pen);
  EXPECT_GT(trace.final_J, 1e-9);
}

}  // namespace
}  // namespace hattr::render
