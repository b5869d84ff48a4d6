// The simulated expert: its script passes through the glyph's via points in writing order,
// starts and ends at rest, peaks at the documented handwriting speed, lifts the pen between
// strokes and presses with a smooth force plan; played on the simulated pen it gives the
// expert's haptic profile.

#include <cmath>
#include <map>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_database.hpp"
#include "sim/expert_checks.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::sim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

const Glyph& na() {
  static const Glyph glyph = loadGlyph(defaultDataDir() / "glyphs" / "na.json");
  return glyph;
}

const HapticProfile& naScript() {
  static const HapticProfile script = expertScript(na());
  return script;
}

using checks::penDownRuns;

/// Speed from the positions alone (central differences).
std::vector<double> finiteDifferenceSpeed(const HapticProfile& p) {
  std::vector<double> speed(p.size(), 0.0);
  for (std::size_t i = 1; i + 1 < p.size(); ++i) {
    speed[i] = (p[i + 1].p_WT - p[i - 1].p_WT).norm() / (p[i + 1].t_s - p[i - 1].t_s);
  }
  return speed;
}

double polylineLength(const std::vector<Vec2>& points) {
  double length = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  return length;
}

TEST(ExpertScript, PassesThroughEveryViaPointInWritingOrder) {
  HATTR_STARTS_NO_THREAD();
  checks::expectPassesEveryViaPointInOrder(na(), naScript());
}

TEST(ExpertScript, StartsAndEndsAtRestAndRestsAtTouchDownAndLiftOff) {
  HATTR_STARTS_NO_THREAD();
  const HapticProfile& script = naScript();
  EXPECT_EQ(script.samples().front().v_WT.norm(), 0.0);
  EXPECT_EQ(script.samples().back().v_WT.norm(), 0.0);
  const auto speed = finiteDifferenceSpeed(script);
  EXPECT_LT(speed[1], 1e-9);
  EXPECT_LT(speed[speed.size() - 2], 1e-9);
  for (const auto& [first, last] : penDownRuns(script)) {
    EXPECT_LT(script[first].v_WT.norm(), 1e-9);
    EXPECT_LT(script[last].v_WT.norm(), 1e-9);
  }
}

TEST(ExpertScript, PeakSpeedIsTheDocumentedHandwritingSpeed) {
  HATTR_STARTS_NO_THREAD();
  const auto speed = finiteDifferenceSpeed(naScript());
  const double peak = *std::max_element(speed.begin(), speed.end());
  EXPECT_GE(peak, 0.050);
  EXPECT_LE(peak, 0.100);
  EXPECT_NEAR(peak, ExpertConfig{}.peak_speed_m_per_s, 0.002);
  // A slower writer: the same path, a lower peak.
  ExpertConfig slow;
  slow.peak_speed_m_per_s = 0.055;
  const auto slow_speed = finiteDifferenceSpeed(expertScript(na(), slow));
  EXPECT_NEAR(*std::max_element(slow_speed.begin(), slow_speed.end()), 0.055, 0.002);
}

TEST(ExpertScript, VelocityChannelIsTheDerivativeOfThePath) {
  HATTR_STARTS_NO_THREAD();
  const HapticProfile& script = naScript();
  double worst = 0.0;
  for (std::size_t i = 1; i + 1 < script.size(); ++i) {
    const Vec3 fd = (script[i + 1].p_WT - script[i - 1].p_WT) / (script[i + 1].t_s - script[i - 1].t_s);
    worst = std::max(worst, (fd - script[i].v_WT).norm());
  }
  EXPECT_LT(worst, 0.002) << "within 2 mm/s everywhere (a central difference at 1 kHz)";
}

TEST(ExpertScript, LiftsThePenTwoToThreeMillimetresBetweenStrokes) {
  HATTR_STARTS_NO_THREAD();
  const HapticProfile& script = naScript();
  const auto runs = penDownRuns(script);
  ASSERT_EQ(runs.size(), 3u);
  for (const auto& [first, last] : runs) {
    for (std::size_t i = first; i <= last; ++i) ASSERT_EQ(script[i].p_WT.z(), 0.0) << "on the paper while pen down";
  }
  for (std::size_t gap = 0; gap + 1 < runs.size(); ++gap) {
    double highest = 0.0;
    for (std::size_t i = runs[gap].second + 1; i < runs[gap + 1].first; ++i) {
      EXPECT_FALSE(script[i].pen_down);
      EXPECT_GE(script[i].p_WT.z(), 0.0);
      highest = std::max(highest, script[i].p_WT.z());
    }
    EXPECT_GE(highest, 0.002);
    EXPECT_LE(highest, 0.003 + 1e-12);
  }
  EXPECT_FALSE(script.samples().front().pen_down);
  EXPECT_FALSE(script.samples().back().pen_down);
}

