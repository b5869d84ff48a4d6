#pragma once
// Simulated writers for the library's tests and benchmarks: each writer's "signature" is a
// smooth curve of their own (three harmonics per axis with their own amplitudes and phases, a
// pressure rhythm, a pen tilt), and
// each recording of it varies a little (amplitude, timing, noise) from a seed. Two strokes with
// a lift between, as a tablet records them (pen-up samples absent, one marked lift sample).

#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "hattr/core/haptic_profile.hpp"

namespace hattr::test {

inline HapticProfile syntheticSignature(int writer, int take, std::uint64_t seed = 7, bool tilt = true) {
  std::mt19937_64 person(1000003u * static_cast<std::uint64_t>(writer) + 17u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double ax[3], ay[3], px[3], py[3];
  for (int k = 0; k < 3; ++k) {
    ax[k] = u(person) / (1.0 + k), ay[k] = u(person) / (1.0 + k);
    px[k] = 6.283 * u(person), py[k] = 6.283 * u(person);
  }
  const double fp = 2.0 + 3.0 * u(person), base_N = 0.6 + 0.6 * u(person);
  const double altitude = 0.8 + 0.5 * u(person), azimuth = 1.5 + 1.5 * u(person);
  const double duration = 1.2 + 0.8 * u(person);
  std::mt19937_64 rec(seed * 7919u + 31u * static_cast<std::uint64_t>(writer) + static_cast<std::uint64_t>(take));
  std::normal_distribution<double> n(0.0, 1.0);
  const double amp = 0.02 * (1.0 + 0.03 * n(rec));
  const double speed = 1.0 + 0.04 * n(rec);
  const double T = duration * speed;
  HapticProfile p({.subject = "W" + std::to_string(writer), .skill = "signature", .device = "synthetic",
                   .source = "test", .nominal_rate_hz = 100.0},
                  RawChannels{.pressure = true, .tilt = tilt});
  const int samples = static_cast<int>(T * 100.0);
  const int lift_at = samples / 2;
  for (int i = 0; i < samples; ++i) {
    const double s = static_cast<double>(i) / static_cast<double>(samples - 1);  // progress 0..1
    Sample x;
    x.t_s = 0.01 * i + (i > lift_at ? 0.1 : 0.0);  // a 100 ms lift half-way
    double cx = 0.0, cy = 0.0;
    for (int k = 0; k < 3; ++k) {
      cx += ax[k] * std::sin(6.283 * (k + 1) * s + px[k]);
      cy += ay[k] * std::sin(6.283 * (k + 1) * s + py[k]);
    }
    x.p_WT = Vec3(amp * cx + 2e-4 * n(rec), amp * cy + 2e-4 * n(rec), 0);
    const double press = base_N * (1.0 + 0.4 * std::sin(6.283 * fp * s)) + 0.02 * n(rec);
    x.f_user_W = Vec3(0, 0, -press);
    x.pressure_raw = press * 500.0;
    x.pen_down = x.in_contact = i != lift_at;
    if (i == lift_at) x.f_user_W.setZero(), x.pressure_raw = 0.0;
    x.tilt_altitude_rad = altitude + 0.02 * n(rec);
    x.tilt_azimuth_rad = azimuth + 0.02 * n(rec);
    p.append(x);
  }
  std::vector<Sample> samples_copy = p.samples();
  fillVelocityByFiniteDifferences(samples_copy);
  HapticProfile out(p.metadata(), p.rawChannels());
  for (const auto& s : samples_copy) out.append(s);
  return out;
}

}  // namespace hattr::test
