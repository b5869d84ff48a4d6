// Example 01: build a haptic profile in code, save it, read it back, look at a channel.
//   example_01_profile OUT.csv

#include <cmath>
#include <iostream>
#include <numbers>

#include "hattr/core/units.hpp"
#include "hattr/io/profile_csv.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: example_01_profile OUT.csv\n";
    return 2;
  }
  // A pen tracing a 20 mm circle in 2 s at 1 kHz while pressing with 1.5 N.
  hattr::HapticProfile profile({.subject = "example", .skill = "circle", .source = "examples/01_profile.cpp",
                                .created_utc = hattr::utcNowIso8601(), .nominal_rate_hz = 1000.0});
  const double radius_m = hattr::units::millimetresToMetres(10.0);
  for (int i = 0; i <= 2000; ++i) {
    hattr::Sample s;
    s.t_s = i * 1e-3;
    const double angle = std::numbers::pi * s.t_s;
    s.p_WT = hattr::Vec3(radius_m * std::cos(angle), radius_m * std::sin(angle), 0.0);
    s.v_WT = hattr::Vec3(-radius_m * std::numbers::pi * std::sin(angle), radius_m * std::numbers::pi * std::cos(angle), 0.0);
    s.f_user_W = hattr::Vec3(0.0, 0.0, -1.5);
    s.pen_down = s.in_contact = true;
    profile.append(s);
  }
  hattr::io::writeProfileCsv(profile, argv[1], hattr::Overwrite::kReplace);

  const hattr::HapticProfile back = hattr::io::readProfileCsv(argv[1]);
  const auto speed = back.channel(hattr::Channel::kSpeed);
  std::cout << "wrote and read " << back.size() << " samples over " << back.duration_s() << " s; "
            << "speed " << hattr::units::metresToMillimetres(speed.front()) << " mm/s; "
            << "identical: " << (back == profile ? "yes" : "no") << '\n';
  return back == profile ? 0 : 1;
}
