#include "studio_test_support.hpp"

#include <unistd.h>

#include <cmath>

#include "hattr/device/hand.hpp"

namespace hattr::studio::test {

HapticProfile figureEightScript(double duration_s, double normal_N, Vec3 centre) {
  constexpr double kTwoPi = 6.283185307179586;
  HapticProfile script(ProfileMetadata{.subject = "script", .skill = "eight"});
  const int n = static_cast<int>(std::lround(duration_s * 200.0));
  for (int i = 0; i <= n; ++i) {
    const double t = duration_s * i / n;
    const double w = kTwoPi / duration_s;
    Sample s;
    s.t_s = t;
    s.p_WT = centre + Vec3(0.020 * std::sin(w * t), 0.015 * std::sin(2.0 * w * t), 0.0);
    s.v_WT = Vec3(0.020 * w * std::cos(w * t), 0.030 * w * std::cos(2.0 * w * t), 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -normal_N);
    s.pen_down = true;
    s.in_contact = true;
    script.append(s);
  }
  return script;
}

render::WorldConfig flatWorld() {
  render::WorldConfig world;
  world.relief.kind = render::ReliefConfig::Kind::kFlat;
  return world;
}

HapticProfile recordExpert(session::TrialEnvironment& environment, double duration_s) {
  const HapticProfile script = figureEightScript(duration_s);
  device::ProfileHandScript hand(script);
  session::TrialSetup setup;
  setup.duration_s = duration_s + 0.1;
  setup.metadata.subject = "expert";
  setup.metadata.skill = "eight";
  return session::runTrial(environment, setup, hand).profile;
}

std::string smallStudyJson(const std::string& modes, double rest_s, const std::string& subjects,
                           const std::string& relief) {
  // Kept out of the test files: moc does not parse raw string literals.
  return R"({"format": "hattr-study/1", "name": "studio test", "skill": "eight",)"
         R"("experts": {"eight": "expert.csv"}, "modes": )" +
         modes + R"(, "protocol": {"training_trials": 1, "recall_trials": 1, "rest_s": )" + std::to_string(rest_s) +
         R"(, "tail_s": 0.2}, "order": {"kind": "fixed"}, "device": "sim://pen",)"
         R"("world": {"relief": {"kind": ")" +
         relief +
         R"("}}, "rate_hz": 1000, "indexing": "time",)"
         R"("subjects": )" +
         subjects + "}";
}

std::filesystem::path freshTempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("hattr-studio-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace hattr::studio::test