TEST(ExpertScript, StopsAtTheSharpCornerOfTheFirstStroke) {
  HATTR_STARTS_NO_THREAD();
  // The first stroke turns 90° at the top left: handwriting comes to rest at such corners.
  const HapticProfile& script = naScript();
  const Vec2 corner = na().strokes[0].points[1];
  std::size_t best = 0;
  for (std::size_t i = 0; i < script.size(); ++i) {
    if (script[i].pen_down && (script[i].p_WT.head<2>() - corner).norm() < (script[best].p_WT.head<2>() - corner).norm()) {
      best = i;
    }
  }
  EXPECT_LT(script[best].v_WT.norm(), 0.001);
}

TEST(ExpertScript, LongerMovementsTakeLongerButLessThanInProportion) {
  HATTR_STARTS_NO_THREAD();
  // Isochrony: a movement's duration grows as its length to the power β (0.5 by default).
  // Strokes 2 and 3 of ந are single movements; each pen-down run is its movement plus the
  // touch-down and lift-off rests.
  const ExpertConfig config;
  const auto runs = penDownRuns(naScript());
  const double rests_s = config.touch_down_s + config.lift_off_s;
  const auto movement_s = [&](std::size_t s) {
    return naScript()[runs[s].second].t_s - naScript()[runs[s].first].t_s - rests_s;
  };
  const double length_ratio = polylineLength(na().strokes[2].points) / polylineLength(na().strokes[1].points);
  ASSERT_GT(length_ratio, 2.0);
  EXPECT_NEAR(movement_s(2) / movement_s(1), std::pow(length_ratio, config.isochrony_exponent), 0.01);
}

TEST(ExpertScript, AxialForceRisesAtTouchDownHoldsAndFallsBeforeLiftOff) {
  HATTR_STARTS_NO_THREAD();
  const ExpertConfig config;
  const HapticProfile& script = naScript();
  const double plateau_N = config.axial_force_N * std::sin(config.altitude_rad);
  // The steepest step of a minimum-jerk rise over T is 1.875/T per second.
  const double ramp_s = std::min(config.touch_down_s, config.lift_off_s);
  const double max_step_N = plateau_N * 1.875 / ramp_s / config.rate_hz * 1.01;
  for (std::size_t i = 0; i < script.size(); ++i) {
    const double normal = -script[i].f_user_W.z();
    if (!script[i].pen_down) {
      EXPECT_EQ(normal, 0.0);
    }
    EXPECT_GE(normal, 0.0);
    EXPECT_LE(normal, plateau_N + 1e-12);
    if (i > 0) {
      EXPECT_LE(std::abs(normal + script[i - 1].f_user_W.z()), max_step_N) << "at t = " << script[i].t_s;
    }
    EXPECT_EQ(script[i].tilt_altitude_rad, config.altitude_rad);
    EXPECT_EQ(script[i].tilt_azimuth_rad, config.azimuth_rad);
  }
  // The first and last pen-down samples lie within one period of touch-down and lift-off, where
  // a minimum-jerk rise over T has reached at most 10·(dt/T)³ of its plateau.
  const double near_zero_N = plateau_N * 10.0 * std::pow(1.0 / (config.rate_hz * ramp_s), 3) * 1.01;
  for (const auto& [first, last] : penDownRuns(script)) {
    EXPECT_LE(-script[first].f_user_W.z(), near_zero_N) << "rises from zero at touch-down";
    EXPECT_NEAR(-script[(first + last) / 2].f_user_W.z(), plateau_N, 1e-12) << "holds mid-stroke";
    EXPECT_LE(-script[last].f_user_W.z(), near_zero_N) << "falls to zero at lift-off";
    // Moving only at the plateau: the pen rests while the force rises and falls.
    for (std::size_t i = first; i <= last; ++i) {
      if (script[i].v_WT.norm() > 1e-9) {
        ASSERT_NEAR(-script[i].f_user_W.z(), plateau_N, 1e-12);
      }
    }
  }
  EXPECT_TRUE(script.rawChannels().tilt);
  EXPECT_EQ(script.metadata().subject, "expert");
  EXPECT_EQ(script.metadata().skill, "na");
}

TEST(ExpertScript, RejectsABadConfigurationByName) {
  ExpertConfig config;
  config.peak_speed_m_per_s = -1.0;
  try {
    (void)expertScript(na(), config);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("peak_speed_m_per_s: expected a value in [0.01, 0.5] m/s, got -1"));
  }
  EXPECT_THROW((void)expertScript(Glyph{.name = "empty"}), InputError);
}

TEST(RecordExpert, PlaysTheScriptOnTheSimulatedPen) {
  const HapticProfile script = expertScript(loadGlyph(defaultDataDir() / "glyphs" / "loop.json"));
  render::WorldConfig world;
  world.relief.kind = render::ReliefConfig::Kind::kFlat;
  session::TrialEnvironment environment("sim://pen", world, 1000.0);
  const HapticProfile expert =
      recordExpert(environment, script, ProfileMetadata{.subject = "expert", .skill = "loop"});
  EXPECT_NEAR(static_cast<double>(expert.size()), script.duration_s() * 1000.0, 1.0);
  EXPECT_EQ(expert.metadata().extra.at("mode"), "BASIC");
  EXPECT_EQ(expert.metadata().subject, "expert");
  // Where the script writes at its plateau force, the pen is on the paper, close to the
  // script's path, pressing with about the planned force.
  checks::expectRecordingFollowsScript(script, expert, 500);
}

// A study may name an expert by its glyph (built-in name or character): the simulated expert
// writing it on the study's pen and world, the same to the bit as recording it by hand, and
// stored by create; a file is still a file, a missing one refused, an unknown name refused.
TEST(RecordNamedExperts, RecordsTheGlyphsSimulatedExpertForTheStudyToStore) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  const auto parse = [&](const std::string& experts) {
    return session::parseStudy(R"({"name": "named", "skill": "na", "experts": )" + experts +
                                   R"(, "world": {"relief": {"kind": "flat"}},
                                   "subjects": {"count": 1, "participant": "script"}})",
                               "study.json", dir.path());
  };
  session::StudyDefinition study = parse(R"({"na": "ந", "o": "loop"})");
  EXPECT_EQ(study.named_experts, (std::map<std::string, std::string>{{"na", "ந"}, {"o", "loop"}}));
  try {
    (void)session::StudyDatabase::create(dir / "early.sqlite", study);
    FAIL() << "a named expert not recorded yet";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("experts.na: \"ந\" names the simulated expert writing a glyph"));
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "early.sqlite"));

  recordNamedExperts(study);
  render::WorldConfig flat;
  flat.relief.kind = render::ReliefConfig::Kind::kFlat;
  session::TrialEnvironment environment("sim://pen", flat, 1000.0);
  const HapticProfile by_hand = recordExpert(environment, expertScript(findGlyph("na")),
                                             {.subject = "expert", .skill = "na", .source = "sim:expert"});
  const HapticProfile& named = study.named_expert_profiles.at("na");
  ASSERT_EQ(named.size(), by_hand.size());
  for (const Channel c : {Channel::kTime, Channel::kX, Channel::kY, Channel::kZ, Channel::kFz}) {
    EXPECT_EQ(named.channel(c), by_hand.channel(c)) << static_cast<int>(c);
  }
  EXPECT_EQ(study.named_expert_profiles.at("o").metadata().skill, "o");
  const session::StudyDatabase db = session::StudyDatabase::create(dir / "s.sqlite", study);
  EXPECT_EQ(db.expert("na").channel(Channel::kX), by_hand.channel(Channel::kX));
  EXPECT_EQ(db.study().experts.at("o"), "loop") << "the definition says how the expert was named";

  // A file stays a file; a missing one (a '/' or .csv in it, in any case) is refused; a name that
  // is no glyph too. A glyph file beside the study is a glyph, wherever the program runs.
  io::writeProfileCsv(by_hand, dir / "na-expert.csv");
  EXPECT_TRUE(parse(R"({"na": "na-expert.csv"})").named_experts.empty());
  EXPECT_THAT([&] { (void)parse(R"({"na": "missing.csv"})"); },
              ThrowsMessage<InputError>(HasSubstr("experts.na: expert file")));
  EXPECT_THAT([&] { (void)parse(R"({"na": "missing.CSV"})"); },
              ThrowsMessage<InputError>(HasSubstr("experts.na: expert file")));
  EXPECT_THAT([&] { (void)parse(R"({"na": "mine.json"})"); },
              ThrowsMessage<InputError>(HasSubstr("experts.na: glyph file")));
  std::filesystem::copy_file(defaultDataDir() / "glyphs" / "loop.json", dir / "mine.json");
  session::StudyDefinition own = parse(R"({"na": "mine.json"})");
  EXPECT_EQ(own.named_experts.at("na"), (dir / "mine.json").string());
  recordNamedExperts(own);
  const HapticProfile loop_by_hand = recordExpert(environment, expertScript(findGlyph("loop")),
                                                  {.subject = "expert", .skill = "na", .source = "sim:expert"});
  EXPECT_EQ(own.named_expert_profiles.at("na").channel(Channel::kX), loop_by_hand.channel(Channel::kX));
  session::StudyDefinition unknown = parse(R"({"na": "zz"})");
  EXPECT_THAT([&] { recordNamedExperts(unknown); },
              ThrowsMessage<InputError>(AllOf(HasSubstr("experts.na: "), HasSubstr("loop"), HasSubstr("na"))));
}

}  // namespace
}  // namespace hattr::sim
